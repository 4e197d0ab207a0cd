// converter/pipeline/streamline_source.h and batch_reader.h: a source hands out every streamline once per
// pass, whole and in order, whether it is a TCK read in bounded memory or streamlines in memory.
#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "converter/export/tck_writer.h"
#include "converter/pipeline/batch_reader.h"
#include "converter/pipeline/streamline_source.h"
#include "converter/readers/read_tractogram.h"
#include "converter/synth/synth.h"
#include "test_support.h"

namespace vxl {
namespace {

constexpr std::uint64_t kMebibyte = 1ull << 20;

// Every streamline of every batch of one pass, as one tractogram, and the batches' sizes.
struct Pass {
  Tractogram all;
  std::vector<std::uint64_t> batch_sizes;
};

Pass one_pass(BatchReader& reader) {
  Pass pass;
  pass.all.offsets.assign(1, 0);
  reader.each_batch("reading", [&](const Tractogram& b, std::uint64_t first) {
    EXPECT_EQ(first, pass.all.streamline_count()) << "batches out of order";
    for (std::uint64_t k = 0; k < b.streamline_count(); ++k)
      pass.all.add_streamline(b.positions.data() + 3 * b.offsets[k], b.offsets[k + 1] - b.offsets[k]);
    pass.batch_sizes.push_back(b.streamline_count());
  });
  return pass;
}

TEST(StreamlineSource, ATractogramIsHandedOutInBatchesOfWholeStreamlinesThenEnds) {
  const Tractogram t = synthesize_tractogram({1000, 3, 1});
  TractogramBatchSource source(t, 300);
  Tractogram batch;
  std::vector<std::uint64_t> sizes;
  std::uint64_t first = 0;
  while (source.next(batch)) {
    sizes.push_back(batch.streamline_count());
    // As a TCK's batches: up to the first streamline that brings the points and streamlines to 300.
    const std::uint64_t n = batch.streamline_count();
    if (first + n < t.streamline_count()) {
      EXPECT_GE(batch.point_count() + n, 300u);
    }
    EXPECT_LT(batch.offsets[n - 1] + (n - 1), 300u) << "a batch goes no further than the streamline that fills it";
    ASSERT_EQ(batch.offsets.front(), 0u);
    for (std::uint64_t k = 0; k < batch.streamline_count(); ++k) {
      const std::uint64_t n = batch.offsets[k + 1] - batch.offsets[k];
      ASSERT_EQ(n, t.offsets[first + k + 1] - t.offsets[first + k]) << "streamline " << first + k;
      ASSERT_TRUE(std::equal(batch.positions.begin() + std::ptrdiff_t(3 * batch.offsets[k]),
                             batch.positions.begin() + std::ptrdiff_t(3 * batch.offsets[k + 1]),
                             t.positions.begin() + std::ptrdiff_t(3 * t.offsets[first + k])));
    }
    first += batch.streamline_count();
  }
  EXPECT_EQ(first, t.streamline_count());
  EXPECT_GT(sizes.size(), 3u);
  EXPECT_EQ(batch.streamline_count(), 0u) << "the batch after the last is empty";
  EXPECT_DOUBLE_EQ(source.progress(), 1.0);
  source.rewind();
  EXPECT_DOUBLE_EQ(source.progress(), 0.0);
  ASSERT_TRUE(source.next(batch));
  EXPECT_EQ(batch.streamline_count(), sizes.front()) << "a rewound source starts again at the first streamline";
}

TEST(StreamlineSource, ATckAndTheSameStreamlinesInMemoryReadAlikePassAfterPass) {
  test::ScratchDir dir;
  const std::string tck = dir.file("source.tck");
  {
    const Tractogram t = synthesize_tractogram({5000, 2, 1});
    TckWriter w(tck, t.streamline_count());
    for (std::uint64_t i = 0; i < t.streamline_count(); ++i)
      w.add({t.positions.data() + 3 * t.offsets[i], 3 * (t.offsets[i + 1] - t.offsets[i])});
    w.finish();
  }
  MemoryBudget budget(64 * kMebibyte, tck);
  BatchReader from_file(tck, budget, 2, {});
  const Tractogram in_memory = read_tck(tck);
  MemoryBudget other(64 * kMebibyte, tck);
  BatchReader from_memory(std::make_unique<TractogramBatchSource>(in_memory, 700), plan_reading(other), other, 2, {});
  for (int pass = 0; pass < 2; ++pass) {
    const Pass a = one_pass(from_file), b = one_pass(from_memory);
    EXPECT_EQ(a.all.offsets, in_memory.offsets) << "pass " << pass;
    EXPECT_EQ(a.all.positions, in_memory.positions) << "pass " << pass;
    EXPECT_EQ(b.all.offsets, in_memory.offsets) << "pass " << pass;
    EXPECT_EQ(b.all.positions, in_memory.positions) << "pass " << pass;
    EXPECT_GT(b.batch_sizes.size(), 5u) << "700 points and streamlines a batch";
  }
  EXPECT_EQ(from_file.passes(), 2u);
  EXPECT_EQ(from_file.source().xxh3_128, in_memory.source.xxh3_128);
  EXPECT_GT(budget.used(), 16 * kMebibyte) << "the batches are counted against the budget";
}

}  // namespace
}  // namespace vxl
