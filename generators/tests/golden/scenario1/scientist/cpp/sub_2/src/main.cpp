// Subscriber sub_2 (drone usv): AVERAGE of usv.accelerometer.accel_y
// (METER_PER_SECOND_SQUARED) every 2.0 s, delivered by the SubBroker over TCP to
// 127.0.0.1:7402.
//
// This file is yours: `modd generate` wrote it once and will never overwrite it.
// Put your processing in on_value().
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <exception>

#include "modd/client/subscriber.hpp"

namespace {

modd::Subscriber* running = nullptr;

void on_value(const modd::Delivered& d) {
  // A window filled from the drone's archive after an outage is historical, not the latest.
  const char* mark = d.backfilled ? " (backfilled)" : "";
  if (!d.present) {
    std::printf("%lld %s: no sample in the window%s\n", static_cast<long long>(d.end_ns), d.topic.c_str(), mark);
  } else if (!d.values.empty()) {
    std::printf("%lld %s: %zu samples%s\n", static_cast<long long>(d.end_ns), d.topic.c_str(), d.values.size(),
                mark);
  } else {
    std::printf("%lld %s %s = %.9g%s\n", static_cast<long long>(d.end_ns), d.topic.c_str(),
                d.aggregation.c_str(), d.value, mark);
  }
  std::fflush(stdout);
}

}  // namespace

int main() {
  const char* port_env = std::getenv("MODD_SUBSCRIBER_PORT");  // override for tests
  const long wanted = port_env ? std::strtol(port_env, nullptr, 10) : 7402;
  if (wanted < 0 || wanted > 65535) {
    std::fprintf(stderr, "MODD_SUBSCRIBER_PORT: not a port: %s\n", port_env);
    return 2;
  }
  const auto port = static_cast<uint16_t>(wanted);
  try {
    // Values are accepted only from the SubBroker, which proves it holds the
    // delivery key ($MODD_DELIVERY_KEY, or ~/.config/modd/delivery.key).
    modd::Subscriber sub("127.0.0.1", port, on_value);
    running = &sub;
    std::signal(SIGINT, [](int) { if (running) running->stop(); });
    std::signal(SIGTERM, [](int) { if (running) running->stop(); });
    std::printf("%s: listening on %s:%u\n", "sub_2", "127.0.0.1", sub.port());
    std::fflush(stdout);
    sub.run();
    running = nullptr;
    const auto s = sub.stats();
    std::fprintf(stderr, "%llu values, %llu connections refused\n",
                 static_cast<unsigned long long>(s.received), static_cast<unsigned long long>(s.refused));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
  return 0;
}
