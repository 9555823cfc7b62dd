// One-line log messages on stderr, prefixed with the UTC time and the program.
#pragma once

namespace modd {
void log_line(const char* fmt, ...) __attribute__((format(printf, 1, 2)));
}
