// Generated from the contracts by `python -m modd_contracts.typegen`. Do not edit.
// The archive record (metamodel/src/modd_contracts/schemas/archive_record.schema.json):
// the MCAP message, schema and channel of one sample, written by the archiver
// and read by the archive reader (docs/pubbroker.md).
#pragma once

#include <cstdint>
#include <string_view>

namespace modd::archive_record {

inline constexpr int64_t kVersion = 1;
// The one field of a message: the sample.
inline constexpr std::string_view kValue = "value";
// A channel's schema is named kSchemaPrefix + value type.
inline constexpr std::string_view kSchemaPrefix = "modd.";
inline constexpr std::string_view kSchemaEncoding = "jsonschema";
inline constexpr std::string_view kMessageEncoding = "json";
// The channel metadata key holding the value type.
inline constexpr std::string_view kTypeMetadataKey = "type";
// Schema data of a channel, by value type (link::ValueType's order).
inline constexpr std::string_view kChannelSchemas[] = {
    "{\"type\":\"object\",\"properties\":{\"value\":{\"type\":\"number\"}},\"required\":[\"value\"]}",
    "{\"type\":\"object\",\"properties\":{\"value\":{\"type\":\"number\"}},\"required\":[\"value\"]}",
    "{\"type\":\"object\",\"properties\":{\"value\":{\"type\":\"integer\"}},\"required\":[\"value\"]}",
    "{\"type\":\"object\",\"properties\":{\"value\":{\"type\":\"boolean\"}},\"required\":[\"value\"]}",
};

}  // namespace modd::archive_record
