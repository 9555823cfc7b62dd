#include "modd/archive/reader.hpp"

#include <algorithm>
#include <charconv>
#include <cstring>
#include <filesystem>
#include <string_view>

#include "modd/archive/archive_record.gen.hpp"
#include "modd/archive/recover.hpp"
#include "modd/util/error.hpp"

namespace modd::archive {

namespace {

constexpr uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', 0x30, '\r', '\n'};
enum Op : uint8_t {
  kFooter = 0x02,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kDataEnd = 0x0F
};
constexpr uint64_t kMaxRecord = 1ull << 31;

template <typename T>
T get(const uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

bool parse_value(std::string_view json, link::ValueType type, ArchivedSample& s) {
  const std::string_view key = archive_record::kValue;
  size_t at = json.find(key);
  // the field name in quotes: "value"
  if (at == 0 || at == std::string_view::npos || at + key.size() >= json.size() ||
      json[at - 1] != '"' || json[at + key.size()] != '"')
    return false;
  const char* b = json.data() + at + key.size() + 1;
  const char* e = json.data() + json.size();
  auto space = [&] {
    while (b < e && (*b == ' ' || *b == '\t' || *b == '\n' || *b == '\r')) ++b;
  };
  space();
  if (b == e || *b++ != ':') return false;
  space();
  switch (type) {
    case link::ValueType::Float32: {
      float f = 0;
      if (std::from_chars(b, e, f).ec != std::errc()) return false;
      s.number = f;
      return true;
    }
    case link::ValueType::Float64: return std::from_chars(b, e, s.number).ec == std::errc();
    case link::ValueType::Int: return std::from_chars(b, e, s.integer).ec == std::errc();
    case link::ValueType::Bool: {
      std::string_view rest(b, static_cast<size_t>(e - b));
      if (rest.starts_with("true"))
        s.integer = 1;
      else if (rest.starts_with("false"))
        s.integer = 0;
      else
        return false;
      return true;
    }
  }
  return false;
}

}  // namespace

TopicReader::TopicReader(std::string dir, std::string prefix, std::string topic,
                         link::ValueType type)
    : dir_(std::move(dir)), prefix_(std::move(prefix)), topic_(std::move(topic)), type_(type) {}

bool TopicReader::next_file() {
  std::string current = file_open_ ? files_[file_] : std::string();
  files_.clear();
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir_, ec)) {
    std::string name = e.path().filename().string();
    if (name.rfind(prefix_, 0) == 0 && name.ends_with(".mcap")) files_.push_back(e.path().string());
  }
  std::sort(files_.begin(), files_.end());  // <prefix>-<UTC stamp>-<counter>.mcap: time order
  auto it = std::upper_bound(files_.begin(), files_.end(), current);
  if (it == files_.end()) {
    if (file_open_)
      file_ =
          static_cast<size_t>(std::find(files_.begin(), files_.end(), current) - files_.begin());
    return false;
  }
  file_ = static_cast<size_t>(it - files_.begin());
  in_.close();
  in_.clear();
  in_.open(files_[file_], std::ios::binary);
  if (!in_) throw Error(ErrorCode::Io, "cannot read archive file " + files_[file_]);
  file_open_ = true;
  file_done_ = false;
  offset_ = 8;
  channels_.clear();
  uint8_t magic[8];
  in_.read(reinterpret_cast<char*>(magic), 8);
  if (in_.gcount() == 8 && std::memcmp(magic, kMagic, 8) != 0)
    throw Error(ErrorCode::Io, files_[file_] + " is not an MCAP file");
  return true;
}

void TopicReader::channel(const uint8_t* p, uint64_t len) {
  if (len < 8) return;
  uint16_t id = get<uint16_t>(p);
  uint32_t n = get<uint32_t>(p + 4);
  if (len - 8 < n) return;
  if (std::string_view(reinterpret_cast<const char*>(p + 8), n) == topic_) channels_.insert(id);
}

