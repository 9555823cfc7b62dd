#include "modd/broker/run_record.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <nlohmann/json.hpp>

#include "modd/util/log.hpp"

namespace modd::broker {

RunRecord::RunRecord(std::string dir, const std::string& prefix, int64_t started_ns)
    : dir_(std::move(dir)), started_ns_(started_ns) {
  std::time_t t = static_cast<std::time_t>(started_ns / 1'000'000'000);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y%m%dT%H%M%SZ", &tm);
  run_ = std::string(stamp) + "-" + std::to_string(::getpid());
  path_ = dir_ + "/" + prefix + "-run-" + run_ + ".counters.json";
}

void RunRecord::note_clock(uint64_t steps, int64_t wall_minus_timeline_ns, Timeline::Step last) {
  clock_steps_ = steps;
  clock_offset_ns_ = wall_minus_timeline_ns;
  clock_last_ = last;
}

bool RunRecord::write(const std::vector<std::pair<std::string, uint64_t>>& counters,
                      const std::vector<std::pair<std::string, uint64_t>>& files, bool final,
                      int64_t now_ns) {
  nlohmann::ordered_json doc;
  doc["run"] = run_;
  doc["started_ns"] = started_ns_;
  doc["updated_ns"] = now_ns;
  doc["final"] = final;
  auto& c = doc["counters"] = nlohmann::ordered_json::object();
  for (const auto& [k, v] : counters) c[k] = v;
  if (clock_steps_)
    doc["clock"] = {{"steps", clock_steps_},
                    {"wall_minus_timeline_ns", clock_offset_ns_},
                    {"last_step_at_ns", clock_last_.at_ns},
                    {"last_step_ns", clock_last_.delta_ns}};
  auto& f = doc["files"] = nlohmann::ordered_json::object();
  for (const auto& [name, n] : files) f[name] = n;
  std::string text = doc.dump() + "\n";
  std::string tmp = path_ + ".tmp";
  bool ok = false;
  int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  int err = errno;
  if (fd >= 0) {
    size_t done = 0;
    while (done < text.size()) {
      ssize_t n = ::write(fd, text.data() + done, text.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) break;
      done += static_cast<size_t>(n);
    }
    err = errno;
    ok = ::close(fd) == 0 && done == text.size();
    if (ok) ok = ::rename(tmp.c_str(), path_.c_str()) == 0;
    if (!ok) {
      err = errno ? errno : err;
      ::unlink(tmp.c_str());  // a partial copy must not hold space the archive needs
    }
  }
  if (ok == failing_) {
    failing_ = !ok;
    if (failing_)
      log_line("archive: cannot write the run's counters %s: %s (the last copy stays)",
               path_.c_str(), std::strerror(err));
    else
      log_line("archive: the run's counters are written again (%s)", path_.c_str());
  }
  return ok;
}

}  // namespace modd::broker
