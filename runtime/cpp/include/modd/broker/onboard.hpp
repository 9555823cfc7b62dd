// The on-board model file on the PubBroker's side (docs/protocol.md, "ONBOARD";
// docs/sensors.md, "Deploying to a running drone"): an ONBOARD's model written where
// modd-sensors and modd-mavlink --watch read it, and their answers gathered for the
// ONBOARD_ACK. The file layout is modd.onboard's (runtime/python/src/modd/onboard.py):
// `<file>.valid` holds the digest (the first 16 hex digits of the SHA-256 of the file's
// bytes), then `<file>` is replaced; each process answers in `<dir>/applied/<name>.json`.
#pragma once
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "modd/link/messages.hpp"

namespace modd::broker {

// The zstd frame `model` decompressed (bounded by kMaxOnboardBytes, its size declared in
// the frame), checked to be a JSON object and written to `path` (atomically, `.valid`
// first); its digest. Throws Error(BadConfig) naming what is wrong.
std::string write_onboard(const std::string& path, std::span<const uint8_t> model);

// Every on-board process's answer for `digest`, as a JSON object by process name, once
// each result file under `<dir of path>/applied` carries it, or when `final` (those that
// have not answered say so); nullopt while one is still awaited.
std::optional<std::string> onboard_answers(const std::string& path, const std::string& digest,
                                           bool final);

// ONBOARD_ACK carrying `answers_json` compressed (a one-line summary when it does not fit).
link::OnboardAck onboard_ack(uint8_t config_id, uint8_t status, const std::string& answers_json);

}  // namespace modd::broker
