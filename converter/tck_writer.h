// Streaming TCK writer (Float32LE, RAS mm). The file appears at its path only after finish().
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "atomic_output.h"

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

}  // namespace vxl
