// Driver of publisher imu (drone usv): reads the sensors every
// 0.04 s and hands the readings to the on-board PubBroker.
//
// This file is yours. `modd generate` wrote it once and will never overwrite it;
// what the model dictates (topic names, period, ingress) lives in
// generated/imu_topics.hpp, which is regenerated. If a topic is renamed
// in the model, the build fails here, at the line to update.
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>

#include "generated/imu_topics.hpp"

namespace gen = modd_gen::imu;

namespace {

std::atomic<bool> running{true};

// ---- Sensor reads: replace each body with the read of your sensor. ----------
// Until then they return a test signal, so the project runs end to end.
float read_accel_z(double t) {
  return static_cast<float>(std::sin(t + 0));
}
// ------------------------------------------------------------------------------

void usage(const char* argv0) {
  std::printf("usage: %s [--ingress ADDR] [--count N]\n"
              "  --ingress ADDR  unix:/path or tcp:host:port (default: $MODD_INGRESS or %s)\n"
              "  --count N       stop after N readings (default: run until Ctrl-C)\n",
              argv0, gen::kDefaultIngress);
}

}  // namespace

int main(int argc, char** argv) {
  const char* env_ingress = std::getenv("MODD_INGRESS");
  std::string ingress = env_ingress ? env_ingress : gen::kDefaultIngress;
  unsigned long long count = 0;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--ingress") && i + 1 < argc) {
      ingress = argv[++i];
    } else if (!std::strcmp(argv[i], "--count") && i + 1 < argc) {
      count = std::strtoull(argv[++i], nullptr, 10);
    } else {
      usage(argv[0]);
      return std::strcmp(argv[i], "--help") ? 2 : 0;
    }
  }
  std::signal(SIGINT, [](int) { running = false; });
  std::signal(SIGTERM, [](int) { running = false; });

  modd::Publisher pub(gen::kPublisher, ingress);  // waits up to 1 s for the broker's catalogue
  if (!pub.connected()) {
    // Said at once, not after the first flush: the driver keeps queueing (bounded) and
    // reconnects by itself, but whoever starts it should know nothing is received yet.
    std::fprintf(stderr,
                 "%s: cannot reach the PubBroker at %s: is it running (modd up starts one)? "
                 "Readings are queued and sent when it answers.\n",
                 gen::kPublisher, ingress.c_str());
  }
  gen::declare_topics(pub);
  const auto start = std::chrono::steady_clock::now();
  auto next = start;
  for (unsigned long long n = 0; running && (count == 0 || n < count); ++n) {
    const int64_t ts = gen::now_ns();
    const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    // ---- One publish call per topic of imu. ----
    pub.publish(gen::topic::accel_z, ts, read_accel_z(t));
    next += gen::kPeriod;
    std::this_thread::sleep_until(next);
  }
  const bool delivered = pub.flush(std::chrono::seconds(5));
  const auto s = pub.stats();
  const auto dropped = s.dropped_queue_full + s.dropped_bad_topic;
  std::printf("%s: %llu samples published, %llu handed to the PubBroker, %llu dropped\n",
              gen::kPublisher, static_cast<unsigned long long>(s.published), static_cast<unsigned long long>(s.sent),
              static_cast<unsigned long long>(dropped));
  if (!delivered) {
    std::fprintf(stderr, "%s: %llu samples could not be handed to the PubBroker at %s\n",
                 gen::kPublisher, static_cast<unsigned long long>(s.published - s.sent - dropped), ingress.c_str());
    return 1;
  }
  return 0;
}
