// Streaming writers of MRtrix track files (Float32LE): TCK (points, RAS mm) and TSF (one value per point,
// "mrtrix track scalars"). Both end a streamline with a NaN entry and the file with an Inf one; a file
// appears at its path only after finish().
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "format/base/atomic_output.h"

namespace vxl {

// The writer of both: a header with `magic`, then records of `record_values` floats (3 for a TCK point,
// 1 for a TSF value); a record of NaNs after each streamline, one of Infs at the end.
class MrtrixTrackWriter {
 public:
  // One streamline's records, `record_values` floats each (a TCK's x,y,z interleaved).
  void add(std::span<const float> values);
  void finish();  // writes the Inf terminator and commits

 protected:
  // `count` goes into the header; `extra_header` lines ("key: value") are written as given.
  MrtrixTrackWriter(const std::string& path, const char* magic, std::size_t record_values, std::uint64_t count,
                    const std::vector<std::string>& extra_header);

 private:
  void flush();
  AtomicOutputFile out_;
  std::size_t record_values_;
  std::vector<float> buffer_;
};

class TckWriter : public MrtrixTrackWriter {
 public:
  // add(xyz): one streamline, x,y,z interleaved.
  TckWriter(const std::string& path, std::uint64_t count, const std::vector<std::string>& extra_header = {});
};

class TsfWriter : public MrtrixTrackWriter {
 public:
  // As TckWriter; add(values): one streamline's values, one per point. They must be finite: NaN and Inf
  // are the format's separators (the caller checks, before anything is written).
  TsfWriter(const std::string& path, std::uint64_t count, const std::vector<std::string>& extra_header = {});
};

}  // namespace vxl
