// A source read pass after pass in bounded memory (streaming_convert.h): each pass hands out the batches of
// whole streamlines of a StreamlineSource, the next batch read while the one before is processed, and counts
// what the two batches hold against the memory budget.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "converter/pipeline/conversion_plan.h"
#include "converter/pipeline/memory_budget.h"
#include "converter/pipeline/streamline_source.h"
#include "converter/tractogram.h"
#include "converter/voxelize.h"
#include "format/base/parallel.h"

namespace vxl {

class BatchReader {
 public:
  // Reads the TCK file `path` (TckBatchSource): takes the program's own memory and the read buffer from
  // `budget` (plan_reading), which must outlive the reader. With more than one thread the next batch is read
  // while one is processed.
  BatchReader(const std::string& path, MemoryBudget& budget, unsigned threads, ProgressFn progress);
  // Reads `source`, whose batches `plan` sized.
  BatchReader(std::unique_ptr<StreamlineSource> source, const ReadPlan& plan, MemoryBudget& budget, unsigned threads,
              ProgressFn progress);

  const ReadPlan& plan() const { return plan_; }
  const SourceInfo& source() const { return source_->source(); }
  unsigned passes() const { return passes_; }  // each_batch calls so far

  // Reads the source once, calling body(batch, index of its first streamline) per batch; `stage` names the
  // pass in the progress reports. Throws as the budget does when a streamline is too long to hold whole or
  // the two batches outgrow what is left.
  template <typename Body>
  void each_batch(const std::string& stage, Body&& body);

  // Notes the longest streamline of batch b (numbered from `first`), for the message of a budget exceeded
  // by the batches: pass 1 calls it for every batch.
  void note_longest(const Tractogram& b, std::uint64_t first);

 private:
  void check_overflow(const Tractogram& b, std::uint64_t first) const;
  void track_batches();
  void report(const std::string& stage, double fraction) const {
    if (progress_) progress_(stage.c_str(), fraction);
  }

  MemoryBudget& budget_;
  ReadPlan plan_;
  std::unique_ptr<StreamlineSource> source_;
  Tractogram batches_[2];                          // one processed while the next is read
  std::uint64_t held_ = 0;                         // what the two batches hold, as taken from the budget
  std::uint64_t longest_ = 0, longest_index_ = 0;  // the longest streamline noted (in points)
  bool read_ahead_ = false;
  unsigned passes_ = 0;
  ProgressFn progress_;
};

template <typename Body>
void BatchReader::each_batch(const std::string& stage, Body&& body) {
  source_->rewind();
  ++passes_;
  report(stage, 0.0);
  std::uint64_t first = 0;
  auto read = [&](int b) { return source_->next(batches_[b]); };
  int current = 0;
  bool more = read(current);
  check_overflow(batches_[current], first);
  while (more) {
    const int other = 1 - current;
    parallel_invoke(
        read_ahead_, [&] { body(static_cast<const Tractogram&>(batches_[current]), first); },
        [&] { more = read(other); });
    first += batches_[current].streamline_count();
    current = other;
    check_overflow(batches_[current], first);
    track_batches();
    report(stage, source_->progress());
  }
  report(stage, 1.0);
}

}  // namespace vxl
