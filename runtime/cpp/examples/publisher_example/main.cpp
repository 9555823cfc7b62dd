// A sensor driver publishing three accelerometer axes to the PubBroker's ingress.
//
//   publisher_example [ADDRESS [COUNT [HZ]]]   default unix:/tmp/modd/usv/ingress.sock, 250, 25
//   publisher_example --self-test              no broker: samples queue, nothing throws
//
// Values are sin(0.1 * i + axis) as float32; timestamps are the system clock in ns.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>

#include "modd/client/publisher.hpp"

static int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

int main(int argc, char** argv) {
  bool self_test = argc > 1 && !std::strcmp(argv[1], "--self-test");
  std::string ingress = self_test  ? "unix:/nonexistent/modd-example.sock"
                        : argc > 1 ? argv[1]
                                   : "unix:/tmp/modd/usv/ingress.sock";
  int count = self_test ? 10 : argc > 2 ? std::atoi(argv[2]) : 250;
  double hz = argc > 3 ? std::atof(argv[3]) : 25.0;
  modd::Publisher pub("pub_1", ingress, {.queue_capacity = self_test ? 8u : 65536u});
  const char* axes[] = {"usv.accelerometer.accel_x", "usv.accelerometer.accel_y",
                        "usv.accelerometer.accel_z"};
  for (const char* a : axes) pub.declare(a, modd::ValueType::Float32);
  for (int i = 0; i < count; ++i) {
    for (int k = 0; k < 3; ++k)
      pub.publish(axes[k], now_ns(), static_cast<float>(std::sin(0.1 * i + k)));
    if (!self_test && hz > 0) std::this_thread::sleep_for(std::chrono::duration<double>(1.0 / hz));
  }
  bool flushed = pub.flush(std::chrono::seconds(5));
  auto s = pub.stats();
  std::printf("published %llu, sent %llu, dropped (queue full) %llu\n",
              static_cast<unsigned long long>(s.published), static_cast<unsigned long long>(s.sent),
              static_cast<unsigned long long>(s.dropped_queue_full));
  if (self_test) return (s.published + s.dropped_queue_full == 30 && s.published <= 16) ? 0 : 1;
  return flushed && s.sent == static_cast<unsigned long long>(3 * count) ? 0 : 1;
}
