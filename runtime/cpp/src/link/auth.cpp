#include "modd/link/auth.hpp"

#include <openssl/crypto.h>
#include <openssl/evp.h>
#include <openssl/hmac.h>
#include <openssl/rand.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <cstdlib>

#include "modd/util/error.hpp"

namespace modd::link {

constexpr off_t kMaxKeyFile = 64 * 1024;

Mac hmac_sha256(std::span<const uint8_t> key, std::span<const uint8_t> data) {
  Mac out{};
  unsigned int len = 0;
  if (!HMAC(EVP_sha256(), key.data(), static_cast<int>(key.size()), data.data(), data.size(),
            out.data(), &len))
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

bool macs_equal(const Mac& a, const Mac& b) {
  return CRYPTO_memcmp(a.data(), b.data(), a.size()) == 0;
}

static constexpr size_t kKeyedHalf = 8;

static Mac hello_tag(std::span<const uint8_t> key, const uint8_t* random) {
  std::vector<uint8_t> msg{'M', 'O', 'D', 'D', 'H', 'L'};
  msg.insert(msg.end(), random, random + kKeyedHalf);
  return hmac_sha256(key, msg);
}

Nonce keyed_nonce(std::span<const uint8_t> key, std::span<const uint8_t, 8> random) {
  Nonce n{};
  std::copy(random.begin(), random.end(), n.begin());
  Mac tag = hello_tag(key, n.data());
  std::copy_n(tag.begin(), n.size() - kKeyedHalf, n.begin() + kKeyedHalf);
  return n;
}

bool is_keyed_nonce(std::span<const uint8_t> key, const Nonce& n) {
  Mac tag = hello_tag(key, n.data());
  return CRYPTO_memcmp(tag.data(), n.data() + kKeyedHalf, n.size() - kKeyedHalf) == 0;
}

ClientProofs::ClientProofs(std::span<const uint8_t> key)
    : inner_(EVP_MD_CTX_new()), outer_(EVP_MD_CTX_new()), work_(EVP_MD_CTX_new()) {
  std::array<uint8_t, 64> k{}, ipad{}, opad{};
  if (key.size() > k.size()) {
    unsigned int n = 0;
    EVP_Digest(key.data(), key.size(), k.data(), &n, EVP_sha256(), nullptr);
  } else {
    std::copy(key.begin(), key.end(), k.begin());
  }
  for (size_t i = 0; i < k.size(); ++i) {
    ipad[i] = k[i] ^ 0x36;
    opad[i] = k[i] ^ 0x5c;
  }
  if (!inner_ || !outer_ || !work_ || !EVP_DigestInit_ex(inner_, EVP_sha256(), nullptr) ||
      !EVP_DigestUpdate(inner_, ipad.data(), ipad.size()) ||
      !EVP_DigestInit_ex(outer_, EVP_sha256(), nullptr) ||
      !EVP_DigestUpdate(outer_, opad.data(), opad.size())) {
    EVP_MD_CTX_free(inner_);  // a constructor that throws runs no destructor
    EVP_MD_CTX_free(outer_);
    EVP_MD_CTX_free(work_);
    throw Error(ErrorCode::Internal, "SHA-256 set-up failed");
  }
}

ClientProofs::~ClientProofs() {
  EVP_MD_CTX_free(inner_);
  EVP_MD_CTX_free(outer_);
  EVP_MD_CTX_free(work_);
}

Mac ClientProofs::operator()(const Nonce& client, const Nonce& server) {
  Mac in{}, out{};
  unsigned int n = 0;
  bool ok = EVP_MD_CTX_copy_ex(work_, inner_) && EVP_DigestUpdate(work_, "MODD1C", 6) &&
            EVP_DigestUpdate(work_, server.data(), server.size()) &&
            EVP_DigestUpdate(work_, client.data(), client.size()) &&
            EVP_DigestFinal_ex(work_, in.data(), &n) && EVP_MD_CTX_copy_ex(work_, outer_) &&
            EVP_DigestUpdate(work_, in.data(), in.size()) &&
            EVP_DigestFinal_ex(work_, out.data(), &n);
  if (!ok) throw Error(ErrorCode::Internal, "SHA-256 failed");
  return out;
}

Nonce random_nonce() {
  Nonce n{};
  if (RAND_bytes(n.data(), static_cast<int>(n.size())) != 1)
    throw Error(ErrorCode::Internal, "RAND_bytes failed");
  return n;
}

// A key file: a regular file (no final symlink, never a FIFO or device) of at most
// kMaxKeyFile bytes; a warning when group or others may read it (docs/security.md).
static std::string read_key_file(const std::string& ref) {
  const std::string path = ref.substr(5);
  const int fd = ::open(path.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) throw Error(ErrorCode::BadConfig, "key reference " + ref + ": cannot open the file");
  struct stat st {};
  std::string key;
  std::string problem;
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    problem = "not a regular file";
  } else if (st.st_size > kMaxKeyFile) {
    problem = "larger than " + std::to_string(kMaxKeyFile) + " bytes";
  } else {
    if ((st.st_mode & 077) != 0)
      std::fprintf(stderr, "warning: key file %s can be read by group or others: chmod 600 it\n",
                   path.c_str());
    key.resize(static_cast<size_t>(st.st_size));
    size_t got = 0;
    while (got < key.size()) {
      const ssize_t n = ::read(fd, key.data() + got, key.size() - got);
      if (n <= 0) break;
      got += static_cast<size_t>(n);
    }
    key.resize(got);
  }
  ::close(fd);
  if (!problem.empty()) throw Error(ErrorCode::BadConfig, "key reference " + ref + ": " + problem);
  return key;
}

std::string resolve_key(const std::string& ref) {
  std::string key;
  if (ref.rfind("env:", 0) == 0) {
    const char* v = std::getenv(ref.substr(4).c_str());
    if (!v)
      throw Error(ErrorCode::BadConfig, "key reference " + ref + ": environment variable not set");
    key = v;
  } else if (ref.rfind("file:", 0) == 0) {
    key = read_key_file(ref);
    while (!key.empty() && (key.back() == '\n' || key.back() == '\r')) key.pop_back();
  } else {
    throw Error(ErrorCode::BadConfig,
                "key reference '" + ref + "' is neither env:NAME nor file:PATH");
  }
  if (key.size() < kMinKeyBytes)
    throw Error(ErrorCode::BadConfig,
                "key reference " + ref + " gives a key of " + std::to_string(key.size()) +
                    " bytes; a link key needs at least " + std::to_string(kMinKeyBytes) +
                    " (e.g. openssl rand -hex 16)");
  return key;
}

}  // namespace modd::link
