// A source read pass after pass in bounded memory (streaming_convert.h): each pass hands out the batches of
// whole streamlines of a StreamlineSource, the next batch read while the one before is processed, and counts
// what the two batches hold against the memory budget.
#pragma once

#include <cstdint>
#include <exception>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "converter/convert/voxelize.h"
#include "converter/pipeline/conversion_plan.h"
#include "converter/pipeline/memory_budget.h"
#include "converter/pipeline/streamline_source.h"
#include "converter/tractogram.h"
#include "format/base/batch_queue.h"

namespace vxl {

// What a pass does with each batch (BatchReader::each_batch): its parts, the pieces of the sink's work on the
// batch before, and the order they are handed out in (BatchQueueShape::hand_out).
struct BatchPass {
  std::uint64_t parts = 1;
  std::uint64_t sink_items = 0;
  std::span<const std::uint64_t> hand_out = {};
};

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

  // Reads the source once, batch by batch, as a queue (format/base/batch_queue.h: run_batch_queue); `stage` names
  // the pass in the progress reports. Per batch (its first streamline's index in the source is `first`, its slot
  // `slot`): prepare(batch, first, slot) on the calling thread, then part(batch, first, p, slot) for every p in
  // [0, pass.parts) on the reader's threads, beside the next batch's read and sink(item, slot of the batch before)
  // for every item in [0, pass.sink_items), then finish(batch, first, slot) on the calling thread; after the last
  // batch, its sink alone. The sink must read only what the parts of its batch made (in the slot's place), never
  // the batch, whose slot the next batch is being read into. Errors: the sink's, then the parts', then the read's,
  // the lowest item's first. Throws as the budget does when a streamline is too long to hold whole or the two
  // batches outgrow what is left.
  template <typename Prepare, typename Part, typename Sink, typename Finish>
  void each_batch(const std::string& stage, const BatchPass& pass, Prepare&& prepare, Part&& part, Sink&& sink,
                  Finish&& finish);
  // The same with the whole batch as one part and no sink: body(batch, first).
  template <typename Body>
  void each_batch(const std::string& stage, Body&& body) {
    each_batch(
        stage, BatchPass{}, [](const Tractogram&, std::uint64_t, int) {},
        [&](const Tractogram& b, std::uint64_t first, std::uint64_t, int) { body(b, first); },
        [](std::uint64_t, int) {}, [](const Tractogram&, std::uint64_t, int) {});
  }

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
  unsigned threads_ = 1;
  bool read_ahead_ = false;  // threads_ > 1
  unsigned passes_ = 0;
  ProgressFn progress_;
};

template <typename Prepare, typename Part, typename Sink, typename Finish>
void BatchReader::each_batch(const std::string& stage, const BatchPass& pass, Prepare&& prepare, Part&& part,
                             Sink&& sink, Finish&& finish) {
  source_->rewind();
  ++passes_;
  report(stage, 0.0);
  std::uint64_t first[2] = {0, 0}, read_streamlines = 0;
  const auto read = [&](int slot) {
    const bool more = source_->next(batches_[slot]);
    first[slot] = read_streamlines;
    check_overflow(batches_[slot], read_streamlines);
    read_streamlines += batches_[slot].streamline_count();
    return more;
  };
  bool started = false;
  run_batch_queue(
      threads_, {pass.parts, pass.sink_items, read_ahead_, pass.hand_out}, read,
      [&](int slot) {
        if (started) {  // both batches are in memory now: one being read while the other was processed
          track_batches();
          report(stage, source_->progress());
        }
        started = true;
        prepare(std::as_const(batches_[slot]), first[slot], slot);
      },
      [&](int slot, std::uint64_t p, unsigned) { part(std::as_const(batches_[slot]), first[slot], p, slot); },
      [&](int slot, std::uint64_t item, unsigned) { sink(item, slot); },
      [&](int slot) { finish(std::as_const(batches_[slot]), first[slot], slot); });
  report(stage, 1.0);
}

}  // namespace vxl
