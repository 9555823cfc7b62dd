// Where the datagrams of a udp or serial link come and go: a UDP socket bound
// to the PubBroker's endpoint (replies to the sender, DATA to the last
// authenticated base station), or a character device (a telemetry radio, a
// UART, a pseudo-terminal) in raw mode, each datagram one serial frame
// (COBS + CRC-16, 0x00; docs/protocol.md, "Serial framing").
#pragma once
#include <sys/socket.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "modd/broker/dgram_link.hpp"

namespace modd::broker {

class DgramPort : public DatagramOut {
 public:
  ~DgramPort() override = default;
  virtual int fd() const = 0;
  // Reads what is ready; each whole datagram goes to fn (its sender remembered for replies).
  virtual void read(const std::function<void(std::span<const uint8_t>)>& fn) = 0;
  // Sends output left waiting (serial: the device was full); true when nothing waits.
  virtual bool flush_pending() { return true; }
  virtual std::string describe() const = 0;
  // The device went away (EIO): the server closes it and opens it again later.
  virtual bool broken() const { return false; }
  uint64_t bytes_in = 0, bytes_out = 0, dropped_out = 0, corrupt = 0;
};

// Throws Error(Io / BadConfig) naming the endpoint or the device.
std::unique_ptr<DgramPort> open_udp(const std::string& host, uint16_t port, uint16_t& bound);
std::unique_ptr<DgramPort> open_serial(const std::string& device, uint32_t baud, size_t max_frame);

}  // namespace modd::broker
