// The PubBroker's configuration file (docs/pubbroker.md): one struct, loaded
// once by main() and passed down. Errors name the file and the JSON pointer.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "modd/archive/mcap_writer.hpp"
#include "modd/link/messages.hpp"

namespace modd::broker {

struct TopicDefault {
  std::string name;
  link::ValueType type = link::ValueType::Float32;
  uint32_t buffer_size = 0;  // 0: default_buffer_size
};

struct BrokerConfig {
  std::string name = "drone";
  // --onboard-model PATH (not in the config file): where an ONBOARD's model is written for
  // modd-sensors and modd-mavlink --watch; empty: ONBOARD refused (docs/protocol.md)
  std::string onboard_model;
  // link: where the SubBroker connects
  std::string link_host = "127.0.0.1";
  uint16_t link_port = 7171;
  std::string key_ref;  // env:NAME or file:PATH
  uint32_t handshake_timeout_ms = 5000;
  // transport (docs/pubbroker.md, "link"): tcp (listen on host:port), udp (datagrams on
  // host:port) or serial (framed datagrams on a character device)
  std::string link_transport = "tcp";
  std::string link_device;        // serial: the radio's device on board
  uint32_t link_baud = 57600;     // serial
  uint32_t link_max_packet = 0;   // udp: datagram payload; serial: frame; 0: 1472 / 252
  uint32_t link_delay_ms = 1000;  // accepted delay: slots packed into one datagram up to it
  uint32_t link_keepalive_timeout_s = 90;  // silence after which DATA stops (0: never)
  uint32_t link_ring_bytes = 64 * 1024;  // udp/serial: the resend ring's bound (also 256 datagrams)
  // ingress: where publishers connect
  std::string ingress_unix;  // empty: no Unix socket
  std::string ingress_host = "127.0.0.1";
  uint16_t ingress_port = 0;  // 0: no TCP ingress
  // A sample's timestamp is judged against the broker's clock: refused (rejected_timestamp,
  // and the publisher told why) only beyond these bounds. 0: no bound on that side.
  uint64_t max_future_ms = 10'000;
  uint64_t max_past_ms = 3'600'000;
  // Fair share of the archive queue, applied once the queue holds half its limit: a
  // publisher (or topic) with more samples not yet on disk than its share is refused
  // (rejected_quota). 0: queue_limit_samples / 2 shared by the connected publishers
  // (topics: queue_limit_samples / 4).
  uint64_t publisher_quota_samples = 0;
  uint64_t topic_quota_samples = 0;
  // archive
  std::string archive_dir;
  std::string archive_prefix = "modd";
  uint64_t rotate_bytes = 256ull << 20;
  uint64_t rotate_s = 3600;
  archive::FsyncPolicy fsync = archive::FsyncPolicy::Chunk;
  archive::Compression compression = archive::Compression::Zstd;
  size_t chunk_bytes = 256 * 1024;
  bool message_index = true;
  uint32_t flush_interval_ms = 1000;
  uint64_t queue_limit_samples = 1'000'000;
  uint64_t low_space_mb = 256;  // free space under which the operator is warned (STATUS + log)
  uint32_t retry_max_ms =
      2000;  // write retry backoff (from 250 ms, doubling) while the disk is full
  // backfill (docs/protocol.md, "Backfill"): the pace of a request that sets no rate
  uint64_t backfill_default_rate_bps = 1000;
  // topics
  std::vector<TopicDefault> topics;
  uint32_t default_buffer_size = 25;
  bool accept_unknown_topics = false;
  // reporting
  uint32_t status_period_s = 30;  // until a CONFIG sets it
  uint32_t log_period_s = 10;
  // The broker's own log: stderr when empty, else this file rotated by size.
  std::string log_file;
  uint64_t log_max_bytes = 4ull << 20;
  uint32_t log_keep = 3;
};

// Throws modd::Error(BadConfig) "FILE: /json/pointer: what".
BrokerConfig load_config(const std::string& path);
BrokerConfig parse_config(const std::string& json_text, const std::string& origin);

}  // namespace modd::broker
