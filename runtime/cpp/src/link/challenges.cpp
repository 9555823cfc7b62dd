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
  ++c_.keyed;
  remember(keyed_, hello, now, lim_.max_keyed);
  if (!keyed_budget_.take(now)) {
    ++c_.unanswered;
    return std::nullopt;
  }
  ++c_.challenges;
  return cookie(hello, source, bucket(now));
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
