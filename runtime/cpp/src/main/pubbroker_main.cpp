// modd-pubbroker: the on-board broker. main() is a straight line:
// arguments -> config -> key -> server (archive, listeners) -> loop -> clean stop.
#include <signal.h>

#include <cstdio>
#include <cstring>
#include <string>

#include "modd/broker/config.hpp"
#include "modd/broker/server.hpp"
#include "modd/link/auth.hpp"
#include "modd/util/clock.hpp"
#include "modd/util/error.hpp"
#include "modd/util/log.hpp"

namespace {

const char* kUsage =
    "usage: modd-pubbroker --config FILE [--onboard-model PATH]\n"
    "\n"
    "The MoDD on-board broker: archives every published sample to MCAP files,\n"
    "computes the scheduled aggregates and sends them to the base station over\n"
    "the MoDD link (docs/protocol.md). The config file format is in docs/pubbroker.md.\n"
    "\n"
    "options:\n"
    "  --config FILE   the broker's JSON configuration (required)\n"
    "  --onboard-model PATH  write a deployed model received over the link (ONBOARD)\n"
    "                  there, for modd-sensors and modd-mavlink --watch, and send\n"
    "                  their answers back (docs/sensors.md); without it ONBOARD is refused\n"
    "  --help          this text\n"
    "\n"
    "SIGTERM or SIGINT: flush the buffers, close the archive, exit 0.\n";

}  // namespace

int main(int argc, char** argv) {
  std::string config_path, onboard_model;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--help") || !std::strcmp(argv[i], "-h")) {
      std::fputs(kUsage, stdout);
      return 0;
    }
    if (!std::strcmp(argv[i], "--config") && i + 1 < argc) {
      config_path = argv[++i];
      continue;
    }
    if (!std::strcmp(argv[i], "--onboard-model") && i + 1 < argc) {
      onboard_model = argv[++i];
      continue;
    }
    std::fprintf(stderr, "modd-pubbroker: unknown argument '%s'\n%s", argv[i], kUsage);
    return 2;
  }
  if (config_path.empty()) {
    std::fprintf(stderr, "modd-pubbroker: --config FILE is required\n%s", kUsage);
    return 2;
  }
  // SIGTERM/SIGINT are read from a signalfd by the event loop: block them before any thread
  // (the archive writer) starts, so that every thread inherits the mask.
  sigset_t mask;
  sigemptyset(&mask);
  sigaddset(&mask, SIGTERM);
  sigaddset(&mask, SIGINT);
  pthread_sigmask(SIG_BLOCK, &mask, nullptr);
  try {
    modd::broker::BrokerConfig cfg = modd::broker::load_config(config_path);
    cfg.onboard_model = onboard_model;
    if (!cfg.log_file.empty()) modd::log_to_file(cfg.log_file, cfg.log_max_bytes, cfg.log_keep);
    std::string key = modd::link::resolve_key(cfg.key_ref);
    modd::SystemClock clock;
    modd::broker::Server server(cfg, key, clock);
    server.run();
  } catch (const modd::Error& e) {
    std::fprintf(stderr, "modd-pubbroker: %s\n", e.what());
    return 1;
  }
  return 0;
}
