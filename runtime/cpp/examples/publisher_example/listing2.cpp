// Driver code written like the paper's Listing 2: the variable's short name, a double on a
// float32 topic. Every sample reaches the archive; a wrong topic name is refused at the call.
//
//   listing2 ADDRESS COUNT
// Exit 0 when the contract held: COUNT samples accepted and acknowledged on disk, the
// misspelt topic refused with a message naming it.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>

#include "modd/client/publisher.hpp"

static int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: listing2 ADDRESS COUNT\n");
    return 2;
  }
  int count = std::atoi(argv[2]);
  auto publisher = std::make_unique<modd::Publisher>("pub_1", argv[1]);
  int accepted = 0;
  for (int i = 0; i < count; ++i) {
    int64_t timestamp = now_ns();
    double value = 9.81 + 0.001 * i;
    accepted += publisher->publish("accel_z", timestamp, value);
  }
  bool refused = !publisher->publish("accel_zz", now_ns(), 1.0);
  std::string why = publisher->last_error();
  bool on_disk = publisher->wait_on_disk(std::chrono::seconds(5));
  auto s = publisher->stats();
  std::printf("accepted %d, refused wrong name %d (%s), on disk %llu, rejected by broker %llu\n",
              accepted, refused, why.c_str(), static_cast<unsigned long long>(s.on_disk),
              static_cast<unsigned long long>(s.rejected_by_broker));
  bool ok = accepted == count && refused && why.find("accel_zz") != std::string::npos && on_disk &&
            s.on_disk == static_cast<uint64_t>(count) && s.rejected_by_broker == 0;
  return ok ? 0 : 1;
}
