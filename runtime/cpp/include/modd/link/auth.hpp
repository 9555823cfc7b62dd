// The pre-shared-key challenge: HMAC-SHA256 proofs over both nonces, with a
// label per direction so that a proof cannot be reflected.
#pragma once
#include <span>
#include <string>

#include "modd/link/messages.hpp"

struct evp_md_ctx_st;  // OpenSSL's EVP_MD_CTX

namespace modd::link {

Mac hmac_sha256(std::span<const uint8_t> key, std::span<const uint8_t> data);
// The client's proof: HMAC(key, "MODD1C" || server_nonce || client_nonce).
Mac client_proof(std::span<const uint8_t> key, const Nonce& client, const Nonce& server);
// The server's proof: HMAC(key, "MODD1S" || client_nonce || server_nonce).
Mac server_proof(std::span<const uint8_t> key, const Nonce& client, const Nonce& server);
bool macs_equal(const Mac& a, const Mac& b);  // constant time

// A keyed HELLO nonce (docs/protocol.md, "Keyed HELLO"): 8 bytes (the SubBroker's: its clock
// in seconds, big-endian u32, then 4 random bytes), then HMAC(key, "MODDHL" || those 8)[0:8]. The
// HELLO's layout is unchanged; the PubBroker tells the base station's HELLO from a keyless
// stranger's by it (is_keyed_nonce).
Nonce keyed_nonce(std::span<const uint8_t> key, std::span<const uint8_t, 8> random);
bool is_keyed_nonce(std::span<const uint8_t> key, const Nonce& n);  // constant time

// client_proof under one key for many nonce pairs (RFC 2104 with the key's pads hashed
// once): an AUTH checked against many outstanding handshakes costs two SHA-256 blocks a
// pair instead of a whole HMAC set-up.
class ClientProofs {
 public:
  explicit ClientProofs(std::span<const uint8_t> key);
  ~ClientProofs();
  ClientProofs(const ClientProofs&) = delete;
  ClientProofs& operator=(const ClientProofs&) = delete;
  Mac operator()(const Nonce& client, const Nonce& server);  // == client_proof(key, client, server)

 private:
  ::evp_md_ctx_st *inner_, *outer_, *work_;
};
Nonce random_nonce();

// Shorter link keys than kMinKeyBytes (modd/link/wire.gen.hpp) are refused where
// they are read (here and in the SubBroker).

// Resolves a key reference: "env:NAME" or "file:PATH" (file content, trailing
// newline stripped). Throws Error(BadConfig) naming the reference, and for a key
// shorter than kMinKeyBytes.
std::string resolve_key(const std::string& reference);

}  // namespace modd::link
