// Driver of publisher pub_1 (drone usv): reads the sensors every
// 0.04 s and hands the readings to the on-board PubBroker.
//
// This file is yours. `modd generate` wrote it once and will never overwrite it;
// what the model dictates (topic names, period, ingress) lives in
// generated/pub_1_topics.hpp, which is regenerated. If a topic is renamed
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

#include "generated/pub_1_topics.hpp"

namespace gen = modd_gen::pub_1;

namespace {

std::atomic<bool> running{true};

// ---- Sensor reads: replace each body with the read of your sensor. ----------
// Until then they return a test signal, so the project runs end to end.
float read_accel_x(double t) {
  return static_cast<float>(std::sin(t + 0));
}
float read_accel_y(double t) {
  return static_cast<float>(std::sin(t + 1));
}
float read_accel_z(double t) {
  return static_cast<float>(std::sin(t + 2));
}
float read_gyro_x(double t) {
  return static_cast<float>(std::sin(t + 3));
}
float read_gyro_y(double t) {
  return static_cast<float>(std::sin(t + 4));
}
float read_gyro_z(double t) {
  return static_cast<float>(std::sin(t + 5));
}
float read_roll(double t) {
  return static_cast<float>(std::sin(t + 6));
}
float read_pitch(double t) {
  return static_cast<float>(std::sin(t + 7));
}
float read_yaw(double t) {
  return static_cast<float>(std::sin(t + 8));
}
float read_vel_north(double t) {
  return static_cast<float>(std::sin(t + 9));
}
float read_vel_east(double t) {
  return static_cast<float>(std::sin(t + 10));
}
float read_vel_down(double t) {
  return static_cast<float>(std::sin(t + 11));
}
float read_latitude(double t) {
  return static_cast<float>(std::sin(t + 12));
}
float read_longitude(double t) {
  return static_cast<float>(std::sin(t + 13));
}
float read_altitude(double t) {
  return static_cast<float>(std::sin(t + 14));
}
float read_temperature(double t) {
  return static_cast<float>(std::sin(t + 15));
}
float read_pressure(double t) {
  return static_cast<float>(std::sin(t + 16));
}
float read_heave(double t) {
  return static_cast<float>(std::sin(t + 17));
}
float read_undulation(double t) {
  return static_cast<float>(std::sin(t + 18));
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
    // ---- One publish call per topic of pub_1. ----
    pub.publish(gen::topic::accel_x, ts, read_accel_x(t));
    pub.publish(gen::topic::accel_y, ts, read_accel_y(t));
    pub.publish(gen::topic::accel_z, ts, read_accel_z(t));
    pub.publish(gen::topic::gyro_x, ts, read_gyro_x(t));
    pub.publish(gen::topic::gyro_y, ts, read_gyro_y(t));
    pub.publish(gen::topic::gyro_z, ts, read_gyro_z(t));
    pub.publish(gen::topic::roll, ts, read_roll(t));
    pub.publish(gen::topic::pitch, ts, read_pitch(t));
    pub.publish(gen::topic::yaw, ts, read_yaw(t));
    pub.publish(gen::topic::vel_north, ts, read_vel_north(t));
    pub.publish(gen::topic::vel_east, ts, read_vel_east(t));
    pub.publish(gen::topic::vel_down, ts, read_vel_down(t));
    pub.publish(gen::topic::latitude, ts, read_latitude(t));
    pub.publish(gen::topic::longitude, ts, read_longitude(t));
    pub.publish(gen::topic::altitude, ts, read_altitude(t));
    pub.publish(gen::topic::temperature, ts, read_temperature(t));
    pub.publish(gen::topic::pressure, ts, read_pressure(t));
    pub.publish(gen::topic::heave, ts, read_heave(t));
    pub.publish(gen::topic::undulation, ts, read_undulation(t));
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
