// TSF reader (MRtrix track scalar file): per-point values of a tractogram kept in a separate file.
//
// Layout: the MRtrix text header ("mrtrix track scalars", key: value lines, END; mrtrix_header.h), then from
// "file: . OFFSET" one value per streamline point in the "datatype" (Float32/64, LE/BE); a NaN ends a
// streamline, an Inf ends the file (a missing Inf at end of file is tolerated, as for TCK). The file has no
// positions: it belongs to the tractogram it was made for, point by point, which attach_tsf checks.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "converter/tractogram.h"

namespace vxl {

struct TrackScalars {
  std::vector<float> values;             // all values, streamline after streamline
  std::vector<std::uint64_t> offsets;    // streamline i = values [offsets[i], offsets[i+1]); size N+1
  std::optional<std::string> timestamp;  // the header's, which MRtrix copies from the tractogram
  std::vector<std::string> warnings;
  nlohmann::json provenance;  // {"name", "bytes", "xxh3_128", "header"}
};

// Throws vxl::Error (Input, Unsupported) naming the file and the byte offset where known.
TrackScalars read_tsf(const std::string& path);

// Adds the values of the TSF at `tsf_path` to `t` as a per-point value set named after the file (its stem).
// Refuses, with an Input error naming the TSF, a file whose streamline count or any streamline's point
// count differs from the tractogram's; warns (in t.source.warnings) when the timestamps differ.
void attach_tsf(Tractogram& t, const std::string& tsf_path);

}  // namespace vxl
