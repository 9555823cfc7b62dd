#include "modd/broker/server.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <signal.h>
#include <sys/epoll.h>
#include <sys/signalfd.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "modd/link/auth.hpp"
#include "modd/util/log.hpp"

namespace modd::broker {

namespace {

constexpr size_t kReadChunk =
    64 * 1024;  // per connection per wake-up: no publisher starves the others
constexpr size_t kLinkBacklog =
    64 * 1024;  // unsent link bytes above which DATA is dropped (and counted)
constexpr size_t kIngressBacklog =
    64 * 1024;  // unsent bytes to a publisher above which replies wait

[[noreturn]] void sys_fail(const std::string& what) {
  throw Error(ErrorCode::Io, what + ": " + std::strerror(errno));
}

int tcp_listen(const std::string& host, uint16_t port, uint16_t& bound) {
  int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) sys_fail("socket");
  int one = 1;
  setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  if (inet_pton(AF_INET, host.c_str(), &a.sin_addr) != 1)
    throw Error(ErrorCode::BadConfig, "bad IPv4 address " + host);
  if (::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) < 0)
    sys_fail("bind " + host + ":" + std::to_string(port));
  if (::listen(fd, 16) < 0) sys_fail("listen");
  socklen_t len = sizeof a;
  getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
  bound = ntohs(a.sin_port);
  return fd;
}

int unix_listen(const std::string& path) {
  int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) sys_fail("socket");
  sockaddr_un a{};
  a.sun_family = AF_UNIX;
  if (path.size() >= sizeof a.sun_path)
    throw Error(ErrorCode::BadConfig, "unix socket path too long: " + path);
  std::memcpy(a.sun_path, path.c_str(), path.size() + 1);
  ::unlink(path.c_str());
  if (::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) < 0) sys_fail("bind " + path);
  if (::listen(fd, 16) < 0) sys_fail("listen");
  return fd;
}

}  // namespace

Server::Server(const BrokerConfig& cfg, std::string key, Clock& clock)
    : cfg_(cfg), key_(std::move(key)), clock_(clock), systemd_(SdNotifier::from_env(clock)) {
  broker_ = std::make_unique<Broker>(cfg_, key_, clock_, *this);
  epfd_ = epoll_create1(EPOLL_CLOEXEC);
  if (epfd_ < 0) sys_fail("epoll_create1");
  sigset_t mask;
  sigemptyset(&mask);
  sigaddset(&mask, SIGTERM);
  sigaddset(&mask, SIGINT);
  sigprocmask(SIG_BLOCK, &mask, nullptr);
  signal(SIGPIPE, SIG_IGN);
  sigfd_ = signalfd(-1, &mask, SFD_NONBLOCK | SFD_CLOEXEC);
  if (sigfd_ < 0) sys_fail("signalfd");
  add_fd(sigfd_, Kind::Signal);
  if (cfg_.link_transport == "tcp") {
    add_fd(tcp_listen(cfg_.link_host, cfg_.link_port, link_port_), Kind::LinkListen);
  } else {
    DgramOptions o;
    o.max_datagram = cfg_.link_transport == "serial" ? serial_capacity(cfg_.link_max_packet)
                                                     : cfg_.link_max_packet;
    o.delay_ns = int64_t{cfg_.link_delay_ms} * 1'000'000;
    o.keepalive_timeout_ns = int64_t{cfg_.link_keepalive_timeout_s} * 1'000'000'000;
    o.ring_bytes = cfg_.link_ring_bytes;
    dlink_ = std::make_unique<DatagramLink>(key_, *broker_, *this, o);
    broker_->set_backfill_link(o.max_datagram,
                               control_frame_overhead(cfg_.link_transport == "serial"));
    broker_->set_status_room(control_frame_room(o.max_datagram));
    open_dgram_port();
    if (!port_) throw Error(ErrorCode::Io, "cannot open the link device " + cfg_.link_device);
  }
  if (!cfg_.ingress_unix.empty()) add_fd(unix_listen(cfg_.ingress_unix), Kind::IngressUnixListen);
  if (cfg_.ingress_port)
    add_fd(tcp_listen(cfg_.ingress_host, cfg_.ingress_port, ingress_port_), Kind::IngressTcpListen);
  int64_t now = broker_->now();
  next_flush_ = now + int64_t{cfg_.flush_interval_ms} * 1'000'000;
  next_log_ =
      cfg_.log_period_s ? now + int64_t{cfg_.log_period_s} * 1'000'000'000 : Executor::kNever;
  next_status_ = now + int64_t{std::max<uint32_t>(broker_->status_period_s(), 1)} * 1'000'000'000;
}

