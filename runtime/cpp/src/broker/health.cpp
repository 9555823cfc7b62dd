#include "modd/broker/health.hpp"

#include <algorithm>

#include "modd/link/codec.hpp"
#include "modd/link/wire.gen.hpp"
#include "modd/util/bytes.hpp"

namespace modd::broker {

namespace {

// Length of the valid UTF-8 sequence at `s[i]` (its code point in `cp`), or 0.
size_t utf8_sequence(std::string_view s, size_t i, uint32_t& cp) {
  auto b = [&](size_t k) { return static_cast<uint8_t>(s[i + k]); };
  uint8_t c = b(0);
  size_t n = c < 0x80             ? 1
             : (c & 0xE0) == 0xC0 ? 2
             : (c & 0xF0) == 0xE0 ? 3
             : (c & 0xF8) == 0xF0 ? 4
                                  : 0;
  if (n == 0 || i + n > s.size()) return 0;
  cp = n == 1 ? c : c & (0x7F >> n);
  for (size_t k = 1; k < n; ++k) {
    if ((b(k) & 0xC0) != 0x80) return 0;
    cp = (cp << 6) | (b(k) & 0x3F);
  }
  static constexpr uint32_t kLeast[] = {0, 0, 0x80, 0x800, 0x10000};
  if (cp < kLeast[n] || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) return 0;  // overlong
  return n;
}

bool is_control(uint32_t cp) {
  return cp < 0x20 || (cp >= 0x7F && cp <= 0x9F) || cp == 0x2028 || cp == 0x2029 ||
         (cp >= 0x202A && cp <= 0x202E) || (cp >= 0x2066 && cp <= 0x2069);
}

size_t frame_size(const link::Status& st) {
  std::vector<uint8_t> out;
  link::encode(out, st);
  return out.size();
}

using link::StatusField;
constexpr size_t at(StatusField f) { return static_cast<size_t>(f); }

uint64_t state_of(const link::SensorHealth& h) {
  return h.fields.size() > kStateField ? h.fields[kStateField] : kStateClosed;
}

}  // namespace

std::string printable_name(std::string_view raw) {
  std::string out;
  out.reserve(raw.size());
  for (size_t i = 0; i < raw.size();) {
    uint32_t cp = 0;
    size_t n = utf8_sequence(raw, i, cp);
    if (n == 0 || is_control(cp)) {
      out += '?';
      i += n ? n : 1;
    } else {
      out.append(raw.substr(i, n));
      i += n;
    }
  }
  return out;
}

size_t sanitise_health(link::SensorHealth& h) {
  size_t fixed = 0;
  std::string name = printable_name(h.name);
  if (name != h.name) {
    h.name = std::move(name);
    ++fixed;
  }
  for (size_t i = 0; i < h.fields.size(); ++i) {
    uint64_t& f = h.fields[i];
    uint64_t ok = i == kStateField       ? std::min(f, kStateSilent)
                  : i == kLastValueField ? (f > kMaxLastValueMs ? 0 : f)
                                         : std::min(f, kMaxHealthCount);
    if (ok != f) {
      f = ok;
      ++fixed;
    }
  }
  return fixed;
}

size_t health_entry_size(const link::SensorHealth& h) {
  size_t n = varint_size(h.name.size()) + h.name.size() + varint_size(h.fields.size());
  for (uint64_t f : h.fields) n += varint_size(f);
  return n;
}

void count_instruments(std::vector<uint64_t>& counters,
                       const std::vector<link::SensorHealth>& all) {
  if (counters.size() < link::kStatusFieldCount) counters.resize(link::kStatusFieldCount, 0);
  counters[at(StatusField::Instruments)] = all.size();
  counters[at(StatusField::InstrumentsOpen)] = 0;
  counters[at(StatusField::InstrumentsSilent)] = 0;
  counters[at(StatusField::InstrumentsClosed)] = 0;
  for (const auto& h : all) {
    uint64_t s = state_of(h);
    ++counters[at(s == kStateOpen     ? StatusField::InstrumentsOpen
                  : s == kStateSilent ? StatusField::InstrumentsSilent
                                      : StatusField::InstrumentsClosed)];
  }
}

link::Status fit_status(std::vector<uint64_t> counters, std::vector<link::SensorHealth> all,
                        size_t room) {
  count_instruments(counters, all);
  // The instruments in trouble first: they are what the operator must see.
  std::ranges::stable_sort(all, [](const auto& a, const auto& b) {
    bool ta = state_of(a) != kStateOpen, tb = state_of(b) != kStateOpen;
    return ta != tb ? ta : a.name < b.name;
  });
  counters[at(StatusField::InstrumentsUnlisted)] = all.size();  // the most it can be: an upper
  size_t used = frame_size(link::Status{counters}) + 2;         // bound of its varint, + count
  size_t take = 0;
  while (take < all.size() && take < link::kMaxHealthSensors &&
         used + health_entry_size(all[take]) <= room)
    used += health_entry_size(all[take++]);
  all.resize(take);
  std::ranges::sort(all, {}, &link::SensorHealth::name);
  counters[at(StatusField::InstrumentsUnlisted)] = counters[at(StatusField::Instruments)] - take;
  link::Status st{std::move(counters), std::move(all)};
  while (!st.sensors.empty() && frame_size(st) > room) {  // the frame's length varint grew
    st.sensors.pop_back();
    ++st.counters[at(StatusField::InstrumentsUnlisted)];
  }
  return st;
}

}  // namespace modd::broker
