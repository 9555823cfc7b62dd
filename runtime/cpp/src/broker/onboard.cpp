#include "modd/broker/onboard.hpp"

#include <openssl/sha.h>
#include <zstd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "modd/util/error.hpp"

namespace modd::broker {

namespace fs = std::filesystem;
using link::kMaxOnboardBytes;
using link::kMaxOnboardWire;

namespace {

std::string digest_of(const std::string& data) {
  unsigned char md[SHA256_DIGEST_LENGTH];
  SHA256(reinterpret_cast<const unsigned char*>(data.data()), data.size(), md);
  static const char* hex = "0123456789abcdef";
  std::string out;
  for (int i = 0; i < 8; ++i) {
    out += hex[md[i] >> 4];
    out += hex[md[i] & 0xF];
  }
  return out;
}

void replace_file(const fs::path& path, const std::string& data) {
  fs::path tmp = path;
  tmp += ".tmp";
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    f.write(data.data(), static_cast<std::streamsize>(data.size()));
    if (!f) throw Error(ErrorCode::Io, "cannot write " + tmp.string());
  }
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) throw Error(ErrorCode::Io, "cannot replace " + path.string() + ": " + ec.message());
}

std::string decompress(std::span<const uint8_t> model) {
  unsigned long long size = ZSTD_getFrameContentSize(model.data(), model.size());
  if (size == ZSTD_CONTENTSIZE_ERROR || size == ZSTD_CONTENTSIZE_UNKNOWN)
    throw Error(ErrorCode::BadConfig, "on-board model: not a zstd frame with its size");
  if (size > kMaxOnboardBytes)
    throw Error(ErrorCode::BadConfig, "on-board model: " + std::to_string(size) + " B, above " +
                                          std::to_string(kMaxOnboardBytes));
  std::string out(static_cast<size_t>(size), '\0');
  size_t n = ZSTD_decompress(out.data(), out.size(), model.data(), model.size());
  if (ZSTD_isError(n) || n != out.size())
    throw Error(ErrorCode::BadConfig, "on-board model: corrupt zstd frame");
  return out;
}

}  // namespace

std::string write_onboard(const std::string& path, std::span<const uint8_t> model) {
  std::string data = decompress(model);
  auto doc = nlohmann::json::parse(data, nullptr, false);
  if (doc.is_discarded() || !doc.is_object())
    throw Error(ErrorCode::BadConfig, "on-board model: not a JSON object");
  fs::path file(path);
  std::error_code ec;
  fs::create_directories(file.parent_path(), ec);
  std::string digest = digest_of(data);
  fs::path valid = file;
  valid += ".valid";
  replace_file(valid, digest + "\n");
  replace_file(file, data);
  return digest;
}

std::optional<std::string> onboard_answers(const std::string& path, const std::string& digest,
                                           bool final) {
  nlohmann::json out = nlohmann::json::object();
  bool all = true;
  std::error_code ec;
  fs::path dir = fs::path(path).parent_path() / "applied";
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    if (entry.path().extension() != ".json") continue;
    std::ifstream f(entry.path());
    std::stringstream text;
    text << f.rdbuf();
    auto doc = nlohmann::json::parse(text.str(), nullptr, false);
    std::string name = entry.path().stem().string();
    if (!doc.is_discarded() && doc.is_object() && doc.value("digest", "") == digest) {
      out[name] = doc;
      continue;
    }
    all = false;
    out[name] = {
        {"process", name},
        {"ok", false},
        {"problem", "no answer within " + std::to_string(link::kOnboardWaitMs / 1000) + " s"}};
  }
  if (!all && !final) return std::nullopt;
  return out.dump();
}

link::OnboardAck onboard_ack(uint8_t config_id, uint8_t status, const std::string& answers_json) {
  auto pack = [](const std::string& s) {
    std::vector<uint8_t> out(ZSTD_compressBound(s.size()));
    size_t n = ZSTD_compress(out.data(), out.size(), s.data(), s.size(), 19);
    out.resize(ZSTD_isError(n) ? 0 : n);
    return out;
  };
  link::OnboardAck ack{config_id, status, pack(answers_json)};
  if (ack.answers.empty() || ack.answers.size() > kMaxOnboardWire)
    ack.answers =
        pack(R"({"pubbroker":{"ok":false,"problem":"the answers do not fit ONBOARD_ACK"}})");
  return ack;
}

}  // namespace modd::broker
