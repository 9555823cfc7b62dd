// The PubBroker's event loop: one thread, epoll over the link listener, the
// ingress listeners (Unix and TCP), their connections, and a signalfd. Bytes
// go to the sessions (Broker, LinkSession, IngressSession); DATA comes back
// through LinkOutput. The archive writer runs on its own thread.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "modd/broker/broker.hpp"
#include "modd/broker/dgram_link.hpp"
#include "modd/broker/dgram_port.hpp"
#include "modd/util/sd_notify.hpp"

namespace modd::broker {

class Server final : public LinkOutput, public DatagramOut {
 public:
  Server(const BrokerConfig& cfg, std::string key, Clock& clock);
  ~Server() override;
  // Runs until SIGTERM/SIGINT, then flushes and closes the archive. Under systemd
  // (Type=notify) it reports READY=1 on entry and feeds the watchdog from the loop.
  void run();
  uint16_t link_port() const { return link_port_; }
  uint16_t ingress_port() const { return ingress_port_; }

  bool link_ready() const override;
  bool link_write(std::vector<uint8_t>&& bytes) override;
  size_t link_backlog() const override;
  bool datagrams() const override { return dlink_ != nullptr; }
  LinkDatagramCounts datagram_counts() const override;
  bool link_slot(uint8_t config_id, uint64_t slot, int64_t date_ns, std::vector<uint8_t>&& values,
                 std::vector<bool>&& presence, link::SlotEncoder&& enc) override;
  // DatagramOut: to the current port (a serial device is opened again after it went away)
  void send(std::vector<uint8_t>&& datagram, bool reply) override;
  void adopt_source() override;
  std::vector<uint8_t> source() const override;
  bool from_peer() const override;

 private:
  enum class Kind { LinkListen, IngressUnixListen, IngressTcpListen, Link, Ingress, Signal, Dgram };
  struct Conn {
    int fd = -1;
    Kind kind{};
    std::unique_ptr<LinkSession> link;
    std::unique_ptr<IngressSession> ingress;
    std::vector<uint8_t> out;
    int64_t deadline_ns = 0;  // handshake deadline (link, before READY)
  };
  void add_fd(int fd, Kind kind, uint32_t events = 0x001 /*EPOLLIN*/);
  void accept_on(Conn& listener);
  void on_readable(Conn& c);
  void flush_out(Conn& c);
  void send_ingress_output(Conn& c);
  void close_conn(int fd);
  void timers(int64_t now);
  int timeout_ms(int64_t now) const;
  void open_dgram_port();
  void on_dgram_readable();

  BrokerConfig cfg_;
  std::string key_;
  Clock& clock_;
  SdNotifier systemd_;  // READY=1 once listening, WATCHDOG=1 from the loop (docs/operations.md)
  std::unique_ptr<Broker> broker_;
  int epfd_ = -1;
  int sigfd_ = -1;
  std::unordered_map<int, Conn> conns_;
  int active_link_ = -1;
  uint16_t link_port_ = 0, ingress_port_ = 0;
  bool stop_ = false;
  int64_t next_flush_ = 0, next_log_ = 0, next_status_ = 0;
  std::vector<int> to_close_;
  // udp and serial transports (docs/protocol.md, "Datagram transports")
  std::unique_ptr<DgramPort> port_;
  std::unique_ptr<DatagramLink> dlink_;
  int64_t port_retry_ns_ = 0;
};

}  // namespace modd::broker
