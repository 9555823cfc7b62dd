// The datagram handshake and resends against a stranger in radio range and a NACK storm
// (docs/protocol.md, "Handshake under a flood", "Resends"): several handshakes outstanding,
// CHALLENGEs rate-limited per source and in all, the session bound to its peer's address,
// resends capped per NACK and earned by live DATA.
#include <gtest/gtest.h>

#include "modd/broker/dgram_link.hpp"
#include "modd/link/auth.hpp"
#include "modd/link/challenges.hpp"
#include "modd/link/codec.hpp"
#include "modd/link/datagram.hpp"

using namespace modd;
using namespace modd::broker;
using namespace modd::link;
namespace dg = modd::link::dgram;

namespace {

constexpr int64_t kMs = 1'000'000;
const std::string kPsk = "a-link-key-of-32-bytes-for-tests";
std::span<const uint8_t> psk() {
  return {reinterpret_cast<const uint8_t*>(kPsk.data()), kPsk.size()};
}

struct Hooks : LinkHooks {
  int auths = 0, rejects = 0;
  ConfigAck on_config(const Config& c) override { return {c.config_id, 0, 77}; }
  AuthOk current_config() override { return {}; }
  void on_authenticated() override { ++auths; }
  void on_rejected(const std::string&) override { ++rejects; }
};

// A radio: every datagram the drone sends is heard by everyone (serial, a relay); the
// sender's address is what the port reports (udp), or nothing (serial).
struct Air : DatagramOut {
  std::vector<std::vector<uint8_t>> sent;
  std::vector<uint8_t> from, peer;
  size_t bytes = 0;
  void send(std::vector<uint8_t>&& d, bool) override {
    bytes += d.size();
    sent.push_back(std::move(d));
  }
  void adopt_source() override { peer = from; }
  std::vector<uint8_t> source() const override { return from; }
  bool from_peer() const override { return from == peer; }
};

template <typename T>
std::vector<uint8_t> hs(const T& m) {
  std::vector<uint8_t> d{dg::kHandshake};
  encode(d, m);
  return d;
}

std::optional<Message> handshake_answer(const std::vector<uint8_t>& d) {
  if (d.empty() || d[0] != dg::kHandshake) return std::nullopt;
  auto f = split_frame(std::span(d).subspan(1));
  return decode(*f);
}

Nonce nonce(uint8_t b, uint8_t c = 0) {
  Nonce n{};
  n.fill(b);
  n[0] = c;
  return n;
}

struct Drone {
  Hooks hooks;
  Air air;
  DatagramLink link;
  explicit Drone(DgramOptions o = DgramOptions{}) : link(kPsk, hooks, air, o, Mac{}) {}
  void hear(const std::vector<uint8_t>& d, const std::vector<uint8_t>& from, int64_t now) {
    air.from = from;
    link.on_datagram(d, now);
  }
  // The base station's handshake from `from` (HELLO, then AUTH with the CHALLENGE it got):
  // the session key.
  Mac open_session(const std::vector<uint8_t>& from, int64_t now) {
    auto [h, c] = hello(from, now);
    hear(hs(Auth{client_proof(psk(), h, c)}), from, now + kMs);
    EXPECT_TRUE(link.ready());
    return dg::session_key(psk(), h, c);
  }
  // The base station's HELLO: its nonce and the CHALLENGE it got.
  std::pair<Nonce, Nonce> hello(const std::vector<uint8_t>& from, int64_t now) {
    Nonce h = nonce(7);
    size_t mark = air.sent.size();
    hear(hs(Hello{kVersion, h}), from, now);
    return {h, challenges(mark).at(0)};
  }
  // The CHALLENGEs sent since datagram `since`.
  std::vector<Nonce> challenges(size_t since = 0) const {
    std::vector<Nonce> out;
    for (size_t i = since; i < air.sent.size(); ++i)
      if (auto m = handshake_answer(air.sent[i]); m && std::holds_alternative<Challenge>(*m))
        out.push_back(std::get<Challenge>(*m).nonce);
    return out;
  }
};

}  // namespace