Server::~Server() {
  for (auto& [fd, c] : conns_)
    if (c.kind != Kind::Dgram) ::close(fd);  // the port closes its own
  if (!cfg_.ingress_unix.empty()) ::unlink(cfg_.ingress_unix.c_str());
  if (epfd_ >= 0) ::close(epfd_);
}

void Server::add_fd(int fd, Kind kind, uint32_t events) {
  epoll_event ev{};
  ev.events = events;
  ev.data.fd = fd;
  if (epoll_ctl(epfd_, EPOLL_CTL_ADD, fd, &ev) < 0) sys_fail("epoll_ctl");
  Conn c;
  c.fd = fd;
  c.kind = kind;
  conns_[fd] = std::move(c);
}

void Server::open_dgram_port() {
  try {
    if (cfg_.link_transport == "udp")
      port_ = open_udp(cfg_.link_host, cfg_.link_port, link_port_);
    else
      port_ = open_serial(cfg_.link_device, cfg_.link_baud, cfg_.link_max_packet);
  } catch (const Error& e) {
    if (cfg_.link_transport == "udp") throw;
    log_line("link: %s (trying again in 1 s)", e.what());
    port_.reset();
    return;
  }
  add_fd(port_->fd(), Kind::Dgram);
}

void Server::on_dgram_readable() {
  int64_t now = broker_->now();
  port_->read([&](std::span<const uint8_t> d) { dlink_->on_datagram(d, now); });
  if (port_->broken()) {
    log_line("link: %s went away; opening it again every second", port_->describe().c_str());
    int fd = port_->fd();
    epoll_ctl(epfd_, EPOLL_CTL_DEL, fd, nullptr);
    conns_.erase(fd);
    port_.reset();
    port_retry_ns_ = now + 1'000'000'000;
  }
}

void Server::send(std::vector<uint8_t>&& datagram, bool reply) {
  if (port_) port_->send(std::move(datagram), reply);
}

void Server::adopt_source() {
  if (port_) port_->adopt_source();
}

std::vector<uint8_t> Server::source() const {
  return port_ ? port_->source() : std::vector<uint8_t>{};
}

bool Server::from_peer() const { return !port_ || port_->from_peer(); }

LinkDatagramCounts Server::datagram_counts() const {
  if (!dlink_) return {};
  const DgramCounters& c = dlink_->counters();
  return {c.datagrams_out,      c.resent,  c.nacks, c.dropped,
          c.forged + c.foreign, c.replayed};  // foreign: forged's row
}

bool Server::link_slot(uint8_t config_id, uint64_t slot, int64_t date_ns,
                       std::vector<uint8_t>&& values, std::vector<bool>&& presence,
                       link::SlotEncoder&& enc) {
  return dlink_ && dlink_->add_slot(config_id, slot, date_ns, std::move(values),
                                    std::move(presence), std::move(enc));
}

bool Server::link_ready() const {
  if (dlink_) return dlink_->ready();
  if (active_link_ < 0) return false;
  auto it = conns_.find(active_link_);
  return it != conns_.end() && it->second.out.size() < kLinkBacklog;
}

size_t Server::link_backlog() const {
  auto it = conns_.find(active_link_);
  return it == conns_.end() ? 0 : it->second.out.size();
}

bool Server::link_write(std::vector<uint8_t>&& bytes) {
  if (dlink_) return dlink_->send_frame(bytes);
  if (!link_ready()) return false;
  Conn& c = conns_[active_link_];
  c.out.insert(c.out.end(), bytes.begin(), bytes.end());
  flush_out(c);
  return true;
}

