// libFuzzer target: the backfill decoders (docs/protocol.md, "Backfill") on
// arbitrary frames, every value kind of DATA. Must never crash, leak or hit UB;
// whatever decodes must encode back to the same bytes.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "modd/link/backfill.hpp"

using namespace modd;
using namespace modd::link;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  // First byte picks the value kind of BACKFILL_DATA (any aggregation, events included);
  // the rest is a frame stream.
  ValueKind kind = value_kind(static_cast<ValueType>(data[0] & 3),
                              static_cast<Aggregation>((data[0] >> 2) % table::kAggregationCount));
  std::span<const uint8_t> in(data + 1, size - 1);
  size_t at = 0;
  try {
    while (auto f = split_frame(in.subspan(at))) {
      at += f->size;
      std::vector<uint8_t> out;
      if (f->type == static_cast<uint8_t>(backfill::Type::Data)) {
        backfill::encode_data(out, backfill::decode_data(*f, kind), kind);
      } else {
        backfill::encode(out, backfill::decode(*f));
        // The encoding is canonical except for non-minimal varints: re-decoding must agree.
        auto g = split_frame(out);
        if (!g || !(backfill::decode(*g) == backfill::decode(*f))) std::abort();
      }
    }
  } catch (const Error&) {}
  return 0;
}
