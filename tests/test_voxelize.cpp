// Voxelisation (Algorithm 1 + face splitting, spec §6) and order building (spec §6.4) on hand-made data, read back
// from the file the conversion writes.
#include <algorithm>
#include <cmath>
#include <cstring>

#include <sys/resource.h>

#include "converter/convert/convert.h"
#include "converter/convert/segment_orders.h"
#include "converter/convert/voxel_table.h"
#include "format/base/error.h"
#include "format/vxl_file.h"
#include "format/vxl_positions.h"
#include "format/vxl_verify.h"
#include "tests/test_support.h"

namespace vxl {
namespace {

Tractogram make(std::initializer_list<std::vector<float>> streamlines) {
  Tractogram t;
  t.source.path = "hand-made";
  for (const auto& s : streamlines) t.add_streamline(s.data(), s.size() / 3);
  return t;
}

// What a conversion wrote, copied out of its file.
struct Voxelized {
  MetaSection meta{};
  std::vector<VoxelEntry> voxels;
  std::vector<float> vertices;       // float32 positions
  std::vector<std::uint32_t> words;  // packed positions
  std::vector<std::uint8_t> orders;  // ORDB's payload
  std::vector<VoxlineEntry> voxlines;
  std::vector<std::uint64_t> streamline_first_voxline;
  bool valid = false;  // verify_vxl's verdict
};

ConvertSettings settings_for(double voxel, unsigned threads) {
  ConvertSettings s;
  s.voxel_size = voxel;
  s.threads = threads;
  s.positions = PositionEncoding::Float32;
  s.levels = 1;
  return s;
}

Voxelized convert(Tractogram t, const ConvertSettings& settings) {
  test::ScratchDir dir;
  const std::string path = dir.file("out.vxl");
  convert_tractogram(std::move(t), path, settings);
  const VxlFile f = VxlFile::open(path);
  Voxelized v;
  v.meta = f.meta();
  v.voxels.assign(f.voxels().begin(), f.voxels().end());
  v.vertices.assign(f.float_vertices().begin(), f.float_vertices().end());
  v.words.assign(f.packed_vertices().begin(), f.packed_vertices().end());
  v.orders.assign(f.order_bytes().begin(), f.order_bytes().end());
  v.voxlines.assign(f.voxlines().begin(), f.voxlines().end());
  v.streamline_first_voxline.assign(f.streamline_first_voxline().begin(), f.streamline_first_voxline().end());
  v.valid = verify_vxl(path).valid;
  return v;
}

Voxelized run(Tractogram t, double voxel = 10.0, unsigned threads = 1) {
  return convert(std::move(t), settings_for(voxel, threads));
}

TEST(Voxelize, AlgorithmOneAddsOneConnectingVertexPerVoxelChange) {
  // Points at x = 0, 4, 8 (voxel 0), 12, 16 (voxel 1), 21 (voxel 2); voxel size 10, origin x = 0.
  auto vt = run(make({{0, 0, 0, 4, 0, 0, 8, 0, 0, 12, 0, 0, 16, 0, 0, 21, 0, 0}}));
  ASSERT_EQ(vt.voxels.size(), 3u);
  EXPECT_EQ(vt.voxels[0].vertex_count, 4u);  // 0, 4, 8 + connector 12
  EXPECT_EQ(vt.voxels[1].vertex_count, 3u);  // 12, 16 + connector 21
  EXPECT_EQ(vt.voxels[2].vertex_count, 1u);  // 21 (last point: no connector)
  EXPECT_EQ(vt.voxels[0].segment_count, 3u);
  EXPECT_EQ(vt.voxels[1].segment_count, 2u);
  EXPECT_EQ(vt.voxels[2].segment_count, 0u);
  EXPECT_EQ(vt.meta.segment_count, 5u);  // = points - streamlines: nothing lost, nothing doubled
  EXPECT_EQ(vt.vertices[3 * 3], 12.0f);  // voxel 0's connecting vertex is the next point
  EXPECT_EQ(vt.meta.synthetic_point_count, 0u);
  EXPECT_EQ(vt.voxlines.size(), 3u);
}

TEST(Voxelize, PointOnAFaceBelongsToTheVoxelOnItsPositiveSide) {
  auto vt = run(make({{0, 0, 0, 10, 0, 0, 20, 0, 0}}));
  ASSERT_EQ(vt.voxels.size(), 3u);
  EXPECT_EQ(vt.voxels[1].coord[0], 1);
  EXPECT_EQ(vt.vertices[3 * vt.voxels[1].vertex_first], 10.0f);
  EXPECT_EQ(voxel_coordinate(10.0f, 0.0, 10.0), 1);
  EXPECT_EQ(voxel_coordinate(9.999999f, 0.0, 10.0), 0);
}

TEST(Voxelize, OnePointAndEmptyStreamlinesAreKept) {
  auto vt = run(make({{}, {1, 2, 3}, {}, {4, 5, 6, 5, 5, 6}}));
  EXPECT_EQ(vt.meta.streamline_count, 4u);
  EXPECT_EQ(vt.meta.point_count, 3u);
  EXPECT_EQ(vt.streamline_first_voxline, (std::vector<std::uint64_t>{0, 0, 1, 1, 2}));
  EXPECT_EQ(vt.meta.segment_count, 1u);
}

TEST(Voxelize, LongStepsAreSplitAtEveryFaceTheyCross) {
  // One step of 35 mm along x with 10 mm voxels crosses 3 faces (x = 10, 20, 30 from origin 0).
  auto vt = run(make({{0, 0, 0, 35, 0, 0}}));
  ASSERT_EQ(vt.voxels.size(), 4u);
  EXPECT_EQ(vt.meta.synthetic_point_count, 3u);
  EXPECT_EQ(vt.meta.segment_count, 4u);
  for (int i = 0; i < 4; ++i) {
    // every piece lies inside its voxel's cube (ends on its faces)
    EXPECT_GE(vt.voxels[i].tight_min[0], 10.0f * i) << i;
    EXPECT_LE(vt.voxels[i].tight_max[0], std::min(35.0f, 10.0f * (i + 1))) << i;
  }
  EXPECT_EQ(vt.voxlines[1].count_flags & kVoxlineSyntheticFirst, kVoxlineSyntheticFirst);
}

TEST(Voxelize, DiagonalStepThroughACornerMakesOneCrossingPoint) {
  // From (5,5,0) to (25,25,0): passes exactly through the corner (10,10) and (20,20).
  auto vt = run(make({{5, 5, 0, 25, 25, 0}}));
  EXPECT_EQ(vt.meta.synthetic_point_count, 2u);
  EXPECT_EQ(vt.voxels.size(), 3u);
}

TEST(Voxelize, StepsToANeighbourVoxelAreNotSplit) {
  auto vt = run(make({{0, 0, 0, 9, 9, 9, 11, 11, 11}}));  // 9 -> 11 crosses to the diagonal neighbour
  EXPECT_EQ(vt.meta.synthetic_point_count, 0u);
  EXPECT_EQ(vt.voxels.size(), 2u);
}

TEST(Voxelize, ResultDoesNotDependOnTheThreadCount) {
  Tractogram t;
  for (int s = 0; s < 500; ++s) {
    std::vector<float> pts;
    for (int i = 0; i < 40; ++i) {
      float a = 0.1f * i + 0.37f * s;
      pts.insert(pts.end(), {30 * std::cos(a) + s % 7, 30 * std::sin(a), 0.5f * i - 0.01f * s});
    }
    t.add_streamline(pts.data(), 40);
  }
  Tractogram copy = t;
  auto one = run(std::move(t), 5.0, 1);
  auto four = run(std::move(copy), 5.0, 4);
  EXPECT_EQ(one.vertices, four.vertices);
  ASSERT_EQ(one.voxels.size(), four.voxels.size());
  for (std::size_t i = 0; i < one.voxels.size(); ++i)
    EXPECT_EQ(0, std::memcmp(&one.voxels[i], &four.voxels[i], sizeof(VoxelEntry)));
  EXPECT_EQ(one.streamline_first_voxline, four.streamline_first_voxline);
}

// Packing while placing (the counting pass finds the tight bounds) must give what packing the float32 blocks
// gives: the same voxel entries and the same words (end bits aside: verify checks them on each voxline's last
// vertex), with 1 and 3 threads, levels of detail and synthetic points at the faces.
TEST(Voxelize, PackingWhilePlacingGivesTheWordsOfPackingThePlacedBlocks) {
  Tractogram t;
  for (int s = 0; s < 300; ++s) {
    std::vector<float> pts;
    for (int i = 0; i < 30; ++i) {
      float a = 0.13f * i + 0.41f * s;
      pts.insert(pts.end(), {25 * std::cos(a) - s % 5, 25 * std::sin(a), 0.7f * i - 0.02f * s});
    }
    t.add_streamline(pts.data(), 30);
  }
  for (unsigned threads : {1u, 3u}) {
    ConvertSettings settings = settings_for(3.0, threads);
    settings.levels = 3;
    const Voxelized floats = convert(t, settings);
    ASSERT_GT(floats.meta.synthetic_point_count, 0u) << "the faces must be crossed by long steps";
    std::vector<std::uint32_t> expected(floats.meta.vertex_count);
    std::vector<float> xyz = floats.vertices;
    for (const VoxelEntry& v : floats.voxels)
      pack_block(v, xyz.data() + 3 * v.vertex_first, v.vertex_count, expected.data() + v.vertex_first);

    settings.positions = PositionEncoding::Packed;
    const Voxelized packed = convert(t, settings);
    EXPECT_TRUE(packed.valid);
    std::vector<std::uint32_t> words = packed.words;
    for (std::uint32_t& w : words) w &= ~kPackedVoxlineEnd;
    EXPECT_TRUE(words == expected) << threads << " threads";
    ASSERT_EQ(packed.voxels.size(), floats.voxels.size());
    for (std::size_t i = 0; i < packed.voxels.size(); ++i) {
      VoxelEntry a = packed.voxels[i], b = floats.voxels[i];
      a.order_offset = b.order_offset = 0;  // the orders' widths may differ with the positions' encoding
      a.flags = b.flags = 0;
      EXPECT_EQ(0, std::memcmp(&a, &b, sizeof(VoxelEntry))) << "voxel " << i;
    }
    EXPECT_EQ(packed.voxlines.size(), floats.voxlines.size());
    EXPECT_EQ(packed.streamline_first_voxline, floats.streamline_first_voxline);
  }
}

// The bounds scan against a plain reading of its points: bounds, longest step, the step sum in 1/1024 mm^2
// (each step capped at 1 m^2) and the count, whatever the split into calls; it stops at the first non-finite
// point and names it (streamline numbered from the base, point within the streamline), and later calls keep it.
TEST(Voxelize, BoundsScanFindsBoundsStepsAndTheFirstNonFinitePoint) {
  const Tractogram t = make({{1, 2, 3, 4, -6, 3.5f},
                             {},
                             {0, 0, 0},
                             {-7, 8, 9, 2000, 8, 9, -7.25f, 8, 10},
                             {0.5f, 0.5f, -40, 0.5f, 0.5f, -39}});
  std::vector<float> lengths(t.streamline_count());
  detail::BoundsScan whole, first, second;
  whole.add(t.positions.data(), t.offsets.data(), 0, t.streamline_count(), 0, lengths.data());
  first.add(t.positions.data(), t.offsets.data(), 0, 3, 0);
  second.add(t.positions.data(), t.offsets.data(), 3, t.streamline_count(), 0);
  first.merge(second);
  double longest = 0;
  std::uint64_t sum = 0, steps = 0;
  for (std::uint64_t k = 0; k < t.streamline_count(); ++k)
    for (std::uint64_t i = t.offsets[k] + 1; i < t.offsets[k + 1]; ++i) {
      double d2 = 0;
      for (int c = 0; c < 3; ++c) d2 += std::pow(double(t.positions[3 * i + c]) - t.positions[3 * i + c - 3], 2);
      longest = std::max(longest, d2);
      sum += static_cast<std::uint64_t>(std::min(d2, 0x1p20) * 1024.0);
      ++steps;
    }
  for (const detail::BoundsScan* scan : {&whole, &first}) {
    EXPECT_EQ(scan->lo[0], -7.25f);
    EXPECT_EQ(scan->lo[1], -6.0f);
    EXPECT_EQ(scan->lo[2], -40.0f);
    EXPECT_EQ(scan->hi[0], 2000.0f);
    EXPECT_EQ(scan->hi[1], 8.0f);
    EXPECT_EQ(scan->hi[2], 10.0f);
    EXPECT_EQ(scan->longest_step2, longest);
    EXPECT_EQ(scan->step2_sum_fixed, sum);
    EXPECT_EQ(scan->steps, steps);
    EXPECT_EQ(scan->steps, 4u);
    EXPECT_EQ(scan->bad_streamline, detail::BoundsScan::kNone);
  }
  EXPECT_EQ(lengths[1], 0.0f);
  EXPECT_FLOAT_EQ(lengths[4], 1.0f);
  // A non-finite coordinate: the scan stops there and a later call does not replace it.
  Tractogram bad = make({{1, 2, 3}, {1, 1, 1, 2, 2, 2, 3, INFINITY, 3, NAN, 4, 4}});
  detail::BoundsScan scan;
  scan.add(bad.positions.data(), bad.offsets.data(), 0, 2, 100);
  EXPECT_EQ(scan.bad_streamline, 101u);
  EXPECT_EQ(scan.bad_point, 2u);
  scan.add(bad.positions.data(), bad.offsets.data(), 1, 2, 7);
  EXPECT_EQ(scan.bad_streamline, 101u);
  try {
    scan.check("bad.tck");
    FAIL() << "a non-finite point was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    EXPECT_NE(std::string(e.what()).find("streamline 101 (point 2)"), std::string::npos) << e.what();
  }
}

TEST(Voxelize, TooSmallAVoxelIsRefusedWithASuggestion) {
  try {
    run(make({{0, 0, 0, 50, 0, 0}}), 0.001);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Unsupported);
    EXPECT_NE(std::string(e.what()).find("--voxel-size"), std::string::npos) << e.what();
  }
}

// Found by fuzz_tck: one step of 8e8 mm at 10 mm voxels would cross ~1e8 faces (8 GB of crossings); the
// budget must be checked before the crossings are generated, not after.
TEST(Voxelize, OneHugeStepIsRefusedBeforeAllocating) {
  struct rusage before {};
  getrusage(RUSAGE_SELF, &before);
  try {
    run(make({{0, 0, 0, 1, 1, 1, 8.2e8f, 2, 2}}));
    FAIL() << "accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Unsupported);
  }
  struct rusage after {};
  getrusage(RUSAGE_SELF, &after);
  EXPECT_LT(after.ru_maxrss - before.ru_maxrss, 256 * 1024)
      << "peak memory grew by " << (after.ru_maxrss - before.ru_maxrss) << " KiB";
}

TEST(SegmentOrders, AxisOrdersSortByMidpointWithStableTies) {
  // Segments inside one voxel with x-midpoints 5, 1, 3 and a tie on y.
  auto vt = run(make({{4, 1, 1, 6, 1, 1}, {0, 1, 1, 2, 1, 1}, {2, 1, 1, 4, 1, 1}}));
  ASSERT_EQ(vt.voxels.size(), 1u);
  EXPECT_EQ(vt.meta.stored_order_count, 3u);
  // Six vertices: entries of 3 bits (the bit width of 5), each array of 3 entries in 2 bytes (spec §5.5).
  ASSERT_EQ(vt.orders.size(), 8u);
  const OrderView x{vt.orders.data() + vt.voxels[0].order_offset, 3, 3}, y{x.data + 2, 3, 3};
  // blocks: [4,6] at 0-1, [0,2] at 2-3, [2,4] at 4-5; +X order: midpoints 1, 3, 5 -> starts 2, 4, 0
  EXPECT_EQ(x[0], 2u);
  EXPECT_EQ(x[1], 4u);
  EXPECT_EQ(x[2], 0u);
  EXPECT_EQ(x.data[0], 2 | 4 << 3 | (0 << 6)) << "entries packed from the lowest bit up";
  // +Y: all keys equal -> ascending local index
  EXPECT_EQ(y[0], 0u);
  EXPECT_EQ(y[1], 2u);
  EXPECT_EQ(y[2], 4u);
  EXPECT_EQ(x.data[1] >> 1, 0) << "the bits after an array's last entry are zero";
}

TEST(SegmentOrders, SeventeenBitEntriesAboveU16Range) {
  std::vector<float> pts;
  for (int i = 0; i < 70000; ++i)
    pts.insert(pts.end(), {float(i % 5) * 0.1f, float((i * 7) % 9) * 0.1f, float(i % 3) * 0.1f});
  Tractogram t;
  t.add_streamline(pts.data(), 70000);
  auto vt = run(std::move(t), 10.0, 2);
  EXPECT_EQ(vt.voxels[0].flags, 1u);                   // beyond 16 bits: the renderer uploads high halves
  const std::uint64_t array = (69999u * 17u + 7) / 8;  // 17 bits: the bit width of 69 999
  EXPECT_EQ(vt.orders.size(), align_up(3 * array, 4));
  for (std::uint32_t k = 0; k < 3; ++k) {
    const OrderView order{vt.orders.data() + k * array, 69999, 17};
    std::vector<std::uint8_t> seen(69999, 0);
    for (std::uint32_t n = 0; n < order.count; ++n) {
      ASSERT_LT(order[n], 69999u) << "order " << k << " entry " << n;
      ASSERT_EQ(seen[order[n]]++, 0) << "order " << k << " entry " << n << " repeats " << order[n];
    }
  }
}

TEST(SegmentOrders, UnknownOrderSetIsAUsageError) {
  EXPECT_THROW(parse_order_set("random"), Error);
  EXPECT_EQ(parse_order_set("axis+diag").directions.size(), 7u);
}

}  // namespace
}  // namespace vxl
