// Numerical stability and limits at the extremes. Each test states the documented
// outcome (README "Precision policy and limits", spec §8–§9).
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <thread>

#include "converter/convert/convert.h"
#include "converter/export/tck_writer.h"
#include "converter/readers/read_tractogram.h"
#include "converter/synth/synth.h"
#include "format/base/error.h"
#include "format/vxl_file.h"
#include "format/vxl_streamlines.h"
#include "format/vxl_verify.h"
#include "tests/address_sanitizer.h"
#include "tests/test_support.h"

namespace vxl {
namespace {

using test::ScratchDir;

// Streamlines on a grid of 1/16 mm (exactly representable at 1e6 mm in float32), shifted by `offset`.
Tractogram shifted(double offset) {
  Tractogram t;
  t.source.path = "shifted";
  for (int s = 0; s < 50; ++s) {
    std::vector<float> p;
    for (int i = 0; i < 60; ++i) {
      double x = std::round(16 * (30 * std::cos(0.05 * i + s))) / 16, y = std::round(16 * (0.7 * i - 20)) / 16,
             z = std::round(16 * (s * 0.8 - 20 + 5 * std::sin(0.1 * i))) / 16;
      for (double v : {x, y, z}) p.push_back(static_cast<float>(v + offset));
    }
    t.add_streamline(p.data(), 60);
  }
  return t;
}

std::vector<float> walk_points(const VxlFile& f) {
  std::vector<float> out;
  walk_streamlines(
      f, {[&](std::uint64_t, std::span<const float> xyz) { out.insert(out.end(), xyz.begin(), xyz.end()); }, {}, {}});
  return out;
}

// float32 positions keep every coordinate bit for bit, however far out; packed ones stay within their
// bound there (test_packed_positions.cpp).
TEST(Extremes, FarFromTheOriginKeepsEveryCoordinateAndTheSameVoxels) {
  ScratchDir dir;
  ConvertSettings exact;
  exact.positions = PositionEncoding::Float32;
  convert_tractogram(shifted(0), dir.file("origin.vxl"), exact);
  VxlFile base = VxlFile::open(dir.file("origin.vxl"));
  for (double offset : {1e5, -1e5, 1e6, -1e6}) {
    SCOPED_TRACE(offset);
    Tractogram t = shifted(offset);
    const std::vector<float> expected = t.positions;
    const std::string path = dir.file("far.vxl");
    convert_tractogram(std::move(t), path, exact);
    VerifyResult r = verify_vxl(path);
    ASSERT_TRUE(r.valid) << r.problem;
    VxlFile f = VxlFile::open(path);
    EXPECT_EQ(walk_points(f), expected);  // bit-exact
    // The grid is anchored at the data's minimum, so the voxel structure is that of the unshifted copy.
    ASSERT_EQ(f.voxels().size(), base.voxels().size());
    for (std::size_t v = 0; v < f.voxels().size(); ++v) {
      EXPECT_EQ(std::memcmp(f.voxels()[v].coord, base.voxels()[v].coord, 12), 0);
      EXPECT_EQ(f.voxels()[v].vertex_count, base.voxels()[v].vertex_count);
    }
  }
}

TEST(Extremes, VoxelSizesFromAHundredthToTenMetres) {
  ScratchDir dir;
  // 10,000 mm: everything in one voxel.
  ConvertSettings big;
  big.voxel_size = 10000;
  convert_tractogram(shifted(0), dir.file("big.vxl"), big);
  EXPECT_EQ(VxlFile::open(dir.file("big.vxl")).meta().voxel_count, 1u);
  // 0.01 mm with ~1 mm steps would add ~100 points per step: refused, with a suggested size.
  ConvertSettings tiny;
  tiny.voxel_size = 0.01;
  try {
    convert_tractogram(shifted(0), dir.file("tiny.vxl"), tiny);
    FAIL() << "accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Unsupported);
    EXPECT_NE(std::string(e.what()).find("--voxel-size"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(dir.file("tiny.vxl")));
  // 0.01 mm works for data whose steps are smaller than that.
  Tractogram fine;
  std::vector<float> p;
  for (int i = 0; i < 1000; ++i) p.insert(p.end(), {0.004f * i, 0.001f * i, 0.0f});
  fine.add_streamline(p.data(), 1000);
  convert_tractogram(std::move(fine), dir.file("fine.vxl"), tiny);
  EXPECT_TRUE(verify_vxl(dir.file("fine.vxl")).valid);
}

// A zero on the data's edge is stored as +0 in META's origin and bounds, as in the tight bounds, whichever
// zero the source lists: packed, where -0 and +0 pack alike, the two files are the same bytes.
TEST(Extremes, AZeroOnTheDatasEdgeIsStoredAsPlusZero) {
  ScratchDir dir;
  auto convert_with = [&](float zero, const std::string& name) {
    Tractogram t;
    t.source.path = "zeros";
    const float points[] = {zero, zero, -3, 3, 3, zero, 1, 2, -1};  // x and y start at 0, z ends at 0
    t.add_streamline(points, 3);
    convert_tractogram(std::move(t), dir.file(name), {});
    return dir.file(name);
  };
  const std::string minus = convert_with(-0.0f, "minus.vxl"), plus = convert_with(0.0f, "plus.vxl");
  const VxlFile f = VxlFile::open(minus);
  for (double v : {f.meta().grid_origin[0], f.meta().grid_origin[1], f.meta().bounds_min[0], f.meta().bounds_min[1],
                   f.meta().bounds_max[2]}) {
    EXPECT_EQ(v, 0.0);
    EXPECT_FALSE(std::signbit(v));
  }
  EXPECT_TRUE(verify_vxl(minus).valid);
  EXPECT_EQ(test::slurp(minus), test::slurp(plus));
}

TEST(Extremes, AGridTooLargeIsRefusedWithASuggestionAndNoOverflow) {
  ScratchDir dir;
  Tractogram t;
  float p[6] = {-1e9f, 0, 0, 1e9f, 0, 0};  // 2e9 mm: 2e11 cells at 0.01 mm
  t.add_streamline(p, 1);
  t.add_streamline(p + 3, 1);
  ConvertSettings s;
  s.voxel_size = 0.01;
  try {
    convert_tractogram(std::move(t), dir.file("huge.vxl"), s);
    FAIL() << "accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Unsupported);
    EXPECT_NE(std::string(e.what()).find("--voxel-size"), std::string::npos) << e.what();
  }
}

TEST(Extremes, OneStreamlineOfTenMillionPoints) {
  ScratchDir dir;
  Tractogram t;
  t.positions.resize(3 * 10'000'000ull);
  for (std::size_t i = 0; i < 10'000'000; ++i) {
    double a = i * 1e-4;
    t.positions[3 * i] = static_cast<float>(60 * std::cos(a));
    t.positions[3 * i + 1] = static_cast<float>(60 * std::sin(a));
    t.positions[3 * i + 2] = static_cast<float>(i * 1e-5 - 50);
  }
  t.offsets = {0, 10'000'000};
  const std::vector<float> expected = t.positions;
  ConvertSettings exact;
  exact.positions = PositionEncoding::Float32;  // compared bit for bit below
  convert_tractogram(std::move(t), dir.file("long.vxl"), exact);
  VxlFile f = VxlFile::open(dir.file("long.vxl"));
  EXPECT_EQ(f.meta().point_count, 10'000'000u);
  EXPECT_EQ(f.meta().streamline_count, 1u);
  EXPECT_TRUE(walk_points(f) == expected);
}

TEST(Extremes, Float64SourcesKeepTheNearestFloat32) {
  ScratchDir dir;
  const std::string path = dir.file("f64.tck");
  const double values[] = {1.0 + 1e-12, 100.0 / 3.0, 1.0 / 7.0, 1.1, 33.4, 0.3};
  {
    const std::string head = "mrtrix tracks\ndatatype: Float64LE\ncount: 1\nfile: . 64\nEND\n";
    std::ofstream out(path, std::ios::binary);
    out << head << std::string(64 - head.size(), '\0');  // the data starts at byte 64
    const double nan = std::nan(""), inf = INFINITY;
    for (double v : values) out.write(reinterpret_cast<const char*>(&v), 8);
    for (double v : {nan, nan, nan, inf, inf, inf}) out.write(reinterpret_cast<const char*>(&v), 8);
  }
  Tractogram t = read_tck(path);
  ASSERT_EQ(t.point_count(), 2u);
  for (int i = 0; i < 6; ++i)
    EXPECT_EQ(t.positions[i], static_cast<float>(values[i])) << "nearest float32 of " << values[i];
  convert_tractogram(std::move(t), dir.file("f64.vxl"), {});
  std::vector<float> stored = walk_points(VxlFile::open(dir.file("f64.vxl")));
  for (int i = 0; i < 6; ++i) EXPECT_EQ(stored[i], static_cast<float>(values[i]));
}

// A .vxl that claims more than 2^32 vertices, built as a sparse file (nothing near 48 GB is written or
// allocated): open() must read every count and range in 64 bits.
TEST(Extremes, CountsAndOffsetsAreSixtyFourBitBeyondTwoToTheThirtyTwo) {
  ScratchDir dir;
  const std::string path = dir.file("sparse.vxl");
  const std::uint64_t first_count = 0xFFFFFFF0u, second_count = 0x20;  // 2^32 + 16 vertices in all
  const std::uint64_t vertices = first_count + second_count;
  MetaSection m{};
  m.streamline_count = 1;
  m.point_count = vertices;
  m.vertex_count = vertices;
  m.segment_count = 2;
  m.voxline_count = 2;
  m.voxel_count = 2;
  m.stored_order_count = 3;
  m.voxel_size = 10;
  m.grid_dims[0] = 2;
  m.grid_dims[1] = m.grid_dims[2] = 1;
  VoxelEntry v[2]{};
  v[0].coord[0] = 0;
  v[1].coord[0] = 1;
  v[0].vertex_first = 0;
  v[0].vertex_count = static_cast<std::uint32_t>(first_count);
  v[1].vertex_first = first_count;
  v[1].vertex_count = static_cast<std::uint32_t>(second_count);
  v[0].segment_count = v[1].segment_count = 1;
  v[0].flags = order_width_code(v[0].vertex_count);
  v[1].flags = order_width_code(v[1].vertex_count);
  v[1].order_offset = voxel_orders_size(v[0].vertex_count, 1, 3, OrderPacking::Bytes);
  const std::uint64_t ordr = v[1].order_offset + voxel_orders_size(v[1].vertex_count, 1, 3, OrderPacking::Bytes);
  DirectionEntry dirs[3] = {{{1, 0, 0}, 0}, {{0, 1, 0}, 0}, {{0, 0, 1}, 0}};
  struct Part {
    const char* id;
    const void* data;
    std::uint64_t size;
  };
  std::vector<std::uint8_t> orders(ordr, 0);
  VoxlineEntry lines[2] = {{0, static_cast<std::uint32_t>(first_count - 1)},
                           {1, static_cast<std::uint32_t>(second_count)}};
  std::uint64_t strm[2] = {0, 2};
  std::vector<Part> parts = {{"META", &m, sizeof m},        {"DIRS", dirs, sizeof dirs},
                             {"VOXT", v, sizeof v},         {"VERT", nullptr, vertices * 12},
                             {"ORDR", orders.data(), ordr}, {"VXLN", lines, sizeof lines},
                             {"STRM", strm, sizeof strm}};
  int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_TRUNC, 0644);
  ASSERT_GE(fd, 0);
  std::vector<SectionEntry> table(parts.size());
  std::uint64_t at = align_up(64 + 32 * parts.size(), 64);
  for (std::size_t i = 0; i < parts.size(); ++i) {
    std::memcpy(table[i].id, parts[i].id, 4);
    table[i].flags = kSectionRequired;
    table[i].offset = at;
    table[i].size = parts[i].size;
    if (parts[i].data) {
      ASSERT_EQ(::pwrite(fd, parts[i].data, parts[i].size, static_cast<off_t>(at)), ssize_t(parts[i].size));
    }
    at = align_up(at + parts[i].size, 64);
  }
  FileHeader h{};
  std::memcpy(h.magic, kVxlMagic.data(), 8);
  h.version_major = 1;
  h.header_size = 64;
  h.file_size = at;
  h.section_table_offset = 64;
  h.section_count = static_cast<std::uint32_t>(parts.size());
  ASSERT_EQ(::pwrite(fd, &h, 64, 0), 64);
  ASSERT_EQ(::pwrite(fd, table.data(), 32 * table.size(), 64), ssize_t(32 * table.size()));
  ASSERT_EQ(::ftruncate(fd, static_cast<off_t>(at)), 0);  // sparse: the vertex section is a hole
  ::close(fd);

  VxlFile f = VxlFile::open(path);
  EXPECT_EQ(f.meta().vertex_count, vertices);
  EXPECT_GT(f.meta().vertex_count, std::uint64_t(1) << 32);
  EXPECT_EQ(f.float_vertices().size(), 3 * vertices);
  EXPECT_EQ(f.voxels()[1].vertex_first, first_count);
  EXPECT_EQ(f.order(1, 2).bits, 16u);
  EXPECT_EQ(f.order(0, 0).bits, 32u);
  // The last vertex is addressable (a hole reads as zeros).
  EXPECT_EQ(f.float_vertices()[3 * vertices - 1], 0.0f);
}

// A conversion killed at any moment leaves nothing at the output path (nor a temporary beside it).
TEST(Extremes, AConversionKilledAtAnyMomentLeavesNoOutput) {
  ScratchDir dir;
  const std::string tck = dir.file("in.tck");
  {
    // Large enough that most runs are killed while writing; the sanitizers' build is several times slower, so a
    // smaller source gives it as long a window.
    Tractogram t = synthesize_tractogram({test::kAddressSanitizer ? 40000u : 150000u, 3});
    TckWriter w(tck, t.streamline_count());
    for (std::uint64_t i = 0; i < t.streamline_count(); ++i)
      w.add({t.positions.data() + 3 * t.offsets[i], 3 * (t.offsets[i + 1] - t.offsets[i])});
    w.finish();
  }
  const std::string out = dir.file("out.vxl");
  const int killed_while_writing = test::kill_conversions(dir, {tck, out}, out, 8);
  EXPECT_GE(killed_while_writing, 3) << "too few runs were killed while writing their output";
}

// Running out of memory fails cleanly: a message about memory, a non-zero exit code (4 when an
// allocation or a thread's start fails, 5 when the output cannot be mapped), no output. The conversion is
// told it may use more memory than the address space allows; the address space is cut at several sizes, so
// that the failure comes at different steps (a buffer, a thread's stack, the output's mapping). Every size must
// stay well below what the conversion needs: 400,000 synthetic streamlines failed within 340,000 KiB of address
// space and converted within 380,000 on the 2-core machine (what it takes varies by tens of MB with where the
// threads' allocator arenas land), and the sizes go to 240,000 KiB. (200,000 streamlines, used before, sometimes
// converted within 220,000-300,000 KiB once the orders' chunk followed the largest voxel.)
// (AddressSanitizer reserves terabytes of address space, so an address-space limit cannot be used under it.)
TEST(Extremes, RunningOutOfMemoryFailsCleanly) {
#if defined(VOXLINES_ADDRESS_SANITIZER)
  GTEST_SKIP() << "an address-space limit cannot be used under AddressSanitizer";
#else
  ScratchDir dir;
  const std::string tck = dir.file("in.tck"), out = dir.file("out.vxl");
  auto synth = test::run_cli("synth '" + tck + "' --streamlines 400000");
  ASSERT_EQ(synth.exit_code, 0) << synth.output;
  for (int kib = 40000; kib <= 240000; kib += 20000) {
    SCOPED_TRACE("ulimit -v " + std::to_string(kib));
    auto r = test::run_program("bash", "-c \"ulimit -v " + std::to_string(kib) + "; exec " + std::string(VOXLINES_CLI) +
                                           " convert '" + tck + "' '" + out + "' --memory-limit 4G\"");
    EXPECT_TRUE(r.exit_code == 4 || r.exit_code == 5) << r.output;
    EXPECT_TRUE(r.output.find("out of memory") != std::string::npos ||
                r.output.find("Cannot allocate memory") != std::string::npos)
        << r.output;
    EXPECT_FALSE(std::filesystem::exists(out));
  }
#endif
}

// The two skips above must follow the build: Clang does not define __SANITIZE_ADDRESS__, so skips keyed on
// it are not taken under Clang's ASan. VOXLINES_TESTS_SANITIZED comes from the CMake option.
TEST(Extremes, TheAddressSanitizerSkipFollowsTheBuild) {
  EXPECT_EQ(test::kAddressSanitizer, VOXLINES_TESTS_SANITIZED != 0);
}

}  // namespace
}  // namespace vxl
