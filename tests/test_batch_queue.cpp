// format/base/batch_queue.h: a pass as a queue — every batch's parts run, the sink takes each batch once, in
// order and one batch behind (the last one alone), the slots alternate, and errors come in the queue's order.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include "format/base/batch_queue.h"

namespace vxl {
namespace {

// A source of `batches` numbered batches, each read into a slot; parts record their batch into the slot's
// results, the sink reads those back.
struct NumberedBatches {
  int batches = 0;
  int read = 0;
  std::array<int, 2> batch_in_slot{-1, -1};
  std::array<std::vector<int>, 2> made;  // per slot: the batch each part saw
  std::vector<std::string> log;          // calling-thread events and the sink's, in order
  std::mutex m;
  bool next(int slot) {
    if (read == batches) return false;
    batch_in_slot[slot] = read++;
    return true;
  }
};

void run(NumberedBatches& q, unsigned threads, bool read_ahead, std::uint64_t parts, std::uint64_t sink_items,
         std::span<const std::uint64_t> hand_out = {}) {
  run_batch_queue(
      threads, {parts, sink_items, read_ahead, hand_out}, [&](int slot) { return q.next(slot); },
      [&](int slot) {
        q.made[slot].assign(parts, -1);
        q.log.push_back("prepare " + std::to_string(q.batch_in_slot[slot]));
      },
      [&](int slot, std::uint64_t p, unsigned) { q.made[slot][p] = q.batch_in_slot[slot]; },
      [&](int slot, std::uint64_t item, unsigned) {
        const std::lock_guard<std::mutex> lock(q.m);
        for (const int batch : q.made[slot])
          q.log.push_back("sink " + std::to_string(item) + " of " + std::to_string(batch));
      },
      [&](int slot) { q.log.push_back("finish " + std::to_string(q.batch_in_slot[slot])); });
}

TEST(BatchQueue, TheSinkTakesEachBatchOnceInOrderOneBehind) {
  for (const unsigned threads : {1u, 2u, 4u})
    for (const bool read_ahead : {true, false}) {
      SCOPED_TRACE(std::to_string(threads) + " threads, read ahead " + std::to_string(read_ahead));
      NumberedBatches q;
      q.batches = 4;
      run(q, threads, read_ahead, 2, 1);
      const std::vector<std::string> expected = {
          "prepare 0", "finish 0",                                // no batch before the first
          "prepare 1", "sink 0 of 0", "sink 0 of 0", "finish 1",  // batch 0's two parts, beside batch 1
          "prepare 2", "sink 0 of 1", "sink 0 of 1", "finish 2",  //
          "prepare 3", "sink 0 of 2", "sink 0 of 2", "finish 3", "sink 0 of 3", "sink 0 of 3"};  // the last alone
      EXPECT_EQ(q.log, expected);
      EXPECT_EQ(q.read, 4);
    }
}

TEST(BatchQueue, NoBatchesRunNothingAndNoSinkRunsNoSink) {
  NumberedBatches none;
  run(none, 2, true, 3, 2);
  EXPECT_TRUE(none.log.empty());
  NumberedBatches q;
  q.batches = 2;
  run(q, 2, true, 3, 0);
  EXPECT_EQ(q.log, (std::vector<std::string>{"prepare 0", "finish 0", "prepare 1", "finish 1"}));
}

TEST(BatchQueue, AHandOutOrderMustCoverTheSinkItemsAndTheParts) {
  NumberedBatches q;
  q.batches = 3;
  const std::array<std::uint64_t, 4> parts_first = {2, 3, 0, 1};
  run(q, 2, true, 2, 2, parts_first);
  EXPECT_EQ(q.log.back(), "sink 1 of 2");  // the last batch's sink, after every round
  const std::array<std::uint64_t, 3> short_order = {0, 1, 2};
  NumberedBatches r;
  r.batches = 1;
  EXPECT_THROW(run(r, 2, true, 2, 2, short_order), std::logic_error);
}

// The sink's error (the earlier batch) comes before the parts', the parts' before the read's, whatever the timing;
// a round that threw ends the pass.
TEST(BatchQueue, ErrorsComeInTheQueuesOrder) {
  for (int repeat = 0; repeat < 20; ++repeat) {
    int rounds = 0, finished = 0;
    // Three batches; in round 2 (batch 1's parts, batch 0's sink, batch 2's read) each may throw.
    const auto attempt = [&](bool sink_throws, bool part_throws, bool read_throws) {
      int reads = 0;
      rounds = finished = 0;
      try {
        run_batch_queue(
            2, {2, 1, true, {}},
            [&](int) {
              ++reads;
              if (reads == 3 && read_throws) throw std::runtime_error("read");
              return reads <= 3;
            },
            [&](int) { ++rounds; },
            [&](int, std::uint64_t p, unsigned) {
              if (rounds == 2 && p == 1 && part_throws) throw std::runtime_error("part");
            },
            [&](int, std::uint64_t, unsigned) {
              if (sink_throws) throw std::runtime_error("sink");
            },
            [&](int) { ++finished; });
      } catch (const std::runtime_error& e) {
        return std::string(e.what());
      }
      return std::string();
    };
    EXPECT_EQ(attempt(true, true, true), "sink");
    EXPECT_EQ(finished, 1) << "a round that threw ends the pass";
    EXPECT_EQ(attempt(false, true, true), "part");
    EXPECT_EQ(attempt(false, false, true), "read");
    EXPECT_EQ(finished, 2) << "a read's error comes after its round has finished";
    EXPECT_EQ(attempt(false, false, false), "");
    EXPECT_EQ(finished, 3);
  }
}

}  // namespace
}  // namespace vxl
