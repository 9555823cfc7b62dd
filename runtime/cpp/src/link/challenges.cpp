#include "modd/link/challenges.hpp"

#include <algorithm>
#include <cstring>

namespace modd::link {

Challenges::Challenges(std::span<const uint8_t> key, ChallengeLimits lim, std::optional<Mac> secret)
    : key_(key.begin(), key.end()),
      proofs_(key),
      lim_(lim),
      total_(lim.total_per_s, lim.total_burst),
      auth_(lim.auth_per_s, lim.auth_burst),
      keyed_budget_(lim.keyed_per_s, lim.keyed_burst) {
  if (secret) {
    secret_ = *secret;
  } else {
    Nonce a = random_nonce(), b = random_nonce();
    std::memcpy(secret_.data(), a.data(), a.size());
    std::memcpy(secret_.data() + a.size(), b.data(), b.size());
  }
}

Nonce Challenges::cookie(const Nonce& hello, std::span<const uint8_t> source,
                         uint64_t bucket) const {
  std::vector<uint8_t> msg{'M', 'O', 'D', 'D', 'C', 'K'};
  msg.insert(msg.end(), hello.begin(), hello.end());
  msg.insert(msg.end(), source.begin(), source.end());
  for (int i = 0; i < 8; ++i) msg.push_back(static_cast<uint8_t>(bucket >> (8 * i)));
  Mac m = hmac_sha256(secret_, msg);
  Nonce n{};
  std::copy_n(m.begin(), n.size(), n.begin());
  return n;
}

void Challenges::remember(std::deque<Entry>& q, const Nonce& n, int64_t now, size_t max) {
  auto it = std::find_if(q.begin(), q.end(), [&](const Entry& e) { return e.nonce == n; });
  if (it != q.end()) q.erase(it);  // heard again: kept from now
  q.push_back({n, now});
  while (q.size() > max) q.pop_front();
}

void Challenges::expire(int64_t now) {
  for (auto* q : {&hellos_, &challenges_})
    while (!q->empty() && now - q->front().at > lim_.lifetime_ns) q->pop_front();
  // a keyed HELLO's cookie is checked in its time bucket and the next one
  while (!keyed_.empty() && now - keyed_.front().at > 2 * lim_.lifetime_ns) keyed_.pop_front();
}

std::optional<Nonce> Challenges::on_hello(const Nonce& hello, std::span<const uint8_t> source,
                                          int64_t now) {
  ++c_.hellos;
  expire(now);
  if (used_.count(hello)) {
    ++c_.replayed;  // a recorded handshake played again: the session it opened is not reset
    return std::nullopt;
  }
  if (!is_keyed_nonce(key_, hello)) return on_keyless_hello(hello, source, now);
  // The base station's (or a copy of one it sent, which opens nothing: see on_auth).
  if (stale(hello)) {
    ++c_.stale_keyed;  // an older attempt's HELLO played again, or a clock set back
    return on_keyless_hello(hello, source, now);
  }
  ++c_.keyed;
  remember_keyed(hello, now);
  if (!keyed_budget_.take(now)) {
    ++c_.unanswered;
    return std::nullopt;
  }
  ++c_.challenges;
  return cookie(hello, source, bucket(now));
}

namespace {
// The base station's clock (seconds) when it made a keyed nonce: its first 4 bytes.
int64_t stamp_of(const Nonce& n) {
  return (int64_t{n[0]} << 24) | (int64_t{n[1]} << 16) | (int64_t{n[2]} << 8) | int64_t{n[3]};
}
}  // namespace

bool Challenges::stale(const Nonce& hello) const {
  int64_t newest = 0;
  for (const Entry& e : keyed_) newest = std::max(newest, stamp_of(e.nonce));
  return stamp_of(hello) + lim_.keyed_slack_s < newest;
}

void Challenges::remember_keyed(const Nonce& n, int64_t now) {
  auto it =
      std::find_if(keyed_.begin(), keyed_.end(), [&](const Entry& e) { return e.nonce == n; });
  if (it != keyed_.end()) keyed_.erase(it);  // heard again: kept from now
  keyed_.push_back({n, now});
  if (keyed_.size() <= lim_.max_keyed) return;
  // full: the oldest attempt goes (the base station's newest is never the one replaced)
  keyed_.erase(std::min_element(keyed_.begin(), keyed_.end(), [](const Entry& a, const Entry& b) {
    return stamp_of(a.nonce) < stamp_of(b.nonce);
  }));
}

bool Challenges::source_allows(std::span<const uint8_t> source, int64_t now) {
  std::string key(source.begin(), source.end());
  auto it = sources_.find(key);
  if (it == sources_.end()) {
    if (sources_.size() >= lim_.max_sources) {
      auto oldest = std::min_element(
          sources_.begin(), sources_.end(),
          [](const auto& a, const auto& b) { return a.second.second < b.second.second; });
      sources_.erase(oldest);
    }
    TokenBucket fresh(lim_.per_source_per_s, lim_.per_source_burst);
    it = sources_.emplace(key, std::make_pair(fresh, now)).first;
  }
  it->second.second = now;
  return it->second.first.take(now);
}

std::optional<Nonce> Challenges::on_keyless_hello(const Nonce& hello,
                                                  std::span<const uint8_t> source, int64_t now) {
  remember(hellos_, hello, now, lim_.max_hellos);
  // The source's own bucket first: a flooding source spends its own tokens, not the others'.
  if (!source_allows(source, now) || !total_.take(now)) {
    ++c_.unanswered;
    return std::nullopt;
  }
  Nonce c = cookie(hello, source, bucket(now));
  remember(challenges_, c, now, lim_.max_challenges);
  ++c_.challenges;
  return c;
}

Challenges::AuthResult Challenges::opened(const Nonce& hello, const Nonce& challenge) {
  used_.insert(hello);
  used_order_.push_back(hello);
  while (used_order_.size() > lim_.max_used) {
    used_.erase(used_order_.front());
    used_order_.pop_front();
  }
  ++c_.auth_ok;
  return {AuthResult::Ok, hello, challenge};
}

std::optional<Challenges::AuthResult> Challenges::keyed_auth(const Mac& mac,
                                                             std::span<const uint8_t> source,
                                                             int64_t now) {
  // Newest first; the cookie made again for the AUTH's own source, this bucket or the last.
  for (auto k = keyed_.rbegin(); k != keyed_.rend(); ++k) {
    for (uint64_t b : {bucket(now), bucket(now) - 1}) {
      Nonce c = cookie(k->nonce, source, b);
      if (!macs_equal(mac, proofs_(k->nonce, c))) continue;
      Nonce h = k->nonce;
      keyed_.erase(std::next(k).base());
      return opened(h, c);
    }
  }
  return std::nullopt;
}

std::optional<Challenges::AuthResult> Challenges::any_pair_auth(const Mac& mac) {
  // Any HELLO heard lately (keyed ones too: on a shared radio the base station may have
  // answered a stranger's CHALLENGE) with any CHALLENGE sent lately, newest first.
  for (auto* q : {&keyed_, &hellos_})
    for (auto h = q->rbegin(); h != q->rend(); ++h)
      for (auto c = challenges_.rbegin(); c != challenges_.rend(); ++c)
        if (macs_equal(mac, proofs_(h->nonce, c->nonce))) {
          Nonce hello = h->nonce, challenge = c->nonce;
          q->erase(std::next(h).base());
          challenges_.erase(std::next(c).base());
          return opened(hello, challenge);
        }
  return std::nullopt;
}

Challenges::AuthResult Challenges::on_auth(const Mac& mac, std::span<const uint8_t> source,
                                           int64_t now) {
  expire(now);
  if (auto ok = keyed_auth(mac, source, now)) return *ok;
  if (!auth_.take(now)) {
    ++c_.auth_limited;
    return {AuthResult::Limited};
  }
  if (auto ok = any_pair_auth(mac)) return *ok;
  ++c_.auth_failed;
  return {AuthResult::Failed};
}

}  // namespace modd::link
