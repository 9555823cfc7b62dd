// A sensor driver publishing three accelerometer axes at 25 Hz to the
// PubBroker's ingress. `--self-test` only checks that the client works with no
// broker running (samples queue, nothing throws) and exits.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <thread>

#include "modd/client/publisher.hpp"

static int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

int main(int argc, char** argv) {
  bool self_test = argc > 1 && !std::strcmp(argv[1], "--self-test");
  std::string ingress = (argc > 2) ? argv[2] : "unix:/tmp/modd/ingress.sock";
  if (self_test) ingress = "unix:/nonexistent/modd-example.sock";
  modd::Publisher pub("pub_1", ingress, {.queue_capacity = 8});
  const char* axes[] = {"usv.accelerometer.accel_x", "usv.accelerometer.accel_y", "usv.accelerometer.accel_z"};
  for (const char* a : axes) pub.declare(a, modd::ValueType::Float32);
  int n = self_test ? 10 : 250;
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) pub.publish(axes[k], now_ns(), static_cast<float>(std::sin(0.1 * i + k)));
    if (!self_test) std::this_thread::sleep_for(std::chrono::milliseconds(40));
  }
  auto s = pub.stats();
  std::printf("published %llu, dropped (queue full) %llu\n", static_cast<unsigned long long>(s.published),
              static_cast<unsigned long long>(s.dropped_queue_full));
  if (self_test) return (s.published + s.dropped_queue_full == 30 && s.published <= 16) ? 0 : 1;
  return 0;
}
