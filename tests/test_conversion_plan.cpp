// converter/pipeline/conversion_plan.h: the split of a conversion within a memory limit, worked out from
// counts alone. The ranges must cover the voxel table in order and fit in what the limit leaves, and a
// limit too small for a part must be refused naming that part.
#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <string>
#include <vector>

#include "converter/convert/segment_orders.h"
#include "converter/pipeline/conversion_plan.h"
#include "format/base/error.h"

namespace vxl {
namespace {

constexpr std::uint64_t kMiB = 1ull << 20;

// A voxel table of voxels with these vertex counts (one level, six orders), laid out as the converter
// lays it out.
struct Table {
  MetaSection meta{};
  std::vector<VoxelEntry> voxels;
  std::uint64_t order_bytes = 0;
  explicit Table(const std::vector<std::uint32_t>& vertex_counts) {
    std::uint64_t first = 0;
    for (std::size_t i = 0; i < vertex_counts.size(); ++i) {
      VoxelEntry v{};
      v.coord[0] = static_cast<std::int32_t>(i);
      v.vertex_first = first;
      v.vertex_count = vertex_counts[i];
      v.segment_count = vertex_counts[i] > 0 ? vertex_counts[i] - 1 : 0;
      first += vertex_counts[i];
      voxels.push_back(v);
    }
    order_bytes = layout_orders(voxels, {}, 1, 6);
    meta.streamline_count = first > 0 ? 1000 : 0;
    meta.point_count = first;
    meta.voxline_count = first > 0 ? 2000 : 0;
    meta.vertex_count = first;
  }
  ConversionCounts counts(PositionEncoding positions = PositionEncoding::Packed, unsigned threads = 4,
                          std::uint64_t order_chunk_request = 0) const {
    return {meta, voxels, {}, 1, positions, order_bytes, threads, 1024, order_chunk_request};
  }
};

// The ranges cover voxels [0, n) in order, without gaps, and agree with the table's vertices.
void expect_ranges_cover(const std::vector<VoxelRange>& ranges, const Table& t) {
  ASSERT_FALSE(ranges.empty());
  std::size_t next = 0;
  for (const VoxelRange& r : ranges) {
    EXPECT_EQ(r.first, next);
    ASSERT_GT(r.end, r.first);
    EXPECT_EQ(r.vertex_first, t.voxels[r.first].vertex_first);
    EXPECT_EQ(r.vertex_end, t.voxels[r.end - 1].vertex_first + t.voxels[r.end - 1].vertex_count);
    std::uint32_t most = 0;
    for (std::size_t i = r.first; i < r.end; ++i) most = std::max(most, t.voxels[i].vertex_count);
    EXPECT_EQ(r.max_vertices, most);
    EXPECT_GE(r.order_threads, 1u);
    next = r.end;
  }
  EXPECT_EQ(next, t.voxels.size());
}

TEST(ConversionPlan, ReadingTakesTheProgramAndTheReadBufferAndSizesTheBatches) {
  for (std::uint64_t limit : {64 * kMiB, 512 * kMiB, 8192 * kMiB}) {
    MemoryBudget budget(limit, "source.tck");
    const ReadPlan plan = plan_reading(budget);
    EXPECT_GE(plan.read_buffer_bytes, 64u << 10);
    EXPECT_LE(plan.read_buffer_bytes, 4 * kMiB);
    EXPECT_EQ(budget.used(), 16 * kMiB + plan.read_buffer_bytes);
    EXPECT_GE(plan.batch_points, 1024u);
    EXPECT_LE(plan.batch_points, 1u << 20);
    EXPECT_EQ(plan.max_header_bytes, budget.left() / 4);
    EXPECT_EQ(plan.max_points_held, budget.left() / kHeldBytesPerPoint);
  }
  MemoryBudget larger(512 * kMiB, "source.tck"), smaller(64 * kMiB, "source.tck");
  EXPECT_GT(plan_reading(larger).batch_points, plan_reading(smaller).batch_points);
}

TEST(ConversionPlan, ALimitBelowTheProgramItselfIsRefusedWithASuggestion) {
  MemoryBudget budget(8 * kMiB, "source.tck");
  try {
    plan_reading(budget);
    FAIL() << "8 MiB accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Unsupported);
    const std::string what = e.what();
    EXPECT_NE(what.find("source.tck"), std::string::npos) << what;
    EXPECT_NE(what.find("the program itself needs 16.0 MiB"), std::string::npos) << what;
    EXPECT_NE(what.find("use --memory-limit 20M or more"), std::string::npos) << what;
  }
}

TEST(ConversionPlan, AmpleMemoryBuildsEveryVoxelInOneRange) {
  const Table t(std::vector<std::uint32_t>(500, 1000));
  MemoryBudget budget(200 * kMiB, "source.tck");
  const ConversionPlan plan = plan_conversion(budget, t.counts());
  ASSERT_EQ(plan.ranges.size(), 1u);
  expect_ranges_cover(plan.ranges, t);
  EXPECT_EQ(plan.direct_staging_bytes, 0u) << "direct writes start at 256 MiB";
  EXPECT_EQ(plan.block_staging_bytes, 0u);
  EXPECT_LE(budget.used(), budget.limit());
  EXPECT_GT(plan.staged_bytes, 0u);
}

TEST(ConversionPlan, LittleMemoryCutsSeveralRangesThatEachFit) {
  const Table t(std::vector<std::uint32_t>(2000, 3000));  // 6M vertices: 24 MB packed
  MemoryBudget budget(12 * kMiB, "source.tck");
  const ConversionPlan plan = plan_conversion(budget, t.counts());
  EXPECT_GT(plan.ranges.size(), 2u);
  expect_ranges_cover(plan.ranges, t);
  // Each range's vertices fit in the limit (with room for its sort buffers).
  for (const VoxelRange& r : plan.ranges) EXPECT_LT((r.vertex_end - r.vertex_first) * 4, budget.limit());
  // Float32 positions take three times the bytes: more ranges.
  MemoryBudget same(12 * kMiB, "source.tck");
  const ConversionPlan float32 = plan_conversion(same, t.counts(PositionEncoding::Float32));
  expect_ranges_cover(float32.ranges, t);
  EXPECT_GT(float32.ranges.size(), plan.ranges.size());
}

TEST(ConversionPlan, AVoxelTooLargeForWhatIsLeftIsNamed) {
  Table t({100, 200, 3'000'000, 100});
  t.voxels[2].coord[1] = 7;
  t.voxels[2].coord[2] = 9;
  // Room for its orders (a chunk holds at least one voxel's), not for its vertices and sort buffers.
  MemoryBudget budget(100 * kMiB, "source.tck");
  try {
    plan_conversion(budget, t.counts(PositionEncoding::Packed, 1));
    FAIL() << "a voxel of 3M vertices fit in 100 MiB";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Unsupported);
    const std::string what = e.what();
    EXPECT_NE(what.find("voxel (2, 7, 9) of 3000000 vertices, with its sort buffers,"), std::string::npos) << what;
    EXPECT_NE(what.find("or a smaller --voxel-size"), std::string::npos) << what;
  }
}

TEST(ConversionPlan, LargeLimitsWriteDirectlyAndVertexBlocksAreReadBack) {
  const Table t(std::vector<std::uint32_t>(300, 500'000));  // VERT: 600 MB, more than the limit
  MemoryBudget budget(512 * kMiB, "source.tck");
  const ConversionPlan plan = plan_conversion(budget, t.counts());
  EXPECT_GT(plan.direct_staging_bytes, 0u);
  ASSERT_GT(plan.block_staging_bytes, 0u);
  EXPECT_GE(plan.pool_bytes, block_staging_total(t.counts(), plan.block_staging_bytes));
  EXPECT_GE(plan.pool_bytes, 2 * (plan.pool_chunk_bytes + plan.pool_read_back_bytes));
  EXPECT_GE(plan.pool_chunk_bytes, plan.order_chunk_bytes);
  EXPECT_EQ(plan.ranges.size(), 1u);
  EXPECT_LE(budget.used(), budget.limit());
}

// Holding VERT whole costs less than writing its blocks and reading them back: where it fits in one range, it is
// held, unless the blocks are asked for.
TEST(ConversionPlan, VerticesThatFitAreHeldWholeUnlessTheBlocksAreAskedFor) {
  const Table t(std::vector<std::uint32_t>(300, 5000));  // VERT: 6 MB
  MemoryBudget budget(512 * kMiB, "source.tck");
  const ConversionPlan plan = plan_conversion(budget, t.counts());
  EXPECT_GT(plan.direct_staging_bytes, 0u);
  EXPECT_EQ(plan.block_staging_bytes, 0u);
  EXPECT_EQ(plan.ranges.size(), 1u);
  ConversionCounts asked = t.counts();
  asked.vertex_blocks_request = true;
  MemoryBudget again(512 * kMiB, "source.tck");
  EXPECT_GT(plan_conversion(again, asked).block_staging_bytes, 0u);
}

TEST(ConversionPlan, TheOrderChunkFollowsTheRequestButHoldsTheLargestVoxel) {
  const Table t({10, 20000, 10, 10});
  const std::uint64_t largest = t.voxels[2].order_offset - t.voxels[1].order_offset;
  MemoryBudget a(200 * kMiB, "source.tck");
  EXPECT_EQ(plan_conversion(a, t.counts(PositionEncoding::Packed, 4, 1)).order_chunk_bytes, largest);
  MemoryBudget b(200 * kMiB, "source.tck");
  EXPECT_EQ(plan_conversion(b, t.counts(PositionEncoding::Packed, 4, 4 * kMiB)).order_chunk_bytes, t.order_bytes)
      << "never more than the whole ORDB payload";
}

// Unasked, a chunk holds two of the largest voxels' orders per ordering thread (so that no thread waits long at a
// chunk's end), within 16 MiB and 256 MiB: larger chunks cost memory twice over and gain nothing.
TEST(ConversionPlan, TheOrderChunkHoldsTwoLargestVoxelsPerThreadWithinItsBounds) {
  const Table t(std::vector<std::uint32_t>(200, 200'000));  // each voxel's orders: a few MB; ORDB: hundreds
  const std::uint64_t largest = t.voxels[1].order_offset - t.voxels[0].order_offset;
  ASSERT_GT(t.order_bytes, 256 * kMiB);
  ASSERT_LT(2 * largest, 16 * kMiB);
  ASSERT_GT(2 * 8 * largest, 16 * kMiB);
  ASSERT_LT(2 * 8 * largest, 256 * kMiB);
  for (unsigned threads : {1u, 8u, 256u}) {
    MemoryBudget budget(64ull << 30, "source.tck");
    const std::uint64_t expected = std::clamp<std::uint64_t>(2 * threads * largest, 16 * kMiB, 256 * kMiB);
    EXPECT_EQ(plan_conversion(budget, t.counts(PositionEncoding::Packed, threads)).order_chunk_bytes, expected)
        << threads << " threads";
  }
}

TEST(ConversionPlan, NoVoxelsMakeOneEmptyRangeThatWritesTheTables) {
  const Table t(std::vector<std::uint32_t>{});
  MemoryBudget budget(64 * kMiB, "source.tck");
  const ConversionPlan plan = plan_conversion(budget, t.counts());
  ASSERT_EQ(plan.ranges.size(), 1u);
  EXPECT_EQ(plan.ranges[0].first, plan.ranges[0].end);
}

TEST(ConversionPlan, TheVoxelIndexIsSortedInOnePassWhenItsListsFit) {
  const Table t(std::vector<std::uint32_t>(300, 5000));
  for (std::uint64_t limit : {200 * kMiB, 512 * kMiB}) {  // written through the page cache, and block by block
    MemoryBudget budget(limit, "source.tck");
    const ConversionPlan plan = plan_conversion(budget, t.counts());
    EXPECT_EQ(plan.voxel_index_buffer_bytes, t.meta.voxline_count * 4) << limit;
  }
}

TEST(ConversionPlan, TheVoxelIndexBufferIsWhatTheWriteStageLeaves) {
  Table t(std::vector<std::uint32_t>(1000, 40'000));
  t.meta.voxline_count = 10'000'000;  // lists of 40 MB
  const MemoryBudget budget(1024 * kMiB, "source.tck");
  const std::uint64_t lists = t.meta.voxline_count * 4, largest = 40'000 * 4;
  const std::uint64_t small = plan_voxel_index(budget, 12 * kMiB, t.counts());
  EXPECT_GE(small, largest);
  EXPECT_LT(small, 12 * kMiB) << "beside the list starts and the tables' parts";
  const std::uint64_t larger = plan_voxel_index(budget, 32 * kMiB, t.counts());
  EXPECT_GT(larger, small);
  EXPECT_LT(larger, lists);
  EXPECT_EQ(plan_voxel_index(budget, 100 * kMiB, t.counts()), lists);
  // A room for the largest list but not for the tables' parts beside it: the largest list alone.
  EXPECT_EQ(plan_voxel_index(budget, largest + 8 * 1001 + 1000, t.counts()), largest);
}

TEST(ConversionPlan, AVoxelIndexListTooLargeForWhatIsLeftIsNamed) {
  Table t({100, 200, 3'000'000, 100});
  t.meta.voxline_count = 3'000'000;
  t.voxels[2].coord[1] = 7;
  const MemoryBudget budget(64 * kMiB, "source.tck");
  try {
    plan_voxel_index(budget, 4 * kMiB, t.counts());
    FAIL() << "a list of 12 MB fit in 4 MiB";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Unsupported);
    const std::string what = e.what();
    EXPECT_NE(what.find("the voxel index's list of voxel (2, 7, 0)"), std::string::npos) << what;
  }
}

TEST(ConversionPlan, AFileWithoutAVoxelIndexNeedsNoBufferForIt) {
  Table t({100, 200, 3'000'000, 100});
  t.meta.voxline_count = 3'000'000;
  t.meta.streamline_count = (1ull << 29) + 1;  // more than a voxel index entry numbers
  const MemoryBudget budget(64 * kMiB, "source.tck");
  EXPECT_EQ(plan_voxel_index(budget, 4 * kMiB, t.counts()), 0u);
}

TEST(ConversionPlan, VoxelRunsAreKeptOnlyBesideThePlanAndItsLargestRange) {
  const Table t(std::vector<std::uint32_t>(500, 1000));
  MemoryBudget budget(200 * kMiB, "source.tck");
  const ConversionPlan plan = plan_conversion(budget, t.counts());
  ASSERT_EQ(plan.ranges.size(), 1u);
  EXPECT_GT(plan.ranges[0].bytes, (plan.ranges[0].vertex_end - plan.ranges[0].vertex_first) * 4);
  const std::uint64_t used = budget.used(), room = budget.left() - plan.ranges[0].bytes;
  EXPECT_FALSE(plan_voxel_runs(budget, plan, room + 1));
  EXPECT_EQ(budget.used(), used) << "runs that do not fit take nothing";
  EXPECT_TRUE(plan_voxel_runs(budget, plan, room));
  EXPECT_EQ(budget.used(), used + room);
  // Ranges cut to use what is left leave no room for them.
  MemoryBudget tight(12 * kMiB, "source.tck");
  const Table large(std::vector<std::uint32_t>(2000, 3000));
  const ConversionPlan cut = plan_conversion(tight, large.counts());
  ASSERT_GT(cut.ranges.size(), 2u);
  EXPECT_FALSE(plan_voxel_runs(tight, cut, 8 * kMiB));
}

TEST(ConversionPlan, VoxelIndexListsAreHeldOnlyInHalfOfWhatThePlanAndItsLargestRangeLeave) {
  const Table t(std::vector<std::uint32_t>(500, 1000));
  MemoryBudget budget(200 * kMiB, "source.tck");
  const ConversionPlan plan = plan_conversion(budget, t.counts());
  ASSERT_EQ(plan.ranges.size(), 1u);
  ASSERT_GT(plan.voxel_index_buffer_bytes, 0u);
  const std::uint64_t used = budget.used(), half = (budget.left() - plan.ranges[0].bytes) / 2;
  EXPECT_FALSE(plan_voxel_index_lists(budget, plan, half + 1));
  EXPECT_EQ(budget.used(), used) << "lists that do not fit take nothing";
  EXPECT_TRUE(plan_voxel_index_lists(budget, plan, half));
  EXPECT_EQ(budget.used(), used + half);
  // A file without a voxel index (plan_voxel_index: no buffer) holds no lists.
  ConversionPlan without = plan;
  without.voxel_index_buffer_bytes = 0;
  EXPECT_FALSE(plan_voxel_index_lists(budget, without, 0));
}

TEST(ConversionPlan, TheSameCountsGiveTheSamePlan) {
  const Table t(std::vector<std::uint32_t>(1500, 2500));
  MemoryBudget a(20 * kMiB, "source.tck"), b(20 * kMiB, "source.tck");
  const ConversionPlan x = plan_conversion(a, t.counts()), y = plan_conversion(b, t.counts());
  ASSERT_EQ(x.ranges.size(), y.ranges.size());
  for (std::size_t k = 0; k < x.ranges.size(); ++k) EXPECT_EQ(x.ranges[k].end, y.ranges[k].end);
  EXPECT_EQ(a.used(), b.used());
  EXPECT_EQ(x.voxel_index_buffer_bytes, y.voxel_index_buffer_bytes);
}

}  // namespace
}  // namespace vxl