void Server::flush_out(Conn& c) {
  while (!c.out.empty()) {
    ssize_t n = ::send(c.fd, c.out.data(), c.out.size(), MSG_NOSIGNAL);
    if (n < 0) {
      if (errno == EINTR) continue;
      if (errno == EAGAIN || errno == EWOULDBLOCK) break;
      to_close_.push_back(c.fd);
      return;
    }
    c.out.erase(c.out.begin(), c.out.begin() + n);
  }
  epoll_event ev{};
  ev.events = EPOLLIN | (c.out.empty() ? 0u : static_cast<uint32_t>(EPOLLOUT));
  ev.data.fd = c.fd;
  epoll_ctl(epfd_, EPOLL_CTL_MOD, c.fd, &ev);
}

void Server::accept_on(Conn& l) {
  for (;;) {
    int fd = ::accept4(l.fd, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0) return;  // EAGAIN, or a transient error: the listener stays
    if (l.kind == Kind::LinkListen) {
      int one = 1;
      setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
      add_fd(fd, Kind::Link);
      Conn& c = conns_[fd];
      c.link = std::make_unique<LinkSession>(key_, *broker_, [] { return link::random_nonce(); });
      c.deadline_ns = broker_->now() + int64_t{cfg_.handshake_timeout_ms} * 1'000'000;
    } else {
      add_fd(fd, Kind::Ingress);
      conns_[fd].ingress = std::make_unique<IngressSession>(*broker_);
      ++broker_->counters().publishers_connected;
      ++broker_->counters().publishers_total;
    }
  }
}

void Server::close_conn(int fd) {
  auto it = conns_.find(fd);
  if (it == conns_.end()) return;
  Conn& c = it->second;
  if (c.kind == Kind::Ingress) --broker_->counters().publishers_connected;
  if (fd == active_link_) {
    active_link_ = -1;
    log_line("link: base station disconnected");
  }
  epoll_ctl(epfd_, EPOLL_CTL_DEL, fd, nullptr);
  ::close(fd);
  conns_.erase(it);
}

void Server::on_readable(Conn& c) {
  uint8_t buf[kReadChunk];
  ssize_t n = ::recv(c.fd, buf, sizeof buf, 0);
  if (n == 0 || (n < 0 && errno != EAGAIN && errno != EINTR)) {
    if (c.kind == Kind::Ingress && c.ingress && c.ingress->on_close())
      log_line("ingress: publisher '%s' vanished in the middle of a frame (counted as malformed)",
               c.ingress->publisher().c_str());
    to_close_.push_back(c.fd);
    return;
  }
  if (n < 0) return;
  std::span<const uint8_t> in(buf, static_cast<size_t>(n));
  if (c.kind == Kind::Ingress) {
    if (!c.ingress->on_bytes(in)) {
      log_line("ingress: publisher '%s' sent a malformed frame, disconnected: %s",
               c.ingress->publisher().c_str(), c.ingress->last_error.c_str());
      to_close_.push_back(c.fd);
      return;
    }
    send_ingress_output(c);
    return;
  }
  bool was_ready = c.link->ready();
  bool keep = c.link->on_bytes(in, c.out);
  if (!was_ready && c.link->ready()) {
    if (active_link_ >= 0 && active_link_ != c.fd) {
      log_line("link: a new authenticated base station replaces the previous connection");
      to_close_.push_back(active_link_);
    }
    active_link_ = c.fd;
  }
  flush_out(c);
  if (!keep) to_close_.push_back(c.fd);
}

void Server::send_ingress_output(Conn& c) {
  auto bytes = c.ingress->take_output();
  if (bytes.empty()) return;
  if (c.out.size() > kIngressBacklog)
    return;  // a publisher that does not read: ACKs are cumulative
  c.out.insert(c.out.end(), bytes.begin(), bytes.end());
  flush_out(c);
}

