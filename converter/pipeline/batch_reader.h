// A source read pass after pass in bounded memory (streaming_convert.h): each pass hands out the batches of
// whole streamlines of a StreamlineSource, the next batch read while the one before is processed, and counts
// what the two batches hold against the memory budget.
#pragma once

#include <cstdint>
#include <exception>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "converter/convert/voxelize.h"
#include "converter/pipeline/conversion_plan.h"
#include "converter/pipeline/memory_budget.h"
#include "converter/pipeline/streamline_source.h"
#include "converter/tractogram.h"
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

  // Reads the source once, batch by batch; `stage` names the pass in the progress reports. Per batch (its
  // first streamline's index in the source is `first`): prepare(batch, first) on the calling thread, then
  // part(batch, first, p) for every p in [0, parts) on the reader's threads while the next batch is read
  // beside them, then finish(batch, first) on the calling thread (with one thread, the read comes after
  // finish). The read is one more item for the same threads, not a thread of its own: the parts fill the
  // cores around it, so that cutting a batch in a few parts keeps every core busy even when the read and
  // the parts take unequal times. An error of a part comes before one of the read (which is further on in
  // the file), the lowest part's first. Throws as the budget does when a streamline is too long to hold
  // whole or the two batches outgrow what is left. With `hand_out` (a permutation of [0, parts)), the parts
  // are handed out in that order after the read — the longest first, so that the threads finish together —
  // their errors still lowest part first.
  template <typename Prepare, typename Part, typename Finish>
  void each_batch(const std::string& stage, std::uint64_t parts, Prepare&& prepare, Part&& part, Finish&& finish,
                  std::span<const std::uint64_t> hand_out = {});
  // The same with the whole batch as one part: body(batch, first).
  template <typename Body>
  void each_batch(const std::string& stage, Body&& body) {
    const auto none = [](const Tractogram&, std::uint64_t) {};
    each_batch(
        stage, 1, none, [&](const Tractogram& b, std::uint64_t first, std::uint64_t) { body(b, first); }, none);
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

template <typename Prepare, typename Part, typename Finish>
void BatchReader::each_batch(const std::string& stage, std::uint64_t parts, Prepare&& prepare, Part&& part,
                             Finish&& finish, std::span<const std::uint64_t> hand_out) {
  // The items: the read (when it comes beside the parts), then the parts, in hand_out's order if given.
  const std::uint64_t read_items = read_ahead_ ? 1 : 0;
  std::vector<std::uint64_t> items;
  if (!hand_out.empty()) {
    if (read_ahead_) items.push_back(0);
    for (const std::uint64_t p : hand_out) items.push_back(p + read_items);
  }
  source_->rewind();
  ++passes_;
  report(stage, 0.0);
  std::uint64_t first = 0;
  int current = 0;
  bool more = source_->next(batches_[current]);
  check_overflow(batches_[current], first);
  while (more) {
    const int other = 1 - current;
    const Tractogram& batch = batches_[current];
    prepare(batch, first);
    std::exception_ptr read_error;
    const auto read_next = [&] {
      try {
        more = source_->next(batches_[other]);
      } catch (...) {
        read_error = std::current_exception();
      }
    };
    // Item 0, handed out first, reads the next batch; items 1.. are the parts.
    parallel_for_first_error_in_order(
        parts + read_items, threads_,
        [&](std::uint64_t item, unsigned) {
          if (read_ahead_ && item == 0) return read_next();
          part(batch, first, item - read_items);
        },
        items);
    finish(batch, first);
    if (!read_ahead_) read_next();
    if (read_error) std::rethrow_exception(read_error);
    first += batch.streamline_count();
    current = other;
    check_overflow(batches_[current], first);
    track_batches();
    report(stage, source_->progress());
  }
  report(stage, 1.0);
}

}  // namespace vxl
