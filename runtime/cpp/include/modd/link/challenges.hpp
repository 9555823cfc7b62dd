// The PubBroker's side of the datagram handshake under a flood of HELLOs from strangers
// (docs/protocol.md, "Handshake under a flood"), without a wire change:
//
// * Each CHALLENGE nonce is a cookie, HMAC(per-process secret, HELLO nonce, source, time
//   bucket): a repeated HELLO gets the same CHALLENGE without new state.
// * A keyed HELLO (its nonce tagged under the link key: the base station's; auth.hpp
//   keyed_nonce) has its own CHALLENGE budget and its own memory, which a keyless flood from
//   any number of sources can neither spend nor evict; its AUTH is checked against the cookie
//   recomputed from the AUTH's source (a few HMACs, no rate limit).
// * Keyless HELLOs (a base station of an earlier release): several handshakes outstanding at
//   once, the HELLO nonces heard lately and the CHALLENGE nonces sent lately, each kept for
//   `lifetime_ns`; an AUTH verifies against any pair of them (a shared radio: the base
//   station may answer a stranger's CHALLENGE). Their CHALLENGEs are rate-limited per
//   source and in all; that search is rate-limited too (up to hellos x challenges HMACs).
// * A HELLO nonce that opened a session never opens another (a replayed handshake).
#pragma once
#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <vector>

#include "modd/link/auth.hpp"
#include "modd/link/messages.hpp"
#include "modd/util/token_bucket.hpp"

namespace modd::link {

struct ChallengeLimits {
  size_t max_hellos = 64;      // keyless HELLO nonces kept (a flood replaces the oldest)
  size_t max_challenges = 64;  // CHALLENGE nonces sent to keyless HELLOs, kept
  int64_t lifetime_ns = 5'000'000'000;
  double per_source_per_s = 2, per_source_burst = 4;
  double total_per_s = 8, total_burst = 8;
  double auth_per_s = 10, auth_burst = 10;
  size_t max_sources = 256;  // per-source buckets kept (least recently used replaced)
  // keyed HELLOs: only the key's holder makes them (a copy of one is refused once it opened
  // a session), so neither their budget nor their memory is a stranger's to spend
  size_t max_keyed = 16;  // keyed HELLO nonces kept, each for two time buckets
  // A keyed nonce starts with the base station's clock in seconds: one more than this older
  // than the newest kept is an earlier attempt played again (or a clock set back), and goes
  // the keyless way; when the memory is full, the oldest by that clock is replaced.
  int64_t keyed_slack_s = 2;
  double keyed_per_s = 8, keyed_burst = 8;
  size_t max_used = 4096;  // HELLO nonces that opened a session, refused from then on
};

struct ChallengeCounters {
  uint64_t hellos = 0, challenges = 0, unanswered = 0;  // unanswered: over a rate limit
  uint64_t keyed = 0;                                   // HELLOs with a keyed nonce
  uint64_t stale_keyed = 0;  // ... older than the newest kept (gone the keyless way)
  uint64_t auth_ok = 0, auth_failed = 0, auth_limited = 0, replayed = 0;
};

class Challenges {
 public:
  Challenges(std::span<const uint8_t> key, ChallengeLimits lim = {},
             std::optional<Mac> secret = std::nullopt);
  // A HELLO from `source` (udp: the address bytes; serial: empty). The CHALLENGE nonce to
  // send, or nullopt when not to answer (over a rate limit: the HELLO is remembered all the
  // same; or a nonce that opened a session already).
  std::optional<Nonce> on_hello(const Nonce& hello, std::span<const uint8_t> source, int64_t now);
  // An AUTH from `source`: the (hello, challenge) pair its proof verifies with under the
  // key, both forgotten (one use); Failed (wrong key, or stale), or Limited (over the
  // verification rate: not checked, to be dropped without an answer).
  struct AuthResult {
    enum Status { Ok, Failed, Limited } status = Failed;
    Nonce hello{}, challenge{};
  };
  AuthResult on_auth(const Mac& mac, std::span<const uint8_t> source, int64_t now);
  const ChallengeCounters& counters() const { return c_; }

 private:
  struct Entry {
    Nonce nonce;
    int64_t at;
  };
  Nonce cookie(const Nonce& hello, std::span<const uint8_t> source, uint64_t bucket) const;
  uint64_t bucket(int64_t now) const { return static_cast<uint64_t>(now / lim_.lifetime_ns); }
  static void remember(std::deque<Entry>& q, const Nonce& n, int64_t now, size_t max);
  void expire(int64_t now);
  bool stale(const Nonce& hello) const;
  void remember_keyed(const Nonce& n, int64_t now);
  std::optional<Nonce> on_keyless_hello(const Nonce& hello, std::span<const uint8_t> source,
                                        int64_t now);
  bool source_allows(std::span<const uint8_t> source, int64_t now);
  std::optional<AuthResult> keyed_auth(const Mac& mac, std::span<const uint8_t> source,
                                       int64_t now);
  std::optional<AuthResult> any_pair_auth(const Mac& mac);
  AuthResult opened(const Nonce& hello, const Nonce& challenge);

  std::vector<uint8_t> key_;
  ClientProofs proofs_;
  ChallengeLimits lim_;
  Mac secret_{};
  std::deque<Entry> hellos_, challenges_, keyed_;
  std::deque<Nonce> used_order_;  // HELLO nonces of sessions opened (oldest first) ...
  std::set<Nonce> used_;          // ... and for lookup: a replayed handshake opens none
  std::map<std::string, std::pair<TokenBucket, int64_t>> sources_;  // bucket, last use
  TokenBucket total_, auth_, keyed_budget_;
  ChallengeCounters c_;
};

}  // namespace modd::link