void Server::timers(int64_t now) {
  broker_->tick(now);
  broker_->pump_backfill(now);
  if (dlink_) {
    dlink_->tick(
        now);  // after the slots due now were added: a full group leaves at its last slot's date
    if (port_) port_->flush_pending();
    if (!port_ && now >= port_retry_ns_) {
      open_dgram_port();
      port_retry_ns_ = now + 1'000'000'000;
    }
  }
  if (now >= next_flush_) {
    broker_->flush_buffers();
    next_flush_ = now + int64_t{cfg_.flush_interval_ms} * 1'000'000;
  }
  broker_->check_archive(now);
  for (auto& [fd, c] : conns_)
    if (c.kind == Kind::Ingress) send_ingress_output(c);
  {
    uint32_t p = broker_->status_period_s();
    int64_t period_ns = int64_t{std::max<uint32_t>(p, 1)} * 1'000'000'000;
    if (next_status_ > now + period_ns)
      next_status_ = now + period_ns;  // a CONFIG shortened the period
    if (now >= next_status_) {
      if (p) broker_->status_due(now);
      next_status_ = now + period_ns;
    }
  }
  broker_->send_overdue_status(now);
  if (now >= next_log_) {
    log_line("counters: %s", broker_->log_summary().c_str());
    if (dlink_) log_line("link: %s", dlink_->summary().c_str());
    next_log_ = now + int64_t{cfg_.log_period_s} * 1'000'000'000;
  }
  for (auto& [fd, c] : conns_)
    if (c.kind == Kind::Link && !c.link->ready() && now >= c.deadline_ns) {
      std::vector<uint8_t> out;
      c.link->close_with_error(ErrorCode::Timeout, "handshake not completed in time", out);
      ::send(fd, out.data(), out.size(), MSG_NOSIGNAL);
      to_close_.push_back(fd);
    }
}

int Server::timeout_ms(int64_t now) const {
  int64_t next = std::min({broker_->next_due_ns(), next_flush_, next_log_, next_status_,
                           broker_->backfill_wake_ns(now), broker_->status_wake_ns(),
                           broker_->onboard_wake_ns()});
  if (dlink_) next = std::min(next, dlink_->next_due_ns());
  for (const auto& [fd, c] : conns_)
    if (c.kind == Kind::Link && !c.link->ready()) next = std::min(next, c.deadline_ns);
  if (next <= now) return 0;
  int64_t ms = (next - now + 999'999) / 1'000'000;
  return static_cast<int>(std::min<int64_t>(ms, 1000));
}

void Server::run() {
  log_line("started: link %s %s:%u, ingress %s%s%s, archive %s",
           port_ ? port_->describe().c_str() : "tcp", cfg_.link_host.c_str(), link_port_,
           cfg_.ingress_unix.c_str(), cfg_.ingress_port ? " tcp:" : "",
           cfg_.ingress_port ? std::to_string(ingress_port_).c_str() : "",
           cfg_.archive_dir.c_str());
  // The archive is open and every listener bound (the constructor): ready for systemd.
  systemd_.ready("archiving to " + cfg_.archive_dir);
  epoll_event events[64];
  while (!stop_) {
    int wait_ms = timeout_ms(broker_->now());
    int dog_ms = systemd_.ms_until_due();
    if (dog_ms >= 0 && dog_ms < wait_ms) wait_ms = dog_ms;
    int n = epoll_wait(epfd_, events, 64, wait_ms);
    if (n < 0 && errno != EINTR) sys_fail("epoll_wait");
    for (int i = 0; i < n; ++i) {
      auto it = conns_.find(events[i].data.fd);
      if (it == conns_.end()) continue;
      Conn& c = it->second;
      switch (c.kind) {
        case Kind::Signal: {
          signalfd_siginfo si{};
          while (::read(sigfd_, &si, sizeof si) == sizeof si) stop_ = true;
          break;
        }
        case Kind::LinkListen:
        case Kind::IngressUnixListen:
        case Kind::IngressTcpListen: accept_on(c); break;
        case Kind::Dgram: on_dgram_readable(); break;
        default:
          if (events[i].events & EPOLLOUT) flush_out(c);
          if (events[i].events & (EPOLLIN | EPOLLHUP | EPOLLERR)) on_readable(c);
      }
    }
    timers(broker_->now());
    for (int fd : to_close_) close_conn(fd);
    to_close_.clear();
    systemd_.tick();  // from the loop itself: a loop that hangs stops feeding the watchdog
  }
  systemd_.stopping();
  log_line("stopping: flushing buffers and closing the archive");
  broker_->shutdown();
  log_line("stopped: %s", broker_->log_summary().c_str());
}

}  // namespace modd::broker
