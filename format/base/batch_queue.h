// The project's one way to run a pass over a source of batches, as MRtrix's Thread::run_queue does: a source that
// gives batches one after another, workers that work on a batch's parts side by side, and an ordered sink that
// takes in what the parts made, batch after batch. The three overlap: while the workers work on batch k, the
// source reads batch k + 1 and the sink takes batch k - 1 (on the same threads, handed out as they come free: a
// pass whose parts and read take unequal times keeps every core busy).
//
// Each batch has a slot, 0 or 1 alternating, for the batch itself and for what its parts make: the sink reads
// slot s one batch after the parts wrote it, while the source reads the next batch into that same slot — so the
// sink must read only what the parts made, never the batch. Threads start in parallel.h's functions only.
#pragma once

#include <cstdint>
#include <exception>
#include <span>
#include <stdexcept>
#include <vector>

#include "format/base/parallel.h"

namespace vxl {

struct BatchQueueShape {
  std::uint64_t parts = 1;       // parts of each batch, worked on side by side
  std::uint64_t sink_items = 0;  // pieces of the sink's work on a batch, side by side (0: no sink)
  // Whether the next batch is read beside the current one's parts (else after them: one thread).
  bool read_ahead = true;
  // The order the sink items and the parts are handed out in, after the read: a permutation of
  // [0, sink_items + parts), sink items first (i < sink_items), then part i - sink_items. Empty: that order.
  // The longest first, so that the threads finish a round together.
  std::span<const std::uint64_t> hand_out;
};

// Runs the queue on `threads` threads (resolve_threads), a round per batch:
//
//   read(slot) -> bool          reads the next batch into `slot`; false when there is none (the pass ends)
//   prepare(slot)               on the calling thread, before the batch's parts
//   part(slot, p, thread)       for every p in [0, shape.parts)
//   sink(slot, item, thread)    for every item in [0, shape.sink_items), on the batch before, in batch order;
//                               after the last batch, on it alone
//   finish(slot)                on the calling thread, after the batch's parts (and the sink of the one before)
//
// Errors, whatever the timing: the sink's (the earlier batch) before the parts', the parts' before the read's (it is
// further on in the source), the lowest item's first within each; a round that threw ends the pass.
template <typename Read, typename Prepare, typename Part, typename Sink, typename Finish>
void run_batch_queue(unsigned threads, const BatchQueueShape& shape, Read&& read, Prepare&& prepare, Part&& part,
                     Sink&& sink, Finish&& finish) {
  const std::uint64_t work = shape.sink_items + shape.parts;
  if (!shape.hand_out.empty() && shape.hand_out.size() != work)
    throw std::logic_error("run_batch_queue: the hand-out order is not of the sink items and parts");
  // A round's items: the sink items, the parts, and (beside them) the read, item `work`, handed out first. The
  // read keeps its error until the round has finished: the items' come first, lowest first.
  const std::uint64_t read_item = work, items = work + (shape.read_ahead ? 1 : 0);
  std::vector<std::uint64_t> order;
  if (!shape.hand_out.empty() || shape.read_ahead) {
    if (shape.read_ahead) order.push_back(read_item);
    for (std::uint64_t k = 0; k < work; ++k) order.push_back(shape.hand_out.empty() ? k : shape.hand_out[k]);
  }
  int slot = 0;
  bool more = read(slot);
  bool behind = false;  // the batch before waits for the sink
  while (more) {
    const int next = 1 - slot;
    prepare(slot);
    std::exception_ptr read_error;
    const auto read_next = [&] {
      try {
        more = read(next);
      } catch (...) {
        read_error = std::current_exception();
      }
    };
    parallel_for_first_error_in_order(
        items, threads,
        [&](std::uint64_t i, unsigned t) {
          if (i == read_item) {
            read_next();
          } else if (i >= shape.sink_items) {
            part(slot, i - shape.sink_items, t);
          } else if (behind) {
            sink(next, i, t);
          }
        },
        order);
    finish(slot);
    if (!shape.read_ahead) read_next();
    if (read_error) std::rethrow_exception(read_error);
    behind = shape.sink_items > 0;
    slot = next;
  }
  if (behind)
    parallel_for_first_error_in_order(shape.sink_items, threads,
                                      [&](std::uint64_t i, unsigned t) { sink(1 - slot, i, t); });
}

}  // namespace vxl
