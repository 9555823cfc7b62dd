// One-line log messages, prefixed with the UTC time and the program: on stderr, or in a
// file rotated by size (log_to_file). Safe to call from any thread.
#pragma once
#include <cstdint>
#include <string>

namespace modd {
void log_line(const char* fmt, ...) __attribute__((format(printf, 1, 2)));
// From now on, lines go to `path` (appended); when it would pass max_bytes it is renamed
// path.1 (path.1 -> path.2, ... up to path.<keep>, the oldest dropped) and a new one begun.
// Throws Error(Io) if the file cannot be opened.
void log_to_file(const std::string& path, uint64_t max_bytes, uint32_t keep);
}  // namespace modd
