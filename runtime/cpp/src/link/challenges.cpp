#include "modd/link/challenges.hpp"

#include <algorithm>
#include <cstring>

#include "modd/link/auth.hpp"

namespace modd::link {

Challenges::Challenges(ChallengeLimits lim, std::optional<Mac> secret)
    : lim_(lim), total_(lim.total_per_s, lim.total_burst), auth_(lim.auth_per_s, lim.auth_burst) {
  if (secret) {
    secret_ = *secret;
  } else {
    Nonce a = random_nonce(), b = random_nonce();
    std::memcpy(secret_.data(), a.data(), a.size());
    std::memcpy(secret_.data() + a.size(), b.data(), b.size());
  }
}

Nonce Challenges::cookie(const Nonce& hello, std::span<const uint8_t> source, int64_t now) const {
  std::vector<uint8_t> msg{'M', 'O', 'D', 'D', 'C', 'K'};
  msg.insert(msg.end(), hello.begin(), hello.end());
  msg.insert(msg.end(), source.begin(), source.end());
  uint64_t bucket = static_cast<uint64_t>(now / lim_.lifetime_ns);
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
  // A used nonce is kept longer than its cookie can be made again (two time buckets).
  while (!used_.empty() && now - used_.front().at > 3 * lim_.lifetime_ns) used_.pop_front();
}

std::optional<Nonce> Challenges::on_hello(const Nonce& hello, std::span<const uint8_t> source,
                                          int64_t now) {
  ++c_.hellos;
  expire(now);
  if (std::any_of(used_.begin(), used_.end(), [&](const Entry& e) { return e.nonce == hello; })) {
    ++c_.replayed;  // a recorded handshake played again: the session it opened is not reset
    return std::nullopt;
  }
  remember(hellos_, hello, now, lim_.max_hellos);
  std::string key(source.begin(), source.end());
  auto it = sources_.find(key);
  if (it == sources_.end()) {
    if (sources_.size() >= lim_.max_sources) {
      auto oldest = std::min_element(
          sources_.begin(), sources_.end(),
          [](const auto& a, const auto& b) { return a.second.second < b.second.second; });
      sources_.erase(oldest);
    }
    it = sources_
             .emplace(key, std::make_pair(TokenBucket(lim_.per_source_per_s, lim_.per_source_burst),
                                          now))
             .first;
  }
  it->second.second = now;
  // The source's own bucket first: a flooding source spends its own tokens, not the others'.
  if (!it->second.first.take(now) || !total_.take(now)) {
    ++c_.unanswered;
    return std::nullopt;
  }
  Nonce c = cookie(hello, source, now);
  remember(challenges_, c, now, lim_.max_challenges);
  ++c_.challenges;
  return c;
}

Challenges::AuthResult Challenges::on_auth(const Mac& mac, std::span<const uint8_t> key,
                                           int64_t now) {
  expire(now);
  if (!auth_.take(now)) {
    ++c_.auth_limited;
    return {AuthResult::Limited};
  }
  // Newest first: the base station's handshake is most likely among the latest.
  ClientProofs proof(key);
  for (auto h = hellos_.rbegin(); h != hellos_.rend(); ++h)
    for (auto c = challenges_.rbegin(); c != challenges_.rend(); ++c)
      if (macs_equal(mac, proof(h->nonce, c->nonce))) {
        AuthResult ok{AuthResult::Ok, h->nonce, c->nonce};
        hellos_.erase(std::next(h).base());
        challenges_.erase(std::next(c).base());
        remember(used_, ok.hello, now, 4 * lim_.max_hellos);
        ++c_.auth_ok;
        return ok;
      }
  ++c_.auth_failed;
  return {AuthResult::Failed};
}

}  // namespace modd::link
