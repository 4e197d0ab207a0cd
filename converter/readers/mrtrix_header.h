// The text header MRtrix puts in front of its track files (TCK, "mrtrix tracks") and track scalar
// files (TSF, "mrtrix track scalars"): a magic line, "key: value" lines (keys may repeat; a line without
// a colon continues the previous value), "END". Required: "datatype" and "file: . OFFSET" (data in the
// same file, after the header).
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>

#include <nlohmann/json.hpp>

namespace vxl {

struct MrtrixHeader {
  nlohmann::json fields = nlohmann::json::object();  // key -> array of values (keys may repeat)
  std::string datatype;
  std::uint64_t data_offset = 0;
  std::optional<std::uint64_t> count;  // "count", when it parses (it may be stale: the data is trusted)
  // The last value of `key`, if present.
  std::optional<std::string> last(const char* key) const;
};

// Throws vxl::Error (Input / Unsupported) naming `path` and the byte offset where known.
MrtrixHeader parse_mrtrix_header(const std::string& path, std::span<const std::uint8_t> bytes, const char* magic);

}  // namespace vxl
