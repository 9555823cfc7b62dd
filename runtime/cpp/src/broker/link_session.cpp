#include "modd/broker/link_session.hpp"

#include "modd/link/backfill.hpp"

#include "modd/link/auth.hpp"
#include "modd/link/codec.hpp"

namespace modd::broker {

using namespace modd::link;

LinkSession::LinkSession(std::string key, LinkHooks& hooks, std::function<Nonce()> nonce_source)
    : key_(std::move(key)), hooks_(hooks), nonce_source_(std::move(nonce_source)) {}

void LinkSession::close_with_error(ErrorCode code, const std::string& why,
                                   std::vector<uint8_t>& out) {
  if (state_ != State::Ready) hooks_.on_rejected(why);
  encode(out, ErrorMsg{static_cast<uint8_t>(code), why});
  state_ = State::Closed;
}

bool LinkSession::on_bytes(std::span<const uint8_t> in, std::vector<uint8_t>& out) {
  if (state_ == State::Closed) return false;
  inbuf_.insert(inbuf_.end(), in.begin(), in.end());
  size_t used = 0;
  try {
    // Before authentication, frames are small: a peer cannot make us buffer 1 MiB.
    size_t limit = state_ == State::Ready ? kMaxFrame : 64;
    while (auto f = split_frame(std::span(inbuf_).subspan(used), limit)) {
      used += f->size;
      if (!handle(f->type, f->body, out)) {
        inbuf_.clear();
        return false;
      }
      limit = state_ == State::Ready ? kMaxFrame : 64;
    }
  } catch (const Error& e) {
    close_with_error(e.code(), e.what(), out);
    inbuf_.clear();
    return false;
  }
  inbuf_.erase(inbuf_.begin(), inbuf_.begin() + static_cast<std::ptrdiff_t>(used));
  return true;
}

bool LinkSession::handle(uint8_t type, std::span<const uint8_t> body, std::vector<uint8_t>& out) {
  RawFrame f{type, body, 0};
  if (is_data_type(type)) throw Error(ErrorCode::BadFrame, "DATA is sent by the PubBroker only", 0);
  if (state_ == State::Ready && link::backfill::is_backfill_type(type)) {
    hooks_.on_backfill(f, out);  // request or cancel (docs/protocol.md, "Backfill")
    return true;
  }
  Message m = decode(f);
  switch (state_) {
    case State::AwaitHello: {
      auto* h = std::get_if<Hello>(&m);
      if (!h) {
        close_with_error(ErrorCode::NotAuthenticated, "expected HELLO first", out);
        return false;
      }
      if (h->version != kVersion) {
        close_with_error(
            ErrorCode::Version,
            "unsupported version " + std::to_string(h->version) + ", this broker speaks 1", out);
        return false;
      }
      client_nonce_ = h->nonce;
      server_nonce_ = nonce_source_();
      encode(out, Challenge{kVersion, server_nonce_});
      state_ = State::AwaitAuth;
      return true;
    }
    case State::AwaitAuth: {
      auto* a = std::get_if<Auth>(&m);
      if (!a) {
        close_with_error(ErrorCode::NotAuthenticated, "expected AUTH", out);
        return false;
      }
      std::span<const uint8_t> key(reinterpret_cast<const uint8_t*>(key_.data()), key_.size());
      if (!macs_equal(a->mac, client_proof(key, client_nonce_, server_nonce_))) {
        close_with_error(ErrorCode::AuthFailed, "HMAC proof does not verify (wrong key)", out);
        return false;
      }
      AuthOk ok = hooks_.current_config();
      ok.mac = server_proof(key, client_nonce_, server_nonce_);
      encode(out, ok);
      state_ = State::Ready;
      hooks_.on_authenticated();
      return true;
    }
    case State::Ready: {
      if (auto* p = std::get_if<Ping>(&m)) {
        encode(out, Pong{p->payload});
        return true;
      }
      if (std::get_if<Pong>(&m)) return true;
      if (auto* c = std::get_if<Config>(&m)) {
        encode(out, hooks_.on_config(*c));
        return true;
      }
      if (auto* o = std::get_if<Onboard>(&m)) {
        if (auto ack = hooks_.on_onboard(*o)) encode(out, *ack);
        return true;
      }
      if (auto* e = std::get_if<ErrorMsg>(&m)) {
        hooks_.on_rejected("peer sent ERROR " + std::to_string(e->code) + ": " + e->message);
        state_ = State::Closed;
        return false;
      }
      throw Error(ErrorCode::BadFrame,
                  "unexpected message type " + std::to_string(type) + " from the base station", 0);
    }
    case State::Closed: return false;
  }
  return false;
}

}  // namespace modd::broker
