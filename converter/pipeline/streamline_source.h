// The streamlines a conversion reads, a batch of whole streamlines at a time and as many passes as it needs:
// the input interface of the batch stages (BatchReader). A TCK file read in bounded memory (TckBatchSource), or
// streamlines already in memory (TractogramBatchSource).
#pragma once

#include <cstdint>
#include <string>

#include "converter/pipeline/conversion_plan.h"
#include "converter/readers/tck_stream.h"
#include "converter/tractogram.h"

namespace vxl {

class StreamlineSource {
 public:
  virtual ~StreamlineSource() = default;
  // What the output's provenance records of the source (for a TCK, complete once a first pass has ended).
  virtual const SourceInfo& source() const = 0;
  // How far the pass has come, in [0, 1].
  virtual double progress() const = 0;
  // Starts a pass at the first streamline.
  virtual void rewind() = 0;
  // Replaces batch.positions and batch.offsets with the next whole streamlines (at least one). Returns false,
  // with no streamline in `batch`, at the end of the pass, or with overflowed() set when a streamline is too
  // long to hold whole.
  virtual bool next(Tractogram& batch) = 0;
  virtual bool overflowed() const { return false; }
};

// A TCK file, a part at a time read into one buffer (TckStream), in batches sized by `plan` (plan_reading).
class TckBatchSource final : public StreamlineSource {
 public:
  TckBatchSource(const std::string& path, const ReadPlan& plan)
      : stream_(path, plan.max_header_bytes, plan.read_buffer_bytes),
        batch_points_(plan.batch_points),
        max_points_held_(plan.max_points_held) {}
  const SourceInfo& source() const override { return stream_.source(); }
  double progress() const override {
    return double(stream_.position()) / double(std::max<std::uint64_t>(1, stream_.file_size()));
  }
  void rewind() override { stream_.rewind(); }
  bool next(Tractogram& batch) override { return stream_.next(batch, batch_points_, max_points_held_); }
  bool overflowed() const override { return stream_.overflowed(); }

 private:
  TckStream stream_;
  std::uint64_t batch_points_, max_points_held_;
};

// Streamlines in memory (`tractogram`, which must outlive the source), in batches cut as a TCK's are (up to the
// first streamline that brings the batch's points and streamlines to `batch_points`); each batch is a copy of its
// streamlines' points.
class TractogramBatchSource final : public StreamlineSource {
 public:
  TractogramBatchSource(const Tractogram& tractogram, std::uint64_t batch_points)
      : tractogram_(tractogram), batch_points_(std::max<std::uint64_t>(1, batch_points)) {}
  const SourceInfo& source() const override { return tractogram_.source; }
  double progress() const override {
    return double(next_) / double(std::max<std::uint64_t>(1, tractogram_.streamline_count()));
  }
  void rewind() override { next_ = 0; }
  bool next(Tractogram& batch) override;

 private:
  const Tractogram& tractogram_;
  std::uint64_t batch_points_;
  std::uint64_t next_ = 0;  // the next streamline to hand out
};

}  // namespace vxl
