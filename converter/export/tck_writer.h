// Streaming writers of MRtrix track files (Float32LE): TCK (points, RAS mm) and TSF (one value per point,
// "mrtrix track scalars"). Both end a streamline with a NaN entry and the file with an Inf one; a file
// appears at its path only after finish(). Given the number of records up front (the file's size is then
// known), the file is written past the page cache (DirectRegionWriter) on a thread of its own
// (DirectWriteQueue): a large export or selection then neither fills the page cache nor pays for its fresh
// pages, and goes on reading streamlines while its last part is written.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <memory>
#include <optional>

#include "format/base/atomic_output.h"
#include "format/base/direct_region_writer.h"
#include "format/base/direct_write_queue.h"

namespace vxl {

// The writer of both: a header with `magic`, then records of `record_values` floats (3 for a TCK point,
// 1 for a TSF value); a record of NaNs after each streamline, one of Infs at the end.
class MrtrixTrackWriter {
 public:
  // One streamline's records, `record_values` floats each (a TCK's x,y,z interleaved).
  void add(std::span<const float> values);
  void finish();  // writes the Inf terminator and commits

 protected:
  // `count` goes into the header; `extra_header` lines ("key: value") are written as given; `records`: the
  // records add() will be given in all (a TCK's points), when known (std::logic_error at finish() when they
  // were not exactly these).
  MrtrixTrackWriter(const std::string& path, const char* magic, std::size_t record_values, std::uint64_t count,
                    const std::vector<std::string>& extra_header, std::optional<std::uint64_t> records);

 private:
  void flush();
  AtomicOutputFile out_;
  std::size_t record_values_;
  std::vector<float> buffer_;
  // With `records` known: the stagings (the writer's and the queue's spares), the queue, the whole file's writer.
  std::unique_ptr<std::uint8_t, void (*)(void*)> stagings_{nullptr, nullptr};
  std::unique_ptr<DirectWriteQueue> queue_;
  std::unique_ptr<DirectRegionWriter> direct_;
};

class TckWriter : public MrtrixTrackWriter {
 public:
  // add(xyz): one streamline, x,y,z interleaved. `points`: the points of all `count` streamlines, when known.
  TckWriter(const std::string& path, std::uint64_t count, const std::vector<std::string>& extra_header = {},
            std::optional<std::uint64_t> points = std::nullopt);
};

class TsfWriter : public MrtrixTrackWriter {
 public:
  // As TckWriter; add(values): one streamline's values, one per point. They must be finite: NaN and Inf
  // are the format's separators (the caller checks, before anything is written).
  TsfWriter(const std::string& path, std::uint64_t count, const std::vector<std::string>& extra_header = {},
            std::optional<std::uint64_t> points = std::nullopt);
};

}  // namespace vxl