TEST(HandshakeFlood, AStrangersHelloDuringAHandshakeDoesNotFailTheRealAuth) {
  Drone d;
  const std::vector<uint8_t> base{1}, stranger{2};
  auto [h, c] = d.hello(base, 0);
  d.hear(hs(Hello{kVersion, nonce(9)}), stranger, 100 * kMs);  // was: replaced the only challenge
  d.hear(hs(Auth{client_proof(psk(), h, c)}), base, 600 * kMs);
  EXPECT_TRUE(d.link.ready());
  EXPECT_EQ(d.hooks.auths, 1);
  EXPECT_EQ(d.hooks.rejects, 0);
}

TEST(HandshakeFlood, OnASharedRadioTheBaseStationAuthenticatesWithAStrangersChallenge) {
  // Serial: no addresses, one rate limit for everyone. 50 HELLO/s from a stranger take every
  // CHALLENGE; the base station's HELLO goes unanswered but is remembered, and the CHALLENGE
  // it hears (the stranger's) opens its session.
  Drone d;
  const std::vector<uint8_t> none;
  int64_t t = 0;
  for (int i = 0; i < 50; ++i, t += 20 * kMs)
    d.hear(hs(Hello{kVersion, nonce(9, static_cast<uint8_t>(i))}), none, t);
  Nonce h = nonce(7);
  d.hear(hs(Hello{kVersion, h}), none, t);  // answered or not (the rate), remembered
  size_t mark = d.air.sent.size();
  for (int i = 50; i < 110; ++i, t += 20 * kMs)
    d.hear(hs(Hello{kVersion, nonce(9, static_cast<uint8_t>(i))}), none, t);
  auto heard = d.challenges(mark);  // answers to the stranger's HELLOs only
  ASSERT_FALSE(heard.empty());
  EXPECT_GE(d.link.handshake_counters().unanswered, 40u);
  t += 300 * kMs;  // the radio's latency, both ways
  d.hear(hs(Auth{client_proof(psk(), h, heard.back())}), none, t);
  EXPECT_TRUE(d.link.ready());
  // The session key is the pair's: a CONTROL datagram under it verifies.
  Mac key = dg::session_key(psk(), h, heard.back());
  std::vector<uint8_t> ping;
  encode(ping, Message{Ping{{1}}});
  size_t before = d.air.sent.size();
  d.hear(dg::encode_control(1, ping, key, dg::kBaseToDrone), none, t + kMs);
  ASSERT_EQ(d.air.sent.size(), before + 1);
  EXPECT_NO_THROW(dg::verify_control(d.air.sent.back(), key, dg::kDroneToBase));
}

TEST(HandshakeFlood, ChallengesAreRateLimitedPerSourceAndInAll) {
  Drone d;
  const std::vector<uint8_t> stranger{2}, base{1};
  int64_t t = 0;
  for (int i = 0; i < 500; ++i, t += 20 * kMs)  // 10 s at 50 HELLO/s
    d.hear(hs(Hello{kVersion, nonce(9, static_cast<uint8_t>(i))}), stranger, t);
  // per source: a burst of 4, then 2 a second
  EXPECT_LE(d.challenges().size(), 4u + 2 * 10 + 1);
  EXPECT_GE(d.link.handshake_counters().unanswered, 470u);
  size_t mark = d.air.sent.size();
  Nonce h = nonce(7);
  d.hear(hs(Hello{kVersion, h}), base, t);  // the base station's own bucket is full
  auto c = d.challenges(mark);
  ASSERT_EQ(c.size(), 1u);
  d.hear(hs(Auth{client_proof(psk(), h, c[0])}), base, t + 600 * kMs);
  EXPECT_TRUE(d.link.ready());
  // In all, whatever the sources (spoofed addresses): at most 8 a second after a burst of 8.
  Drone e;
  t = 0;
  for (int i = 0; i < 1000; ++i, t += 10 * kMs)
    e.hear(hs(Hello{kVersion, nonce(3, static_cast<uint8_t>(i))}),
           {static_cast<uint8_t>(i), static_cast<uint8_t>(i >> 8)}, t);
  EXPECT_LE(e.challenges().size(), 8u + 8 * 10 + 1);
}

