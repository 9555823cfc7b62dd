#include "modd/broker/counters.hpp"

namespace modd::broker {

const char* reject_name(Reject r) {
  switch (r) {
    case Reject::UnknownTopic: return "unknown_topic";
    case Reject::WrongType: return "wrong_type";
    case Reject::NotFinite: return "not_finite";
    case Reject::Timestamp: return "timestamp";
    case Reject::Overflow: return "overflow";
    case Reject::Malformed: return "malformed";
    case Reject::Quota: return "quota";
    case Reject::kCount: break;
  }
  return "?";
}

const char* const kStatusFieldNames[kStatusFieldCount] = {"uptime_s",
                                                          "samples_in",
                                                          "samples_archived",
                                                          "rejected_unknown_topic",
                                                          "rejected_wrong_type",
                                                          "rejected_not_finite",
                                                          "rejected_timestamp",
                                                          "rejected_overflow",
                                                          "rejected_malformed",
                                                          "archive_failed",
                                                          "ingress_malformed_frames",
                                                          "publishers_connected",
                                                          "frames_sent",
                                                          "frames_dropped",
                                                          "link_bytes_sent",
                                                          "disk_free_mb",
                                                          "buffer_fill_pct",
                                                          "archive_files",
                                                          "auth_failures",
                                                          "config_id",
                                                          "rejected_quota",
                                                          "archive_state",
                                                          "archive_rate_bps",
                                                          "samples_pending",
                                                          "link_datagrams_sent",
                                                          "link_datagrams_resent",
                                                          "link_nacks",
                                                          "link_slots_dropped",
                                                          "link_forged",
                                                          "link_replayed"};

}  // namespace modd::broker
