// libFuzzer target: the datagram transports' receive path (tag check of DATA
// and control datagrams, the serial deframer, COBS) fed arbitrary bytes. Must
// never crash, leak or hit UB; nothing unauthenticated is ever returned.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>

#include "modd/link/datagram.hpp"
#include "modd/util/error.hpp"

using namespace modd;
using namespace modd::link::dgram;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::span<const uint8_t> in(data, size);
  const link::Mac key{};
  try {
    verify_data(in, key, kDroneToBase, 70000);
    // 2^-32 per input: a verifying random datagram would be a finding worth seeing
    std::abort();
  } catch (const Forged&) {
  } catch (const Error&) {
  }
  try {
    verify_control(in, key, kBaseToDrone);
    std::abort();
  } catch (const Forged&) {
  } catch (const Error&) {
  }
  Deframer df(252);
  for (const auto& d : df.feed(in)) {
    if (d.size() > 252) std::abort();
  }
  (void)cobs_decode(in);
  return 0;
}