TEST(HandshakeFlood, AReplayedHandshakeOpensNoSession) {
  Drone d;
  const std::vector<uint8_t> base{1};
  Nonce h = nonce(7);
  d.hear(hs(Hello{kVersion, h}), base, 0);
  Mac mac = client_proof(psk(), h, d.challenges().at(0));
  d.hear(hs(Auth{mac}), base, kMs);
  ASSERT_EQ(d.hooks.auths, 1);
  size_t mark = d.air.sent.size();
  d.hear(hs(Hello{kVersion, h}), {3}, 2 * kMs);  // recorded and played again from elsewhere
  d.hear(hs(Auth{mac}), {3}, 3 * kMs);
  EXPECT_EQ(d.hooks.auths, 1);
  EXPECT_TRUE(d.challenges(mark).empty());
}

TEST(HandshakeFlood, TheSessionIsBoundToItsPeersAddress) {
  Drone d;
  const std::vector<uint8_t> base{1}, other{2};
  Mac key = d.open_session(base, 0);
  std::vector<uint8_t> ping;
  encode(ping, Message{Ping{{1}}});
  size_t before = d.air.sent.size();
  d.hear(dg::encode_control(1, ping, key, dg::kBaseToDrone), other,
         2 * kMs);  // a copy from elsewhere
  EXPECT_EQ(d.air.sent.size(), before);
  EXPECT_EQ(d.link.counters().foreign, 1u);
  d.hear(dg::encode_control(2, ping, key, dg::kBaseToDrone), base, 3 * kMs);
  EXPECT_EQ(d.air.sent.size(), before + 1);
}

namespace {
std::vector<uint8_t> wide_nack() {  // 32 ranges of 65535 slots: the widest NACK there is
  std::vector<uint8_t> body{32};
  for (int i = 0; i < 32; ++i) {
    for (uint64_t v : {uint64_t(i) * 65535, uint64_t{65535}}) {
      while (v >= 0x80) {
        body.push_back(static_cast<uint8_t>(v | 0x80));
        v >>= 7;
      }
      body.push_back(static_cast<uint8_t>(v));
    }
  }
  std::vector<uint8_t> f;
  uint64_t len = body.size() + 1;
  while (len >= 0x80) {
    f.push_back(static_cast<uint8_t>(len | 0x80));
    len >>= 7;
  }
  f.push_back(static_cast<uint8_t>(len));
  f.push_back(0x09);
  f.insert(f.end(), body.begin(), body.end());
  return f;
}
}  // namespace

