// Streaming writers of MRtrix track files (Float32LE): TCK (points, RAS mm) and TSF (one value per point,
// "mrtrix track scalars"). Both end a streamline with a NaN entry and the file with an Inf one; a file
// appears at its path only after finish().
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "format/atomic_output.h"

namespace vxl {

class TckWriter {
 public:
  // `count` goes into the header; `extra_header` lines ("key: value") are written as given.
  TckWriter(const std::string& path, std::uint64_t count, const std::vector<std::string>& extra_header = {});
  void add(std::span<const float> xyz);  // one streamline, x,y,z interleaved
  void finish();                         // writes the Inf terminator and commits

 private:
  void flush();
  AtomicOutputFile out_;
  std::vector<float> buffer_;
};

class TsfWriter {
 public:
  // As TckWriter. The values of a streamline must be finite: NaN and Inf are the format's separators
  // (the caller checks, before anything is written).
  TsfWriter(const std::string& path, std::uint64_t count, const std::vector<std::string>& extra_header = {});
  void add(std::span<const float> values);  // one streamline's values, one per point
  void finish();

 private:
  void flush();
  AtomicOutputFile out_;
  std::vector<float> buffer_;
};

}  // namespace vxl
