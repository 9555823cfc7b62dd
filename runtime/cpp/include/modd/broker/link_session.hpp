// One link connection on the PubBroker side, without the socket: bytes in,
// bytes out. State machine: AWAIT_HELLO -> AWAIT_AUTH -> READY (docs/protocol.md).
// Anything but the handshake before READY, a bad proof, or a malformed frame
// gives an ERROR frame and the end of the session.
#pragma once
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "modd/link/codec.hpp"
#include "modd/link/messages.hpp"
#include "modd/util/error.hpp"

namespace modd::broker {

class LinkHooks {
 public:
  virtual ~LinkHooks() = default;
  virtual link::ConfigAck on_config(const link::Config& cfg) = 0;
  virtual link::AuthOk
  current_config() = 0;  // config id and epoch for AUTH_OK (mac filled by the session)
  virtual void on_authenticated() = 0;
  virtual void on_rejected(const std::string& why) = 0;  // logged and counted by the broker
  // A backfill frame from the base station (BACKFILL_REQUEST, BACKFILL_CANCEL); replies go to
  // `out`. Throws Error(BadFrame) on a malformed or misdirected frame. Default: ignored.
  virtual void on_backfill(const link::RawFrame& f, std::vector<uint8_t>& out) {
    (void)f;
    (void)out;
  }
  // The on-board model (ONBOARD): written for the on-board processes; an answer to
  // send at once (a refusal), or none (their answers follow as ONBOARD_ACK).
  virtual std::optional<link::OnboardAck> on_onboard(const link::Onboard& o) {
    return link::OnboardAck{o.config_id, static_cast<uint8_t>(ErrorCode::BadConfig), {}};
  }
};

class LinkSession {
 public:
  enum class State { AwaitHello, AwaitAuth, Ready, Closed };

  LinkSession(std::string key, LinkHooks& hooks, std::function<link::Nonce()> nonce_source);
  // Consumes received bytes; appends what to send to `out`. Returns false
  // when the session is over (send `out`, then close).
  bool on_bytes(std::span<const uint8_t> in, std::vector<uint8_t>& out);
  State state() const { return state_; }
  bool ready() const { return state_ == State::Ready; }
  void close_with_error(ErrorCode code, const std::string& why, std::vector<uint8_t>& out);

 private:
  bool handle(uint8_t type, std::span<const uint8_t> body, std::vector<uint8_t>& out);

  std::string key_;
  LinkHooks& hooks_;
  std::function<link::Nonce()> nonce_source_;
  State state_ = State::AwaitHello;
  std::vector<uint8_t> inbuf_;
  link::Nonce client_nonce_{}, server_nonce_{};
};

}  // namespace modd::broker
