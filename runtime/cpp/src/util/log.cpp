#include "modd/util/log.hpp"

#include <algorithm>
#include <cerrno>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <mutex>

#include "modd/util/error.hpp"

namespace modd {

namespace {

struct Sink {
  std::mutex mu;
  FILE* file = nullptr;  // nullptr: stderr
  std::string path;
  uint64_t max_bytes = 0, size = 0;
  uint32_t keep = 0;

  void rotate() {
    std::fclose(file);
    file = nullptr;
    for (uint32_t i = keep; i >= 1; --i) {
      std::string from = i == 1 ? path : path + "." + std::to_string(i - 1);
      std::rename(from.c_str(), (path + "." + std::to_string(i)).c_str());
    }
    if (keep == 0) std::remove(path.c_str());
    file = std::fopen(path.c_str(), "a");
    size = 0;
  }
};

Sink& sink() {
  static Sink s;
  return s;
}

}  // namespace

void log_to_file(const std::string& path, uint64_t max_bytes, uint32_t keep) {
  Sink& s = sink();
  std::lock_guard lk(s.mu);
  FILE* f = std::fopen(path.c_str(), "a");
  if (!f) throw Error(ErrorCode::Io, "cannot open log file " + path + ": " + std::strerror(errno));
  if (s.file) std::fclose(s.file);
  s.file = f;
  s.path = path;
  s.max_bytes = max_bytes;
  s.keep = keep;
  std::fseek(f, 0, SEEK_END);
  long at = std::ftell(f);
  s.size = at > 0 ? static_cast<uint64_t>(at) : 0;
}

void log_line(const char* fmt, ...) {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  std::tm tm{};
  gmtime_r(&ts.tv_sec, &tm);
  char head[48];
  std::strftime(head, sizeof head, "%Y-%m-%dT%H:%M:%S", &tm);
  char msg[1024];
  va_list ap;
  va_start(ap, fmt);
  std::vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  char line[1200];
  int n = std::snprintf(line, sizeof line, "%s.%03ldZ modd-pubbroker: %s\n", head,
                        ts.tv_nsec / 1000000, msg);
  size_t len = n < 0 ? 0 : std::min<size_t>(static_cast<size_t>(n), sizeof line - 1);
  Sink& s = sink();
  std::lock_guard lk(s.mu);
  if (s.file && s.size + len > s.max_bytes) s.rotate();
  FILE* out = s.file ? s.file : stderr;
  std::fwrite(line, 1, len, out);
  std::fflush(out);
  s.size += len;
}

}  // namespace modd
