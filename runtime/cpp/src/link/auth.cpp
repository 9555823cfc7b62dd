#include "modd/link/auth.hpp"

#include <openssl/crypto.h>
#include <openssl/evp.h>
#include <openssl/hmac.h>
#include <openssl/rand.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "modd/util/error.hpp"

namespace modd::link {

Mac hmac_sha256(std::span<const uint8_t> key, std::span<const uint8_t> data) {
  Mac out{};
  unsigned int len = 0;
  if (!HMAC(EVP_sha256(), key.data(), static_cast<int>(key.size()), data.data(), data.size(), out.data(), &len))
    throw Error(ErrorCode::Internal, "HMAC failed");
  return out;
}

static Mac proof(std::span<const uint8_t> key, const char* label, const Nonce& a, const Nonce& b) {
  std::vector<uint8_t> msg(label, label + 6);
  msg.insert(msg.end(), a.begin(), a.end());
  msg.insert(msg.end(), b.begin(), b.end());
  return hmac_sha256(key, msg);
}

Mac client_proof(std::span<const uint8_t> key, const Nonce& client, const Nonce& server) {
  return proof(key, "MODD1C", server, client);
}
Mac server_proof(std::span<const uint8_t> key, const Nonce& client, const Nonce& server) {
  return proof(key, "MODD1S", client, server);
}

bool macs_equal(const Mac& a, const Mac& b) { return CRYPTO_memcmp(a.data(), b.data(), a.size()) == 0; }

Nonce random_nonce() {
  Nonce n{};
  if (RAND_bytes(n.data(), static_cast<int>(n.size())) != 1) throw Error(ErrorCode::Internal, "RAND_bytes failed");
  return n;
}

std::string resolve_key(const std::string& ref) {
  std::string key;
  if (ref.rfind("env:", 0) == 0) {
    const char* v = std::getenv(ref.substr(4).c_str());
    if (!v) throw Error(ErrorCode::BadConfig, "key reference " + ref + ": environment variable not set");
    key = v;
  } else if (ref.rfind("file:", 0) == 0) {
    std::ifstream f(ref.substr(5), std::ios::binary);
    if (!f) throw Error(ErrorCode::BadConfig, "key reference " + ref + ": cannot read file");
    std::ostringstream ss;
    ss << f.rdbuf();
    key = ss.str();
    while (!key.empty() && (key.back() == '\n' || key.back() == '\r')) key.pop_back();
  } else {
    throw Error(ErrorCode::BadConfig, "key reference '" + ref + "' is neither env:NAME nor file:PATH");
  }
  if (key.empty()) throw Error(ErrorCode::BadConfig, "key reference " + ref + " gives an empty key");
  return key;
}

}  // namespace modd::link