bool TopicReader::take_message(const uint8_t* p, uint64_t len, int64_t from) {
  if (len < 22 || !channels_.count(get<uint16_t>(p))) return false;
  auto stamp = static_cast<int64_t>(get<uint64_t>(p + 6));
  if (stamp < from) return false;
  sample_ = ArchivedSample{};
  sample_.stamp_ns = stamp;
  std::string_view json(reinterpret_cast<const char*>(p + 22), len - 22);
  if (!parse_value(json, type_, sample_))
    throw Error(ErrorCode::Io, files_[file_] + ": a message of " + topic_ + " is not a " +
                                   link::value_type_name(type_) +
                                   " sample: " + std::string(json.substr(0, 64)));
  return true;
}

void TopicReader::scan_chunk_records(int64_t from) {
  while (chunk_at_ + 9 <= chunk_.size()) {
    uint8_t op = chunk_[chunk_at_];
    uint64_t len = get<uint64_t>(chunk_.data() + chunk_at_ + 1);
    if (chunk_.size() - chunk_at_ - 9 < len) break;  // cannot happen after a CRC-checked chunk
    const uint8_t* body = chunk_.data() + chunk_at_ + 9;
    chunk_at_ += 9 + len;
    if (op == kChannel)
      channel(body, len);
    else if (op == kMessage && take_message(body, len, from)) {
      have_ = true;
      return;
    }
  }
  chunk_.clear();
  chunk_at_ = 0;
}

bool TopicReader::read_record(int64_t from) {
  in_.clear();
  in_.seekg(0, std::ios::end);
  auto size = static_cast<uint64_t>(in_.tellg());
  if (size < offset_ + 9) return false;
  uint8_t head[25];
  in_.seekg(static_cast<std::streamoff>(offset_));
  in_.read(reinterpret_cast<char*>(head), 9);
  uint8_t op = head[0];
  uint64_t len = get<uint64_t>(head + 1);
  if (len > kMaxRecord)
    throw Error(ErrorCode::Io,
                files_[file_] + ": record too long at byte " + std::to_string(offset_));
  if (size - offset_ - 9 < len) return false;  // being written
  if (op == kChunk && len >= 16) {
    in_.read(reinterpret_cast<char*>(head + 9), 16);
    auto end = static_cast<int64_t>(get<uint64_t>(head + 17));
    if (end < from) {
      offset_ += 9 + len;
      return true;
    }
    in_.seekg(static_cast<std::streamoff>(offset_ + 9));
  }
  if (op == kChunk || op == kChannel) {
    packed_.resize(len);
    in_.read(reinterpret_cast<char*>(packed_.data()), static_cast<std::streamsize>(len));
    if (static_cast<uint64_t>(in_.gcount()) != len) return false;
    if (op == kChannel) {
      channel(packed_.data(), len);
    } else {
      const uint8_t* p = packed_.data();
      if (len < 32)
        throw Error(ErrorCode::Io,
                    files_[file_] + ": short chunk at byte " + std::to_string(offset_));
      uint64_t usize = get<uint64_t>(p + 16);
      uint32_t clen_name = get<uint32_t>(p + 28);
      if (len < 32 + clen_name + 8ull)
        throw Error(ErrorCode::Io,
                    files_[file_] + ": bad chunk at byte " + std::to_string(offset_));
      std::string comp(reinterpret_cast<const char*>(p + 32), clen_name);
      uint64_t clen = get<uint64_t>(p + 32 + clen_name);
      if (len - 40 - clen_name < clen)
        throw Error(ErrorCode::Io,
                    files_[file_] + ": bad chunk at byte " + std::to_string(offset_));
      if (!decompress_chunk(comp, std::span(p + 40 + clen_name, clen), usize, chunk_))
        throw Error(ErrorCode::Io, files_[file_] + ": chunk at byte " + std::to_string(offset_) +
                                       " does not decompress");
      chunk_at_ = 0;
    }
  } else if (op == kDataEnd || op == kFooter) {
    file_done_ = true;
  }
  offset_ += 9 + len;
  return true;
}

std::optional<ArchivedSample> TopicReader::peek(int64_t from) {
  if (have_ && sample_.stamp_ns < from) have_ = false;
  while (!have_) {
    if (chunk_at_ < chunk_.size()) {
      scan_chunk_records(from);
      continue;
    }
    if (!file_open_ || file_done_) {
      if (!next_file()) return std::nullopt;
      continue;
    }
    if (!read_record(from)) {
      // The end of what is written. A newer file means this one will not grow (a rotation).
      if (!next_file()) return std::nullopt;
    }
  }
  return sample_;
}

}  // namespace modd::archive