TEST(HandshakeFlood, NackResendsAreCappedPerNackAndEarnedByLiveData) {
  // 1,000 wide NACKs drew 67 MB of resends (471x the NACKs): now one NACK gets at most a
  // quarter of the ring, and all of them together what the ring holds plus the live bytes.
  DgramOptions o;
  o.max_datagram = 200;
  o.keepalive_timeout_ns = 0;  // the base station's PINGs are not played here
  Drone d(o);
  const std::vector<uint8_t> base{1};
  Mac key = d.open_session(base, 0);
  int64_t t = 0;
  uint64_t slot = 0;
  auto live = [&](int n) {  // n slots of 150 B, one datagram each
    for (int i = 0; i < n; ++i, t += 250 * kMs) {
      d.link.add_slot(1, slot++, t, std::vector<uint8_t>(150, 1), {true});
      d.link.tick(t + 2'000 * kMs);
    }
  };
  live(400);  // the ring full (64 KiB)
  const size_t live_before = d.air.bytes;
  uint64_t counter = 0;
  size_t nack_bytes = 0;
  size_t resent_bytes = 0;
  for (int i = 0; i < 1000; ++i) {
    auto n = dg::encode_control(++counter, wide_nack(), key, dg::kBaseToDrone);
    nack_bytes += n.size();
    size_t before = d.air.bytes;
    d.hear(n, base, t);
    resent_bytes += d.air.bytes - before;
    EXPECT_LE(d.air.bytes - before, o.ring_bytes / 4) << i;
    if (i % 10 == 0) live(1);
  }
  const size_t live_during = d.air.bytes - live_before - resent_bytes;
  EXPECT_LE(resent_bytes, o.ring_bytes + live_during);
  EXPECT_GT(d.link.counters().resend_paced, 0u);
  std::printf("1,000 wide NACKs (%zu B): %zu B resent (%.2fx), %zu B live meanwhile\n", nack_bytes,
              resent_bytes, static_cast<double>(resent_bytes) / static_cast<double>(nack_bytes),
              live_during);
}

TEST(HandshakeFlood, AnAuthFloodIsDroppedOverItsRateAndTheRealAuthStillVerifies) {
  Drone d;
  const std::vector<uint8_t> stranger{2}, base{1};
  auto [h, c] = d.hello(base, 0);
  size_t mark = d.air.sent.size();
  for (int i = 0; i < 200; ++i) d.hear(hs(Auth{Mac{}}), stranger, i * kMs);  // 200 in 0.2 s
  // answered (ERROR) up to the verification rate only: 10 a second after a burst of 10
  EXPECT_LE(d.air.sent.size() - mark, 13u);
  EXPECT_GE(d.link.handshake_counters().auth_limited, 187u);
  d.hear(hs(Auth{client_proof(psk(), h, c)}), base, 1'500 * kMs);
  EXPECT_TRUE(d.link.ready());
}

TEST(HandshakeFlood, ClientProofsUnderOneKeyAreTheHmacOfTheProtocol) {
  // The fast path the AUTH check takes equals the one-shot HMAC (OpenSSL), for keys shorter
  // than, as long as and longer than SHA-256's block.
  for (size_t len : {16u, 32u, 64u, 65u, 200u}) {
    std::vector<uint8_t> key(len);
    for (size_t i = 0; i < len; ++i) key[i] = static_cast<uint8_t>(i * 7 + len);
    ClientProofs proofs(key);
    for (uint8_t b : {0, 1, 255}) {
      Nonce h = nonce(b, 3), c = nonce(static_cast<uint8_t>(b ^ 0x5a), 4);
      EXPECT_TRUE(macs_equal(proofs(h, c), client_proof(key, h, c))) << len;
      EXPECT_FALSE(macs_equal(proofs(c, h), client_proof(key, h, c))) << len;
    }
  }
}

// Keyed HELLOs (docs/protocol.md, "Keyed HELLO"): the base station's nonce is tagged under
// the link key, so that a keyless flood from any number of sources can neither spend its
// CHALLENGE budget nor evict its handshake.
namespace {

Nonce keyed(uint8_t b) {
  std::array<uint8_t, 8> r{};
  r.fill(b);
  return keyed_nonce(psk(), r);
}

std::vector<uint8_t> source_of(int i) {  // 127.0.0.x:port, as many as asked
  return {127,
          0,
          0,
          static_cast<uint8_t>(2 + i % 250),
          static_cast<uint8_t>(i >> 8),
          static_cast<uint8_t>(i)};
}

// `rate` keyless HELLOs a second from `sources` addresses for `seconds`, from `t` on; the
// time after it.
int64_t flood(Drone& d, int rate, int sources, double seconds, int64_t t) {
  const int64_t step = 1'000'000'000 / rate;
  const int n = static_cast<int>(rate * seconds);
  for (int i = 0; i < n; ++i, t += step) {
    Nonce h = random_nonce();
    d.hear(hs(Hello{kVersion, h}), source_of(i % sources), t);
  }
  return t;
}

}  // namespace

TEST(KeyedHello, TheTagIsTheKeysAndAStrangersNonceIsNotKeyed) {
  Nonce k = keyed(7);
  EXPECT_TRUE(is_keyed_nonce(psk(), k));
  const std::string other = "another-key-of-32-bytes-for-test";
  EXPECT_FALSE(is_keyed_nonce({reinterpret_cast<const uint8_t*>(other.data()), other.size()}, k));
  k[12] ^= 1;
  EXPECT_FALSE(is_keyed_nonce(psk(), k));
  int keyed_by_chance = 0;
  for (int i = 0; i < 10'000; ++i) keyed_by_chance += is_keyed_nonce(psk(), random_nonce());
  EXPECT_EQ(keyed_by_chance, 0);
}

TEST(KeyedHello, AFloodFromManySourcesCannotSpendTheBaseStationsBudget) {
  // 2,000 HELLO/s from 250 sources for 5 s: each source under its own limit, the keyless
  // budget spent; the base station's keyed HELLO is answered at once and its AUTH opens.
  Drone d;
  const std::vector<uint8_t> base{127, 0, 0, 1, 0x1f, 0x90};
  int64_t t = flood(d, 2000, 250, 5, 0);
  EXPECT_LE(d.challenges().size(), 8u + 8 * 5 + 1);  // the keyless budget, whatever the sources
  Nonce h = keyed(7);
  size_t mark = d.air.sent.size();
  d.hear(hs(Hello{kVersion, h}), base, t);
  auto c = d.challenges(mark);
  ASSERT_EQ(c.size(), 1u);
  t = flood(d, 2000, 250, 0.6, t + kMs);  // the flood goes on while the CHALLENGE crosses
  d.hear(hs(Auth{client_proof(psk(), h, c[0])}), base, t);
  EXPECT_TRUE(d.link.ready());
  EXPECT_EQ(d.hooks.auths, 1);
  EXPECT_EQ(d.link.handshake_counters().keyed, 1u);
}

TEST(KeyedHello, AFloodCannotEvictTheBaseStationsHandshakeNorAnAuthFloodDelayIt) {
  Drone d;
  const std::vector<uint8_t> base{127, 0, 0, 1, 0x1f, 0x90};
  auto [h, c] = d.hello(base, 0);  // nonce(7) is keyless: the keyed one below
  Nonce k = keyed(8);
  size_t mark = d.air.sent.size();
  d.hear(hs(Hello{kVersion, k}), base, kMs);
  Nonce ck = d.challenges(mark).at(0);
  int64_t t = flood(d, 2000, 250, 4, 2 * kMs);  // 8,000 HELLOs: the keyless memory is gone
  for (int i = 0; i < 500; ++i, t += kMs / 2)   // and 2,000 AUTH/s from strangers
    d.hear(hs(Auth{Mac{}}), source_of(i), t);
  EXPECT_GE(d.link.handshake_counters().auth_limited, 400u);
  d.hear(hs(Auth{client_proof(psk(), h, c)}), base, t);  // the keyless handshake: evicted
  EXPECT_FALSE(d.link.ready());
  d.hear(hs(Auth{client_proof(psk(), k, ck)}), base, t + kMs);  // the keyed one holds
  EXPECT_TRUE(d.link.ready());
}

TEST(KeyedHello, TheCookieIsBoundToTheSourceAndToTwoTimeBuckets) {
  const std::vector<uint8_t> base{127, 0, 0, 1, 0x1f, 0x90}, other{127, 0, 0, 9, 0, 1};
  {
    Drone d;  // the base station's AUTH, copied and sent from elsewhere first
    Nonce k = keyed(1);
    d.hear(hs(Hello{kVersion, k}), base, 0);
    Mac proof = client_proof(psk(), k, d.challenges().at(0));
    d.hear(hs(Auth{proof}), other, kMs);
    EXPECT_FALSE(d.link.ready());
    d.hear(hs(Auth{proof}), base, 2 * kMs);
    EXPECT_TRUE(d.link.ready());
  }
  {
    Drone d;  // answered in the next time bucket: still good; two buckets on: stale
    const int64_t life = ChallengeLimits{}.lifetime_ns;
    Nonce k = keyed(2), late = keyed(3);
    d.hear(hs(Hello{kVersion, k}), base, life - kMs);
    d.hear(hs(Hello{kVersion, late}), base, life - kMs);
    auto c = d.challenges();
    ASSERT_EQ(c.size(), 2u);
    d.hear(hs(Auth{client_proof(psk(), late, c[1])}), base, 2 * life + kMs);
    EXPECT_FALSE(d.link.ready());
    d.hear(hs(Auth{client_proof(psk(), k, c[0])}), base, life + kMs);
    EXPECT_TRUE(d.link.ready());
  }
}

TEST(KeyedHello, ASniffedExchangePlayedAgainOpensNothing) {
  Drone d;
  const std::vector<uint8_t> base{127, 0, 0, 1, 0x1f, 0x90};
  Nonce k = keyed(4);
  d.hear(hs(Hello{kVersion, k}), base, 0);
  Nonce c = d.challenges().at(0);
  Mac proof = client_proof(psk(), k, c);
  d.hear(hs(Auth{proof}), base, kMs);
  ASSERT_EQ(d.hooks.auths, 1);
  // a new session (the base station restarted) moves the key on
  Nonce k2 = keyed(5);
  size_t mark = d.air.sent.size();
  d.hear(hs(Hello{kVersion, k2}), base, 2 * kMs);
  d.hear(hs(Auth{client_proof(psk(), k2, d.challenges(mark).at(0))}), base, 3 * kMs);
  ASSERT_EQ(d.hooks.auths, 2);
  // the first exchange, played again from the base station's address: no CHALLENGE, no session
  mark = d.air.sent.size();
  d.hear(hs(Hello{kVersion, k}), base, 4 * kMs);
  d.hear(hs(Auth{proof}), base, 5 * kMs);
  EXPECT_TRUE(d.challenges(mark).empty());
  EXPECT_EQ(d.hooks.auths, 2);
  EXPECT_GE(d.link.handshake_counters().replayed, 1u);
}

TEST(KeyedHello, KeyedChallengesHaveABudgetOfTheirOwn) {
  Drone d;
  const std::vector<uint8_t> base{127, 0, 0, 1, 0x1f, 0x90};
  int64_t t = 0;
  for (int i = 0; i < 100; ++i, t += 10 * kMs)  // one keyed HELLO replayed 100 times in 1 s
    d.hear(hs(Hello{kVersion, keyed(6)}), source_of(i), t);
  EXPECT_LE(d.challenges().size(), 8u + 8 + 1);
}

namespace {
Nonce keyed_at(uint32_t stamp, uint8_t b) {  // the SubBroker's form: its clock, then random
  std::array<uint8_t, 8> r{static_cast<uint8_t>(stamp >> 24),
                           static_cast<uint8_t>(stamp >> 16),
                           static_cast<uint8_t>(stamp >> 8),
                           static_cast<uint8_t>(stamp),
                           b,
                           b,
                           b,
                           b};
  return keyed_nonce(psk(), r);
}
}  // namespace

TEST(KeyedHello, RecordedAttemptsPlayedAgainNeitherEvictNorStarveTheNewest) {
  // 40 keyed HELLOs recorded from the base station's earlier attempts (during an outage:
  // none opened a session), played again 2,000 a second from 250 sources: the newest
  // attempt is kept and answered within its retry.
  Drone d;
  const std::vector<uint8_t> base{127, 0, 0, 1, 0x1f, 0x90};
  const uint32_t now_s = 1'800'000'000;
  std::vector<Nonce> recorded;
  for (uint32_t i = 0; i < 40; ++i) recorded.push_back(keyed_at(now_s - 400 + 10 * i, 1));
  int64_t t = 0;
  auto replay = [&](double seconds) {
    for (int i = 0; i < static_cast<int>(2000 * seconds); ++i, t += kMs / 2)
      d.hear(hs(Hello{kVersion, recorded[i % recorded.size()]}), source_of(i), t);
  };
  replay(2);
  Nonce fresh = keyed_at(now_s, 9);
  std::vector<Nonce> got;
  for (int retry = 0; retry < 3 && got.empty(); ++retry) {  // the SubBroker's 1 s retries
    size_t mark = d.air.sent.size();
    d.hear(hs(Hello{kVersion, fresh}), base, t);
    got = d.challenges(mark);
    replay(1);
  }
  ASSERT_EQ(got.size(), 1u);
  replay(0.3);
  d.hear(hs(Auth{client_proof(psk(), fresh, got[0])}), base, t);
  EXPECT_TRUE(d.link.ready());
  EXPECT_GT(d.link.handshake_counters().stale_keyed, 1000u);  // the replays, once it was heard
}

TEST(KeyedHello, AClockSetBackGoesTheKeylessWay) {
  Drone d;
  const std::vector<uint8_t> base{127, 0, 0, 1, 0x1f, 0x90};
  d.hear(hs(Hello{kVersion, keyed_at(2'000'000'000, 1)}), base, 0);
  size_t mark = d.air.sent.size();
  Nonce back = keyed_at(1'000'000'000, 2);  // a clock set back: answered all the same
  d.hear(hs(Hello{kVersion, back}), base, kMs);
  auto c = d.challenges(mark);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(d.link.handshake_counters().stale_keyed, 1u);
  d.hear(hs(Auth{client_proof(psk(), back, c[0])}), base, 2 * kMs);
  EXPECT_TRUE(d.link.ready());
}
