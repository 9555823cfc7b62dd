// libFuzzer target: the link decoder as the PubBroker runs it (a LinkSession
// fed arbitrary bytes, before and after authentication) and the DATA decoder
// with a fixed set of value kinds, and again with declared resolutions (quantised
// values must read back within half a step), and the exact statistics' accumulators
// (MEDIAN, STDDEV, RANGE, PERCENTILE(p)) over the bytes as samples; a CONFIG's
// PERCENTILE p reads back the same, within 0..100. Must never crash, leak or hit UB.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "modd/broker/accumulator.hpp"
#include "modd/broker/events.hpp"
#include "modd/broker/link_session.hpp"
#include "modd/link/auth.hpp"
#include "modd/link/codec.hpp"

using namespace modd;
using namespace modd::link;

namespace {
struct Hooks : broker::LinkHooks {
  ConfigAck on_config(const Config& c) override { return {c.config_id, 0, 1}; }
  AuthOk current_config() override { return {}; }
  void on_authenticated() override {}
  void on_rejected(const std::string&) override {}
};
bool close(double a, double b, double r) {
  return a == b || (std::isnan(a) && std::isnan(b)) || std::fabs(a - b) <= r / 2;
}

// A DATA frame read with declared resolutions: whatever decodes encodes and reads
// back within half a step (an escaped value may come back as steps).
void check_quantised(const RawFrame& f) {
  static const std::vector<ValueKind> kinds = {
      value_kind(ValueType::Float32, Aggregation::Average, 0.01),
      value_kind(ValueType::Float64, Aggregation::All, 0.5),
      value_kind(ValueType::Float32, Aggregation::Max, 1e-9),
      value_kind(ValueType::Int, Aggregation::Sum, 0.1),
      value_kind(ValueType::Float32, Aggregation::Stddev, 0.01),
      value_kind(ValueType::Int, Aggregation::Median, 0.5)};
  Data d;
  try {
    d = decode_data(f, kinds);
  } catch (const Error&) { return; }
  std::vector<uint8_t> out;
  encode_data(out, d, kinds);
  Data back = decode_data(*split_frame(out), kinds);
  for (size_t i = 0; i < kinds.size(); ++i) {
    double r = kinds[i].resolution;
    if (back.values[i].present != d.values[i].present) std::abort();
    if (r > 0 && !close(back.values[i].number, d.values[i].number, r)) std::abort();
    if (back.values[i].numbers.size() != d.values[i].numbers.size()) std::abort();
    for (size_t j = 0; j < d.values[i].numbers.size(); ++j)
      if (!close(back.values[i].numbers[j], d.values[i].numbers[j], r)) std::abort();
  }
}
// The bytes as float64 samples of one window: MEDIAN and PERCENTILE(p) (p from the
// first byte, in (0, 100]) lie within [min, max], PERCENTILE(100) is max, STDDEV lies
// within [0, max - min]; the int RANGE equals max - min.
void check_statistics(std::span<const uint8_t> in) {
  broker::Accumulator med(ValueType::Float64, Aggregation::Median);
  broker::Accumulator sd(ValueType::Float64, Aggregation::Stddev);
  broker::Accumulator range(ValueType::Int, Aggregation::Range);
  double lo = INFINITY, hi = -INFINITY;
  std::vector<double> kept;
  for (size_t at = 0; at + 8 <= in.size(); at += 8) {
    double x;
    std::memcpy(&x, in.data() + at, 8);
    if (!std::isfinite(x) || std::fabs(x) > 1e150) continue;  // no overflow of the squares
    med.add(x, 0);
    sd.add(x, 0);
    range.add(0, static_cast<int64_t>(std::fmod(x, 1e9)));  // in range: no UB
    lo = std::min(lo, x);
    hi = std::max(hi, x);
    kept.push_back(x);
  }
  link::Value m = med.take(), s = sd.take(), r = range.take();
  if (m.present != s.present || m.present != r.present) std::abort();
  if (!m.present) return;
  if (m.number < lo || m.number > hi) std::abort();
  if (!(s.number >= 0) || s.number > (hi - lo) + 1e-9 * std::max(-lo, hi)) std::abort();
  if (r.integer < 0) std::abort();
  double p = 100.0 * (in[0] + 1) / 256.0, q = broker::percentile(kept, p);
  if (q < lo || q > hi || broker::percentile(kept, 100) != hi) std::abort();
  if (broker::percentile(kept, 0) != lo) std::abort();
  // the PERCENTILE(p) accumulator gives the statistic of the window's samples
  broker::Accumulator pct(ValueType::Float64, Aggregation::Percentile, p);
  for (double x : kept) pct.add(x, 0);
  if (pct.take().number != broker::percentile(kept, p)) std::abort();
}
// A THRESHOLD (flapping input) keeps at most N events a window and counts the rest:
// every crossing is kept or coalesced, none lost.
void check_events(std::span<const uint8_t> in) {
  if (in.empty()) return;
  broker::EventSpec spec;
  spec.kind = events::EventKind::Threshold;
  spec.max_events = in[0] % 8 + 1;
  spec.hysteresis = (in[0] >> 3) / 4.0;
  broker::EventDetector det(spec);
  uint64_t crossings = 0, kept = 0, coalesced = 0;
  for (size_t at = 1; at < in.size(); ++at) {
    crossings += det.add(static_cast<int64_t>(at), static_cast<int8_t>(in[at]) / 16.0) ? 1 : 0;
    if (at % 32 == 0 || at + 1 == in.size()) {
      broker::EventWindow w = det.take();
      if (w.events.size() > spec.max_events) std::abort();
      kept += w.events.size();
      coalesced += w.coalesced;
    }
  }
  if (kept + coalesced != crossings) std::abort();
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::span<const uint8_t> in(data, size);
  // 1. Raw frames: split and decode every one.
  size_t at = 0;
  try {
    while (auto f = split_frame(in.subspan(at))) {
      at += f->size;
      if (is_data_type(f->type)) {
        check_quantised(*f);
        static const std::vector<ValueKind> kinds = {
            value_kind(ValueType::Float32, Aggregation::Average),
            value_kind(ValueType::Int, Aggregation::All),
            value_kind(ValueType::Bool, Aggregation::Min),
            value_kind(ValueType::Float64, Aggregation::Count),
            value_kind(ValueType::Int, Aggregation::Sum),
            value_kind(ValueType::Float64, Aggregation::Median),
            value_kind(ValueType::Float32, Aggregation::Stddev),
            value_kind(ValueType::Int, Aggregation::Range),
            value_kind(ValueType::Float32, Aggregation::Percentile),
            value_kind(ValueType::Float32, Aggregation::Threshold),
            value_kind(ValueType::Int, Aggregation::OnChange)};
        (void)decode_data(*f, kinds);
      } else {
        Message m = decode(*f);
        std::vector<uint8_t> out;
        encode(out, m);  // whatever decodes must encode
        if (const auto* c = std::get_if<Config>(&m)) {
          // and a CONFIG (its optional accepted delay included) must read back the same
          auto g = split_frame(out);
          if (!g || !(std::get<Config>(decode(*g)) == *c)) std::abort();
          for (const auto& s : c->streams)  // PERCENTILE's p read back within 0..100
            if (s.aggregation == Aggregation::Percentile &&
                !(s.percentile >= 0 && s.percentile <= 100))
              std::abort();
          for (const auto& s : c->streams)  // event parameters read back in range
            if (is_event(s.aggregation) &&
                (s.event.max_events > events::kMaxEvents || !(s.event.deadband >= 0) ||
                 !(s.event.hysteresis >= 0) || !std::isfinite(s.event.level)))
              std::abort();
        }
      }
    }
  } catch (const Error&) {}
  check_statistics(in);
  check_events(in);
  // 2. A session: the handshake done with the right key, then the fuzz bytes.
  Hooks h;
  const std::string key = "fuzz";
  broker::LinkSession s(key, h, [] { return Nonce{}; });
  std::vector<uint8_t> out, hello, auth;
  Nonce cn{};
  encode(hello, Hello{kVersion, cn});
  std::span<const uint8_t> kb(reinterpret_cast<const uint8_t*>(key.data()), key.size());
  encode(auth, Auth{client_proof(kb, cn, Nonce{})});
  if (size > 0 && (data[0] & 1)) {
    s.on_bytes(hello, out);
    s.on_bytes(auth, out);
  }
  s.on_bytes(in, out);
  return 0;
}
