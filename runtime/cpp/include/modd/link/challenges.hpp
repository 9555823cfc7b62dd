// The PubBroker's side of the datagram handshake under a flood of HELLOs from strangers
// (docs/protocol.md, "Handshake under a flood"), without a wire change:
//
// * Each CHALLENGE nonce is a cookie, HMAC(per-process secret, HELLO nonce, source, time
//   bucket): a repeated HELLO gets the same CHALLENGE without new state.
// * Several handshakes are outstanding at once: the HELLO nonces heard lately (answered or
//   not) and the CHALLENGE nonces sent lately, each kept for `lifetime_ns`. An AUTH verifies
//   against any pair of them, so neither a stranger's newer HELLO nor a stranger's CHALLENGE
//   heard by the base station on a shared radio (serial, a relay) can make it fail.
// * CHALLENGEs are rate-limited per source and in all, so a flood costs bounded air time;
//   AUTH verifications are rate-limited too (each costs up to hellos x challenges HMACs).
#pragma once
#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <span>
#include <string>

#include "modd/link/messages.hpp"
#include "modd/util/token_bucket.hpp"

namespace modd::link {

struct ChallengeLimits {
  size_t max_hellos = 64;      // HELLO nonces kept (a flood replaces the oldest)
  size_t max_challenges = 64;  // CHALLENGE nonces kept
  int64_t lifetime_ns = 5'000'000'000;
  double per_source_per_s = 2, per_source_burst = 4;
  double total_per_s = 8, total_burst = 8;
  double auth_per_s = 10, auth_burst = 10;
  size_t max_sources = 256;  // per-source buckets kept (least recently used replaced)
};

struct ChallengeCounters {
  uint64_t hellos = 0, challenges = 0, unanswered = 0;  // unanswered: over a rate limit
  uint64_t auth_ok = 0, auth_failed = 0, auth_limited = 0, replayed = 0;
};

class Challenges {
 public:
  explicit Challenges(ChallengeLimits lim = {}, std::optional<Mac> secret = std::nullopt);
  // A HELLO from `source` (udp: the address bytes; serial: empty). The CHALLENGE nonce to
  // send, or nullopt when a rate limit says not to answer (the HELLO is remembered all the same).
  std::optional<Nonce> on_hello(const Nonce& hello, std::span<const uint8_t> source, int64_t now);
  // An AUTH: the (hello, challenge) pair its proof verifies with under `key`, both forgotten
  // (one use); Failed (wrong key, or stale), or Limited (over the verification rate: not
  // checked, to be dropped without an answer).
  struct AuthResult {
    enum Status { Ok, Failed, Limited } status = Failed;
    Nonce hello{}, challenge{};
  };
  AuthResult on_auth(const Mac& mac, std::span<const uint8_t> key, int64_t now);
  const ChallengeCounters& counters() const { return c_; }

 private:
  struct Entry {
    Nonce nonce;
    int64_t at;
  };
  Nonce cookie(const Nonce& hello, std::span<const uint8_t> source, int64_t now) const;
  static void remember(std::deque<Entry>& q, const Nonce& n, int64_t now, size_t max);
  void expire(int64_t now);

  ChallengeLimits lim_;
  Mac secret_{};
  std::deque<Entry> hellos_, challenges_;
  std::deque<Entry> used_;  // HELLO nonces of sessions opened: a replayed handshake opens none
  std::map<std::string, std::pair<TokenBucket, int64_t>> sources_;  // bucket, last use
  TokenBucket total_, auth_;
  ChallengeCounters c_;
};

}  // namespace modd::link
