// The .vxlz package (spec/vxlz-package-v2.md): .vxl -> .vxlz -> .vxl keeps the structure exactly and
// every coordinate within the stated bound at 11, 14 and 16 bits; the unpacked file passes verify;
// Draco keeps the point order; damaged, truncated and crafted packages are refused with an Error (never
// a crash: the ASan build runs these too).
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <optional>
#include <random>

#include <nlohmann/json.hpp>

#include "converter/convert/convert.h"
#include "converter/package/pack.h"
#include "converter/package/unpack.h"
#include "converter/readers/read_tractogram.h"
#include "converter/synth/synth.h"
#include "format/base/checksum.h"
#include "format/base/error.h"
#include "format/streamline_length.h"
#include "format/vxl_file.h"
#include "format/vxl_levels.h"
#include "format/vxl_streamlines.h"
#include "format/vxl_verify.h"
#include "format/vxlz_draco.h"
#include "format/vxlz_package.h"
#include "format/vxlz_tables.h"
#include "tests/reseal_checksums.h"
#include "tests/test_support.h"

namespace vxl {
namespace {

using test::ScratchDir;
using test::slurp;

// Synthetic bundles plus the awkward cases: a step over several voxels (synthetic face points), a
// one-point and an empty streamline, and two groups.
Tractogram test_tractogram(std::uint64_t streamlines = 1500) {
  SynthSettings settings;
  settings.streamlines = streamlines;
  settings.seed = 7;
  Tractogram t = synthesize_tractogram(settings);
  t.source.path = "synthetic.tck";
  t.source.format = "tck";
  const float jump[9] = {0, 0, 0, 1, 0.5f, 0.25f, 45, 31, -17};
  t.add_streamline(jump, 3);
  const float one[3] = {-3, 4, 5};
  t.add_streamline(one, 1);
  t.add_streamline(one, 0);
  const std::uint64_t n = t.streamline_count();
  t.groups.push_back({"left", {0, 2, 3, 10, n - 3}});
  t.groups.push_back({"right", {1, n - 1}});
  return t;
}

std::string convert_for_package(Tractogram t, const std::string& path, double voxel_size = 10.0,
                                const char* orders = "axis") {
  ConvertSettings s;
  s.voxel_size = voxel_size;
  s.orders = orders;
  convert_tractogram(std::move(t), path, s);
  return path;
}

// Written as a new file: truncating and rewriting one makes ext4 flush it on close (auto_da_alloc),
// which would make the thousands of rewrites below take seconds.
void dump_bytes(const std::string& p, const std::vector<char>& bytes, std::size_t n) {
  std::filesystem::remove(p);
  std::ofstream(p, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(n));
}

template <typename T>
std::vector<T> to_vector(std::span<const T> s) {
  return {s.begin(), s.end()};
}

// The bound of spec §6, computed here from the .vxl's own bounds rather than taken from the package.
double expected_bound(const MetaSection& m, std::uint32_t bits) {
  double range = 0, magnitude = 0;
  for (int c = 0; c < 3; ++c) range = std::max(range, m.bounds_max[c] - m.bounds_min[c]);
  for (int c = 0; c < 3; ++c)
    magnitude = std::max({magnitude, std::abs(m.bounds_min[c]), std::abs(m.bounds_min[c] + range)});
  return range / double((1u << bits) - 1) / 2 + std::ldexp(magnitude, -23);
}

// Everything the unpacked file must share with the packed one: all tables but the vertex positions, the
// orders and the bounds.
void expect_same_structure(const VxlFile& a, const VxlFile& b) {
  MetaSection ma = a.meta(), mb = b.meta();
  ma.position_encoding = mb.position_encoding = 0;  // the unpacker's choice
  for (int c = 0; c < 3; ++c) {
    ma.bounds_max[c] = mb.bounds_max[c] = 0;  // recomputed from decoded vertices
    EXPECT_EQ(mb.bounds_min[c], mb.grid_origin[c]) << "bounds_min must stay the grid origin (spec §6)";
  }
  EXPECT_EQ(std::memcmp(&ma, &mb, sizeof ma), 0) << "META differs beyond the bounds";
  ASSERT_EQ(a.voxels().size(), b.voxels().size());
  for (std::size_t i = 0; i < a.voxels().size(); ++i) {
    const VoxelEntry &u = a.voxels()[i], &v = b.voxels()[i];
    ASSERT_TRUE(std::equal(u.coord, u.coord + 3, v.coord)) << i;
    ASSERT_EQ(u.vertex_first, v.vertex_first) << i;
    ASSERT_EQ(u.vertex_count, v.vertex_count) << i;
    ASSERT_EQ(u.segment_count, v.segment_count) << i;
    ASSERT_EQ(u.order_offset, v.order_offset) << i;
    ASSERT_EQ(u.flags, v.flags) << i;
  }
  const auto va = a.voxlines(), vb = b.voxlines();
  ASSERT_EQ(va.size(), vb.size());
  if (!va.empty()) {
    EXPECT_EQ(std::memcmp(va.data(), vb.data(), va.size_bytes()), 0);
  }
  EXPECT_EQ(to_vector(a.streamline_first_voxline()), to_vector(b.streamline_first_voxline()));
  ASSERT_EQ(a.directions().size(), b.directions().size());
  EXPECT_EQ(std::memcmp(a.directions().data(), b.directions().data(), a.directions().size_bytes()), 0);
  const auto ga = a.groups(), gb = b.groups();
  ASSERT_EQ(ga.size(), gb.size());
  for (std::size_t g = 0; g < ga.size(); ++g) {
    EXPECT_EQ(ga[g].name, gb[g].name);
    EXPECT_EQ(ga[g].members, gb[g].members);
  }
}

// Largest coordinate error over the shipped points: every voxline's own vertices (they correspond one to
// one: the structure is the same). A connecting vertex is not shipped: the unpacker copies the next
// voxline's first point, which a packed original holds, decoded in another voxel, within both voxels'
// bounds of it (spec §5.4) — not within the package's.
double max_vertex_error(const VxlFile& a, const VxlFile& b) {
  const std::vector<float> x = a.all_vertices(), y = b.all_vertices();
  EXPECT_EQ(x.size(), y.size());
  double worst = 0;
  WalkCallbacks cb;
  cb.voxline = [&](const VoxlineVisit& v) {
    const std::uint64_t first = v.first_vertex, own = v.own_points;
    for (std::uint64_t i = 3 * first; i < 3 * (first + own) && i < std::min(x.size(), y.size()); ++i)
      worst = std::max(worst, std::abs(double(x[i]) - double(y[i])));
  };
  walk_streamlines(a, cb);
  return worst;
}

struct Streamlines {
  std::vector<std::uint64_t> sizes;
  std::vector<float> points;
};
Streamlines streamlines_of(const VxlFile& f) {
  Streamlines s;
  walk_streamlines(f, {[&](std::uint64_t, std::span<const float> xyz) {
                         s.sizes.push_back(xyz.size() / 3);
                         s.points.insert(s.points.end(), xyz.begin(), xyz.end());
                       },
                       {},
                       {}});
  return s;
}

// Checks the whole round trip of `vxl` at `bits` and returns the unpacked file's path.
std::string round_trip(const ScratchDir& dir, const std::string& vxl, std::uint32_t bits,
                       const PackSettings& base = {}) {
  const std::string packed = dir.file("p" + std::to_string(bits) + ".vxlz");
  const std::string unpacked = dir.file("u" + std::to_string(bits) + ".vxl");
  const VxlFile original = VxlFile::open(vxl);
  PackSettings settings = base;
  settings.bits = bits;
  const PackSummary summary = pack_vxl(original, packed, settings);
  EXPECT_EQ(summary.bytes, std::filesystem::file_size(packed));
  // Unpacked as float32, so that the only loss measured is the package's quantisation.
  UnpackSettings exact;
  exact.positions = PositionEncoding::Float32;
  const UnpackSummary back = unpack_vxlz(packed, unpacked, exact);
  EXPECT_EQ(back.pack.quantization_bits, bits);

  const VerifyResult verified = verify_vxl(unpacked);
  EXPECT_TRUE(verified.valid) << verified.problem;
  const VxlFile copy = VxlFile::open(unpacked);
  expect_same_structure(original, copy);

  const double bound = expected_bound(original.meta(), bits);
  EXPECT_NEAR(summary.pack.error_bound, bound, bound * 1e-12);
  const double error = max_vertex_error(original, copy);
  EXPECT_LE(error, bound) << bits << " bits";
  EXPECT_LE(summary.pack.max_error, bound);
  EXPECT_EQ(summary.pack.max_error, error) << "the stated measured error is the real one";

  // Same streamlines, same point counts (the walk drops synthetic points on both sides).
  const Streamlines a = streamlines_of(original), b = streamlines_of(copy);
  EXPECT_EQ(a.sizes, b.sizes);
  EXPECT_EQ(a.points.size(), b.points.size());

  // The unpacked provenance states the loss.
  const auto prov = nlohmann::json::parse(copy.provenance_json());
  EXPECT_EQ(prov["vxlz"]["bits"], bits);
  EXPECT_EQ(prov["vxlz"]["error_bound_mm"].get<double>(), summary.pack.error_bound);
  EXPECT_EQ(prov["source"], nlohmann::json::parse(original.provenance_json())["source"]);
  return unpacked;
}

class VxlzPackage : public ::testing::TestWithParam<std::uint32_t> {
 protected:
  ScratchDir dir;
};

TEST_P(VxlzPackage, RoundTripKeepsStructureAndStaysWithinTheBound) {
  const std::string vxl = convert_for_package(test_tractogram(), dir.file("synthetic.vxl"));
  ASSERT_GT(VxlFile::open(vxl).meta().synthetic_point_count, 0u) << "the test data must have synthetic points";
  round_trip(dir, vxl, GetParam());
}

INSTANTIATE_TEST_SUITE_P(Bits, VxlzPackage, ::testing::Values(11u, 14u, 16u));

TEST(VxlzDraco, ChunkKeepsPointOrderAndDuplicates) {
  // Sequential encoding must keep the order, and no deduplication may merge the many repeated values;
  // small residuals go through joint symbols, large ones through the escape cloud, for every width t.
  std::mt19937 rng(3);
  std::vector<std::int32_t> values(3 * 5000);
  for (std::size_t i = 0; i < values.size(); ++i)
    values[i] = i % 7 == 0   ? 0
                : i % 5 == 0 ? static_cast<std::int32_t>(rng() % 200001) - 100000
                             : static_cast<std::int32_t>(rng() % 9) - 4;
  for (std::size_t i = 300; i < 600; ++i) values[i] = 42;  // a run of identical points
  for (std::uint32_t t = kVxlzMinJointBits; t <= kVxlzMaxJointBits; ++t) {
    SCOPED_TRACE(t);
    const EncodedChunk chunk = encode_residual_chunk(values, t);
    EXPECT_FALSE(chunk.escapes.empty());
    const ChunkBytes bytes{chunk.symbols, chunk.escapes, 0, 0};
    std::vector<std::int32_t> back(values.size());
    decode_residual_chunk(bytes, t, back, "chunk");
    EXPECT_EQ(back, values);
    std::vector<std::int32_t> wrong_count(values.size() - 3);
    EXPECT_THROW(decode_residual_chunk(bytes, t, wrong_count, "chunk"), Error);
  }
  // No escapes at all: the escape buffer is empty.
  const std::vector<std::int32_t> small(3 * 100, -1);
  const EncodedChunk chunk = encode_residual_chunk(small, 3);
  EXPECT_TRUE(chunk.escapes.empty());
  std::vector<std::int32_t> back(small.size());
  decode_residual_chunk({chunk.symbols, chunk.escapes, 0, 0}, 3, back, "chunk");
  EXPECT_EQ(back, small);
}

TEST(VxlzDraco, JointSymbols) {
  const std::int32_t zero[3] = {0, 0, 0}, mixed[3] = {-1, 1, 0}, edge[3] = {-4, 3, -4}, wide[3] = {4, 0, 0};
  EXPECT_EQ(joint_symbol(zero, 3), 1u);
  EXPECT_EQ(joint_symbol(mixed, 3), 1u + 1u + (2u << 3));             // zigzag: -1 -> 1, 1 -> 2
  EXPECT_EQ(joint_symbol(edge, 3), 1u + 7u + (6u << 3) + (7u << 6));  // the largest symbol is 2^9
  EXPECT_EQ(joint_symbol(wide, 3), 0u) << "zigzag(4) = 8 needs 4 bits: escape";
  EXPECT_EQ(joint_symbol(wide, 4), 1u + 8u);
}

TEST(VxlzPackageOptions, ChunkSizeAndThreadsDoNotChangeTheResult) {
  // Decoded values depend only on the quantised points, never on how they are chunked or scheduled;
  // tiny chunks also split streamlines and voxlines across chunk boundaries.
  ScratchDir dir;
  const std::string vxl = convert_for_package(test_tractogram(300), dir.file("s.vxl"));
  PackSettings tiny;
  tiny.chunk_points = 7;
  tiny.threads = 2;
  const std::string a = round_trip(dir, vxl, 12, tiny);
  std::filesystem::rename(a, dir.file("tiny.vxl"));
  PackSettings one;
  one.threads = 1;
  const std::string b = round_trip(dir, vxl, 12, one);
  const VxlFile fa = VxlFile::open(dir.file("tiny.vxl")), fb = VxlFile::open(b);
  EXPECT_EQ(fa.all_vertices(), fb.all_vertices());
  EXPECT_EQ(to_vector(fa.order_bytes()), to_vector(fb.order_bytes()));
}

// The unpacker decodes the chunks side by side, once or twice (its bounds, ends and lengths first, then the positions):
// a streamline cut by chunks, here by every seventh point, gets the length of its points measured whole, to the bit,
// and each voxel the bounds of its vertices, as one streamline and one block at a time would measure them.
TEST(VxlzPackageOptions, StreamlinesCutByChunksGetTheirWholeLengthAndVoxelsTheirBoundsDecodedOnceOrTwice) {
  ScratchDir dir;
  const std::string vxl = convert_for_package(test_tractogram(300), dir.file("s.vxl"));
  PackSettings tiny;
  tiny.chunk_points = 7;
  pack_vxl(VxlFile::open(vxl), dir.file("s.vxlz"), tiny);
  UnpackSettings exact;
  exact.positions = PositionEncoding::Float32;  // the decoded points themselves, which the lengths and bounds are of
  exact.threads = 3;
  unpack_vxlz(dir.file("s.vxlz"), dir.file("u.vxl"), exact);
  const VxlFile f = VxlFile::open(dir.file("u.vxl"));
  ASSERT_EQ(f.streamline_lengths().size(), f.meta().streamline_count);
  ASSERT_GT(f.meta().synthetic_point_count, 0u) << "voxlines whose first point a length leaves out";
  std::uint64_t cut = 0;
  WalkCallbacks cb;
  cb.streamline = [&](std::uint64_t s, std::span<const float> xyz) {
    cut += xyz.size() / 3 > 7;  // more points than a chunk holds, in whatever order the streamlines were shipped
    EXPECT_EQ(std::bit_cast<std::uint32_t>(f.streamline_lengths()[s]),
              std::bit_cast<std::uint32_t>(stored_length_of(xyz)))
        << "streamline " << s;
  };
  walk_streamlines(f, cb);
  EXPECT_GT(cut, 250u);
  // The same lengths and bounds in a packed .vxl, its positions kept as floats for one decode or decoded twice, VERT
  // held whole or written block by block and read back for the orders: the same bytes.
  UnpackSettings packed;
  packed.threads = 3;
  const UnpackSummary kept = unpack_vxlz(dir.file("s.vxlz"), dir.file("kept.vxl"), packed);
  EXPECT_FALSE(kept.decoded_twice || kept.vertices_read_back);
  packed.memory_limit = 8 * f.meta().vertex_count;  // not the floats (12 bytes a vertex), VERT (4) within half
  const UnpackSummary held = unpack_vxlz(dir.file("s.vxlz"), dir.file("held.vxl"), packed);
  EXPECT_TRUE(held.decoded_twice && !held.vertices_read_back);
  packed.memory_limit = 1;
  const UnpackSummary read_back = unpack_vxlz(dir.file("s.vxlz"), dir.file("twice.vxl"), packed);
  EXPECT_TRUE(read_back.decoded_twice && read_back.vertices_read_back);
  EXPECT_EQ(slurp(dir.file("kept.vxl")), slurp(dir.file("held.vxl")));
  EXPECT_EQ(slurp(dir.file("kept.vxl")), slurp(dir.file("twice.vxl")));
  const VxlFile twice = VxlFile::open(dir.file("twice.vxl"));
  EXPECT_EQ(to_vector(twice.streamline_lengths()), to_vector(f.streamline_lengths()));
  for (std::size_t i = 0; i < f.voxels().size(); ++i)
    for (int c = 0; c < 3; ++c) {
      EXPECT_EQ(twice.voxels()[i].tight_min[c], f.voxels()[i].tight_min[c]);
      EXPECT_EQ(twice.voxels()[i].tight_max[c], f.voxels()[i].tight_max[c]);
    }
  // A level alone (its streamlines shipped first, cut by the chunks as the whole's are): the same lengths.
  UnpackSettings level_alone;
  level_alone.level = 1;
  level_alone.memory_limit = 1;
  unpack_vxlz(dir.file("s.vxlz"), dir.file("level.vxl"), level_alone);
  const VxlFile level = VxlFile::open(dir.file("level.vxl"));
  std::vector<float> level_lengths;
  for (std::uint64_t st = 0; st < f.meta().streamline_count; ++st)
    if (streamline_depth(st, f.level_count()) >= 1) level_lengths.push_back(f.streamline_lengths()[st]);
  EXPECT_EQ(to_vector(level.streamline_lengths()), level_lengths);
  const std::vector<float> all = f.all_vertices();
  for (const VoxelEntry& v : f.voxels())
    for (int c = 0; c < 3; ++c) {
      float lo = INFINITY, hi = -INFINITY;
      for (std::uint64_t i = v.vertex_first; i < v.vertex_first + v.vertex_count; ++i)
        lo = std::min(lo, all[3 * i + c]), hi = std::max(hi, all[3 * i + c]);
      EXPECT_EQ(v.tight_min[c], lo + 0.0f);
      EXPECT_EQ(v.tight_max[c], hi + 0.0f);
    }
}

// What a .vxl unpacked from a package will take is known from the package's tables alone (share refuses a package too
// large for the web page by it): the size of the file unpack writes, for its positions, levels and a level alone.
TEST(VxlzPackageOptions, TheUnpackedSizeIsKnownBeforeUnpacking) {
  ScratchDir dir;
  const std::string vxl = convert_for_package(test_tractogram(800), dir.file("s.vxl"));
  pack_vxl(VxlFile::open(vxl), dir.file("s.vxlz"), PackSettings{});
  const VxlzFile package = VxlzFile::open(dir.file("s.vxlz"));
  ASSERT_GT(package.pack().level_count, 1u);
  for (PositionEncoding positions : {PositionEncoding::Packed, PositionEncoding::Float32})
    for (std::uint32_t levels : {1u, kDefaultLevels})
      for (std::uint32_t level : {0u, 1u}) {
        UnpackSettings s;
        s.positions = positions;
        s.levels = levels;
        s.level = level;
        unpack_vxlz(package, dir.file("u.vxl"), s);
        EXPECT_EQ(unpacked_vxl_bytes(package, s), std::filesystem::file_size(dir.file("u.vxl")))
            << vertex_bytes(positions) << " bytes a vertex, " << levels << " levels, level " << level;
        std::filesystem::remove(dir.file("u.vxl"));
      }
}

TEST(VxlzPackageOptions, PackageBytesDoNotDependOnThreads) {
  // The measured errors in PACK are summed in chunk order, whichever thread encoded which chunk.
  ScratchDir dir;
  const VxlFile f = VxlFile::open(convert_for_package(test_tractogram(300), dir.file("s.vxl")));
  PackSettings s;
  s.chunk_points = 64;
  s.threads = 1;
  pack_vxl(f, dir.file("one.vxlz"), s);
  s.threads = 3;
  pack_vxl(f, dir.file("three.vxlz"), s);
  EXPECT_EQ(slurp(dir.file("one.vxlz")), slurp(dir.file("three.vxlz")));
}

// Unpack orders the voxels on every thread it is given, a chunk at a time (write_range_orders), and writes past the
// page cache: the file it writes, byte for byte, must not depend on the thread count, packed or float32.
TEST(VxlzPackageOptions, UnpackedBytesDoNotDependOnThreads) {
  ScratchDir dir;
  const VxlFile f = VxlFile::open(convert_for_package(test_tractogram(300), dir.file("s.vxl")));
  PackSettings pack;
  pack.chunk_points = 64;
  pack_vxl(f, dir.file("s.vxlz"), pack);
  for (PositionEncoding positions : {PositionEncoding::Packed, PositionEncoding::Float32}) {
    UnpackSettings s;
    s.positions = positions;
    s.threads = 1;
    unpack_vxlz(dir.file("s.vxlz"), dir.file("one.vxl"), s);
    s.threads = 3;
    unpack_vxlz(dir.file("s.vxlz"), dir.file("three.vxl"), s);
    EXPECT_EQ(slurp(dir.file("one.vxl")), slurp(dir.file("three.vxl"))) << static_cast<int>(positions);
    EXPECT_TRUE(verify_vxl(dir.file("three.vxl")).valid);
    std::filesystem::remove(dir.file("one.vxl"));
    std::filesystem::remove(dir.file("three.vxl"));
  }
}

TEST(VxlzPackageOptions, EmptyTractogram) {
  ScratchDir dir;
  Tractogram t;
  t.source.path = "empty.tck";
  const std::string vxl = convert_for_package(std::move(t), dir.file("empty.vxl"));
  round_trip(dir, vxl, 14);
}

// Unpack rebuilds the orders of any shared direction set: the diagonals sort by a dot product, not by one
// component as the axes do (verify checks every order's sortedness against the decoded vertices).
TEST(VxlzPackageOptions, AxisDiagOrdersAreRebuiltForTheDecodedPositions) {
  ScratchDir dir;
  const std::string vxl = convert_for_package(test_tractogram(300), dir.file("diag.vxl"), 5.0, "axis+diag");
  ASSERT_EQ(VxlFile::open(vxl).meta().stored_order_count, 7u);
  const VxlFile copy = VxlFile::open(round_trip(dir, vxl, 14));
  EXPECT_EQ(copy.meta().order_set, static_cast<std::uint32_t>(OrderSet::AxisDiag));
}

// Per-voxel random directions (VDIR) are not part of the package format: refused before any output.
TEST(VxlzPackageOptions, RandomOrderSetsAreRefusedWithoutOutput) {
  ScratchDir dir;
  const std::string vxl = convert_for_package(test_tractogram(50), dir.file("random.vxl"), 10.0, "random:4");
  try {
    pack_vxl(VxlFile::open(vxl), dir.file("r.vxlz"), {});
    ADD_FAILURE() << "packing a random:4 file must fail";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Unsupported) << e.what();
    EXPECT_NE(std::string(e.what()).find("--orders axis"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(dir.file("r.vxlz")));
}

TEST(VxlzPackageOptions, BitsOutOfRangeAreAUsageError) {
  ScratchDir dir;
  const std::string vxl = convert_for_package(test_tractogram(20), dir.file("s.vxl"));
  for (std::uint32_t bits : {10u, 17u}) {
    PackSettings s;
    s.bits = bits;
    try {
      pack_vxl(VxlFile::open(vxl), dir.file("x.vxlz"), s);
      ADD_FAILURE() << bits;
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Usage);
    }
    EXPECT_FALSE(std::filesystem::exists(dir.file("x.vxlz")));
  }
}

// Damage -----------------------------------------------------------------------------------------

class DamagedVxlz : public ::testing::Test {
 protected:
  void SetUp() override {
    Tractogram t;
    t.source.path = "small.tck";
    t.source.format = "tck";
    for (int s = 0; s < 10; ++s) {
      std::vector<float> pts;
      for (int i = 0; i < 8; ++i) pts.insert(pts.end(), {3.0f * i + s, 2.0f * s - i, 0.5f * i * s});
      t.add_streamline(pts.data(), 8);
    }
    const float jump[6] = {0, 0, 0, 40, 1, 1};
    t.add_streamline(jump, 2);
    t.groups.push_back({"g", {1, 4}});
    // Value sets, so that every damage below also reaches the PVAL and SVAL sections (spec §4.7).
    ValueSet fa{"fa", {}}, length{"length", {}};
    for (std::uint64_t i = 0; i < t.point_count(); ++i) fa.values.push_back(0.25f + 0.01f * float(i));
    for (std::uint64_t s = 0; s < t.streamline_count(); ++s) length.values.push_back(float(s) * 3.5f);
    t.point_values.push_back(fa);
    t.streamline_values.push_back(length);
    convert_for_package(std::move(t), dir.file("small.vxl"), 8);
    PackSettings s;
    s.chunk_points = 16;  // several chunks
    pack_vxl(VxlFile::open(dir.file("small.vxl")), good(), s);
  }
  std::string good() const { return dir.file("good.vxlz"); }
  std::string out() const { return dir.file("out.vxl"); }

  // Unpacking `path` must throw an Error (Input; Unsupported when a damaged byte reads as a newer
  // version) that names the file, and leave no output.
  void expect_refused(const std::string& path, const std::string& what) {
    try {
      unpack_vxlz(path, out(), {});
      ADD_FAILURE() << what << ": accepted";
    } catch (const Error& e) {
      EXPECT_TRUE(e.kind() == ErrorKind::Input || e.kind() == ErrorKind::Unsupported) << what << ": " << e.what();
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << "the message names the file: " << e.what();
    }
    EXPECT_FALSE(std::filesystem::exists(out())) << what;
  }

  // The package's content as the writer takes it, for crafted packages with valid checksums.
  VxlzContent content() const {
    const VxlzFile f = VxlzFile::open(good());
    VxlzContent c;
    c.pack = f.pack();
    c.meta = f.meta();
    c.directions = to_vector(f.directions());
    c.voxel_coords = f.inflate(section_id("VOXC"));
    c.streamline_voxlines = f.inflate(section_id("STRL"));
    c.voxline_voxels = f.inflate(section_id("VXLV"));
    c.voxline_counts = f.inflate(section_id("VXLC"));
    const auto prov = f.inflate(section_id("PROV"));
    c.provenance = std::string(prov.begin(), prov.end());
    c.groups = f.inflate(section_id("GRPS"));
    for (std::uint64_t i = 0; i < f.chunk_count(); ++i)
      c.chunks.push_back({to_vector(f.chunk(i).symbols), to_vector(f.chunk(i).escapes)});
    return c;
  }
  void expect_crafted_refused(const VxlzContent& c, const std::string& what) {
    const std::string path = dir.file("crafted.vxlz");
    write_vxlz(path, c);
    expect_refused(path, what);
  }

  ScratchDir dir;
};

TEST_F(DamagedVxlz, TheGoodPackageUnpacks) {
  unpack_vxlz(good(), out(), {});
  EXPECT_TRUE(verify_vxl(out()).valid);
  EXPECT_TRUE(VxlzFile::open(good()).has_section(section_id("PVAL")) &&
              VxlzFile::open(good()).has_section(section_id("SVAL")));
  EXPECT_EQ(VxlFile::open(out()).vertex_values().size(), 1u);
  EXPECT_GT(VxlzFile::open(good()).chunk_count(), 3u);
}

TEST_F(DamagedVxlz, EverySingleByteChangeIsRefused) {
  const std::vector<char> bytes = slurp(good());
  ASSERT_GT(bytes.size(), 500u);
  const std::string bad = dir.file("bad.vxlz");
  for (std::size_t pos = 0; pos < bytes.size(); ++pos) {
    std::vector<char> b = bytes;
    b[pos] = static_cast<char>(b[pos] ^ (1 + pos % 255));
    dump_bytes(bad, b, b.size());
    SCOPED_TRACE(pos);
    expect_refused(bad, "byte " + std::to_string(pos));
    if (HasFailure()) break;
  }
}

TEST_F(DamagedVxlz, EveryTruncationIsRefused) {
  const std::vector<char> bytes = slurp(good());
  const std::string bad = dir.file("bad.vxlz");
  for (std::size_t n = 0; n < bytes.size(); ++n) {
    dump_bytes(bad, bytes, n);
    expect_refused(bad, "truncated to " + std::to_string(n));
    if (HasFailure()) break;
  }
  std::vector<char> longer = bytes;
  longer.push_back(0);
  dump_bytes(bad, longer, longer.size());
  expect_refused(bad, "one byte appended");
}

TEST_F(DamagedVxlz, DamageBehindValidChecksumsNeverCrashes) {
  // Every payload byte changed, checksums recomputed: the zlib, varint and Draco decoders and the
  // structure checks see the damage. Each package is refused with an Error or, where the change is
  // still a meaningful package (a different residual, say), unpacks to a file that verify accepts.
  const std::vector<char> bytes = slurp(good());
  FileHeader h;
  std::memcpy(&h, bytes.data(), sizeof h);
  const std::size_t payloads = sizeof h + h.section_count * sizeof(SectionEntry);
  const std::string bad = dir.file("bad.vxlz");
  std::size_t refused = 0, accepted = 0;
  for (std::size_t pos = payloads; pos < bytes.size(); ++pos) {
    std::vector<char> b = bytes;
    b[pos] = static_cast<char>(b[pos] ^ (pos % 2 ? 0x80 : 0x01));  // the lowest or the highest bit
    test::reseal_checksums(b.data(), b.size());
    dump_bytes(bad, b, b.size());
    // VERT held whole or written block by block: the same outcome, and the same bytes where it is accepted.
    std::optional<std::vector<char>> unpacked[2];
    for (const bool blocks : {false, true}) {
      UnpackSettings settings;
      settings.vertex_blocks = blocks;
      try {
        unpack_vxlz(bad, out(), settings);
        const VerifyResult r = verify_vxl(out());
        EXPECT_TRUE(r.valid) << "byte " << pos << ": " << r.problem;
        unpacked[blocks] = slurp(out());
        std::filesystem::remove(out());
      } catch (const Error&) {
        EXPECT_FALSE(std::filesystem::exists(out()));
      }
    }
    EXPECT_EQ(unpacked[0], unpacked[1]) << "byte " << pos;
    ++(unpacked[0] ? accepted : refused);
  }
  EXPECT_GT(refused, 0u);
  EXPECT_GT(accepted, 0u);
}

// Found by fuzz_vxlz: a Draco stream whose point count is damaged behind valid checksums, which would make
// Draco allocate 6 GB, is refused before Draco decodes anything.
TEST_F(DamagedVxlz, ADracoPointCountBeyondTheChunkIsRefusedBeforeDecoding) {
  std::vector<char> bytes = slurp(good());
  const std::string magic = "DRACO";
  std::size_t clouds = 0;
  for (auto at = std::search(bytes.begin(), bytes.end(), magic.begin(), magic.end()); at != bytes.end();
       at = std::search(at + 1, bytes.end(), magic.begin(), magic.end())) {
    // The sequential point cloud's int32 point count follows the 11-byte header (magic, version,
    // encoder type and method, flags).
    std::vector<char> b = bytes;
    const std::int32_t huge = 1 << 29;
    std::memcpy(b.data() + (at - bytes.begin()) + 11, &huge, sizeof huge);
    test::reseal_checksums(b.data(), b.size());
    dump_bytes(dir.file("count.vxlz"), b, b.size());
    expect_refused(dir.file("count.vxlz"), "Draco point count at byte " + std::to_string(at - bytes.begin()));
    try {
      unpack_vxlz(dir.file("count.vxlz"), out(), {});
    } catch (const Error& e) {  // refused by the check before decoding, not by Draco or after it
      EXPECT_NE(std::string(e.what()).find("states 536870912 points"), std::string::npos) << e.what();
    }
    ++clouds;
  }
  EXPECT_GT(clouds, 1u) << "the package must hold several Draco clouds";
}

TEST_F(DamagedVxlz, OtherMajorVersionsAreUnsupported) {
  // 1.0 coded positions differently (no joint symbols): its packages are refused with a hint, never misread.
  for (const std::uint8_t version : {1, 3}) {
    std::vector<char> b = slurp(good());
    b[8] = static_cast<char>(version);
    dump_bytes(dir.file("other.vxlz"), b, b.size());
    try {
      unpack_vxlz(dir.file("other.vxlz"), out(), {});
      ADD_FAILURE() << int(version);
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Unsupported);
      EXPECT_NE(std::string(e.what()).find("major version " + std::to_string(version)), std::string::npos) << e.what();
      if (version == 1) {
        EXPECT_NE(std::string(e.what()).find("pack the .vxl again"), std::string::npos) << e.what();
      }
    }
    EXPECT_FALSE(std::filesystem::exists(out()));
  }
}

TEST_F(DamagedVxlz, CraftedPackagesWithValidChecksumsAreRefused) {
  // The checksums catch damage; these packages are consistent byte-wise but wrong in meaning.
  {
    VxlzContent c = content();
    c.pack.quantization_bits = 17;
    expect_crafted_refused(c, "17 bits");
  }
  {
    VxlzContent c = content();
    c.pack.chunk_count += 1;
    expect_crafted_refused(c, "chunk count");
  }
  {
    VxlzContent c = content();
    c.meta.voxline_count += 1;
    expect_crafted_refused(c, "voxline count");
  }
  {
    VxlzContent c = content();
    c.meta.vertex_count += 1;
    expect_crafted_refused(c, "vertex count");
  }
  {
    VxlzContent c = content();
    c.meta.voxline_count = std::uint64_t(1) << 60;  // must not allocate for it
    expect_crafted_refused(c, "huge voxline count");
  }
  {
    VxlzContent c = content();
    c.voxline_voxels[0] = 0x7F;  // a voxel index far past the table
    expect_crafted_refused(c, "voxel index");
  }
  {
    VxlzContent c = content();
    c.voxline_counts.push_back(2);  // a value after the expected ones
    expect_crafted_refused(c, "trailing value");
  }
  {
    VxlzContent c = content();
    c.voxline_counts[0] = 1;  // own count 0
    expect_crafted_refused(c, "empty voxline");
  }
  {
    VxlzContent c = content();
    c.voxel_coords.assign(c.voxel_coords.size(), 0);  // every voxel at (0, 0, 0): not increasing
    expect_crafted_refused(c, "voxel order");
  }
  {
    VxlzContent c = content();
    c.chunks[0] = encode_residual_chunk(std::vector<std::int32_t>(3 * (c.pack.chunk_points - 1), 0), c.pack.joint_bits);
    expect_crafted_refused(c, "chunk with one point too few");
  }
  {
    VxlzContent c = content();
    std::vector<std::int32_t> huge(3 * c.pack.chunk_points, 1 << 17);  // decodes outside the grid
    c.chunks[0] = encode_residual_chunk(huge, c.pack.joint_bits);
    expect_crafted_refused(c, "residuals off the grid");
  }
  {
    VxlzContent c = content();
    c.chunks[1].symbols.resize(c.chunks[1].symbols.size() / 2);  // a truncated Draco buffer
    expect_crafted_refused(c, "truncated chunk");
  }
  for (std::uint32_t t : {0u, 6u}) {
    VxlzContent c = content();
    c.pack.joint_bits = t;
    expect_crafted_refused(c, "joint bits " + std::to_string(t));
  }
  {
    // Symbols of a wider t than PACK states name no triplet.
    VxlzContent c = content();
    std::vector<std::int32_t> wide(3 * c.pack.chunk_points, 7);
    c.chunks[0] = encode_residual_chunk(wide, kVxlzMaxJointBits);
    c.pack.joint_bits = 2;
    expect_crafted_refused(c, "symbol out of range");
  }
  {
    VxlzContent c = content();
    std::vector<std::int32_t> escaping(3 * c.pack.chunk_points, 1000);
    const EncodedChunk e = encode_residual_chunk(escaping, c.pack.joint_bits);
    ASSERT_FALSE(e.escapes.empty());
    c.chunks[0].symbols = e.symbols;  // escapes missing
    c.chunks[0].escapes.clear();
    expect_crafted_refused(c, "escapes missing");
    c.chunks[0].escapes = encode_residual_chunk(std::vector<std::int32_t>(3 * (c.pack.chunk_points - 1), 1000),
                                                c.pack.joint_bits)
                              .escapes;  // one escape too few
    expect_crafted_refused(c, "escapes short");
  }
  {
    VxlzContent c = content();
    const std::vector<std::int32_t> small(3 * c.pack.chunk_points, 0);
    c.chunks[0] = encode_residual_chunk(small, c.pack.joint_bits);
    c.chunks[0].escapes = encode_residual_chunk(std::vector<std::int32_t>(3, 1000), c.pack.joint_bits).escapes;
    expect_crafted_refused(c, "escapes without escaped points");
  }
  {
    VxlzContent c = content();
    c.groups = encode_group_stream(std::vector<StreamlineGroup>{{"g", {3, 2}}});  // not increasing
    expect_crafted_refused(c, "group order");
  }
  {
    VxlzContent c = content();
    c.provenance = "[1, 2]";
    expect_crafted_refused(c, "provenance not an object");
  }
}

// A group or value-set name that is not UTF-8, behind valid checksums: the .vxl requires UTF-8 names (its spec §7
// step 3), so the package is refused rather than unpacked into a file that `open` would refuse.
TEST_F(DamagedVxlz, NamesThatAreNotUtf8AreRefused) {
  {
    VxlzContent c = content();
    c.groups = encode_group_stream(std::vector<StreamlineGroup>{{"g\xFF", {1, 4}}});
    expect_crafted_refused(c, "group name");
  }
  // The value-set names lie raw in PVAL and SVAL (spec §4.7): "fa" and "length" as the writer stored them.
  for (const std::string name : {std::string("fa\0", 3), std::string("length\0", 7)}) {
    std::vector<char> b = slurp(good());
    const auto at = std::search(b.begin(), b.end(), name.begin(), name.end());
    ASSERT_NE(at, b.end()) << name.c_str();
    at[1] = static_cast<char>(0xC0);  // a lead byte followed by a NUL
    test::reseal_checksums(b.data(), b.size());
    dump_bytes(dir.file("names.vxlz"), b, b.size());
    expect_refused(dir.file("names.vxlz"), name.c_str());
    try {
      unpack_vxlz(dir.file("names.vxlz"), out(), {});
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("UTF-8"), std::string::npos) << e.what();
    }
  }
}

// A package's META whose bounds, origin, voxel size or grid dimensions contradict each other, written with
// valid checksums: refused when the package is opened (so by unpack and info), as the same fields are in a .vxl.
TEST_F(DamagedVxlz, MetaFieldsThatContradictTheGridAreRefusedOnOpen) {
  struct Case {
    const char* name;
    std::function<void(MetaSection&)> damage;
    const char* message;
  };
  const std::vector<Case> cases = {
      {"bounds max at 1e308", [](MetaSection& m) { m.bounds_max[0] = 1e308; }, "grid_dims on x is"},
      {"origin at 1e308", [](MetaSection& m) { m.grid_origin[1] = 1e308; }, "grid origin is not at bounds_min on y"},
      {"voxel size 1e30", [](MetaSection& m) { m.voxel_size = 1e30; }, "the bounds and voxel size make"},
      {"voxel size 1e-30", [](MetaSection& m) { m.voxel_size = 1e-30; }, "the bounds and voxel size make"},
      {"grid dims 2^30", [](MetaSection& m) { m.grid_dims[2] = 1 << 30; }, "grid_dims on z is 1073741824"},
      {"bounds min above max", [](MetaSection& m) { std::swap(m.bounds_min[0], m.bounds_max[0]); },
       "bounds_min above bounds_max on x"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    VxlzContent crafted = content();
    c.damage(crafted.meta);
    const std::string path = dir.file("crafted.vxlz");
    write_vxlz(path, crafted);
    try {
      (void)VxlzFile::open(path);
      ADD_FAILURE() << "opened";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Input) << e.what();
      EXPECT_NE(std::string(e.what()).find(c.message), std::string::npos) << e.what();
    }
    expect_refused(path, c.name);
    EXPECT_EQ(test::run_cli("info '" + path + "'").exit_code, 3);
  }
}

// A grid one voxel larger than its voxels passes open's rule (a voxel of slack) but not the package's voxels: the
// unpacked file would be one verify refuses, so unpack refuses the package, naming the axis.
TEST_F(DamagedVxlz, AGridLargerThanItsVoxelsIsRefusedBeforeDecoding) {
  for (int c = 0; c < 3; ++c) {
    VxlzContent crafted = content();
    ++crafted.meta.grid_dims[c];
    const std::string path = dir.file("crafted.vxlz");
    write_vxlz(path, crafted);
    (void)VxlzFile::open(path);  // within open's slack
    try {
      unpack_vxlz(path, out(), {});
      ADD_FAILURE() << "axis " << c << ": accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Input) << e.what();
      EXPECT_NE(std::string(e.what()).find(std::string("voxel coordinates on ") + "xyz"[c] + " run from 0 to"),
                std::string::npos)
          << e.what();
    }
    EXPECT_FALSE(std::filesystem::exists(out()));
  }
}

TEST_F(DamagedVxlz, CliReportsDamageWithExitCode3) {
  std::vector<char> b = slurp(good());
  b[b.size() / 2] ^= 0x10;
  dump_bytes(dir.file("bad.vxlz"), b, b.size());
  const auto r = test::run_cli("unpack '" + dir.file("bad.vxlz") + "' '" + out() + "'");
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("bad.vxlz"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("checksum mismatch"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(out()));
}

// The command line and real data ----------------------------------------------------------------

// Unpacked with no --levels, a package gives back the levels of the file it was packed from (level order: PACK's;
// streamline order: those its conversion asked for); --levels chooses others.
TEST(VxlzPackCli, UnpackKeepsThePackagesLevels) {
  ScratchDir dir;
  ASSERT_EQ(test::run_cli("synth '" + dir.file("s.tck") + "' --streamlines 300").exit_code, 0);
  const auto unpacked_levels = [&](const std::string& convert_levels, const std::string& unpack_options) {
    const std::string vxl = dir.file("s.vxl"), vxlz = dir.file("s.vxlz"), out = dir.file("u.vxl");
    EXPECT_EQ(test::run_cli("convert '" + dir.file("s.tck") + "' '" + vxl + "' --levels " + convert_levels).exit_code,
              0);
    EXPECT_EQ(test::run_cli("pack '" + vxl + "' '" + vxlz + "'").exit_code, 0);
    const auto r = test::run_cli("unpack '" + vxlz + "' '" + out + "'" + unpack_options);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return VxlFile::open(out).meta().level_count;
  };
  EXPECT_EQ(unpacked_levels("3", ""), 3u);
  EXPECT_EQ(unpacked_levels("5", ""), 5u);
  EXPECT_EQ(unpacked_levels("1", ""), 0u);  // one level: level_count 0
  EXPECT_EQ(unpacked_levels("3", " --levels 2"), 2u);
  EXPECT_EQ(unpacked_levels("1", " --levels 4"), 4u);
}

// `verify` of a package checks it in full (its own checks, every chunk decoded, the .vxl it unpacks to), finds a
// damaged one invalid (exit 1), and a file that is not there is one it cannot read (exit 3), not an invalid one.
TEST(VxlzPackCli, VerifyChecksAPackageInFull) {
  ScratchDir dir;
  const std::string vxl = convert_for_package(test_tractogram(100), dir.file("s.vxl"));
  ASSERT_EQ(test::run_cli("pack '" + vxl + "' '" + dir.file("s.vxlz") + "'").exit_code, 0);
  auto r = test::run_cli("verify '" + dir.file("s.vxlz") + "'");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("s.vxlz: valid"), std::string::npos) << r.output;
  std::vector<char> b = slurp(dir.file("s.vxlz"));
  b[b.size() / 2] ^= 0x10;
  dump_bytes(dir.file("bad.vxlz"), b, b.size());
  r = test::run_cli("verify '" + dir.file("bad.vxlz") + "'");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("bad.vxlz: INVALID: "), std::string::npos) << r.output;
  r = test::run_cli("verify '" + dir.file("missing.vxl") + "'");
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("missing.vxl: cannot be read"), std::string::npos) << r.output;
  for (const auto& e : std::filesystem::directory_iterator(dir.path()))
    EXPECT_TRUE(e.path().extension() == ".vxl" || e.path().extension() == ".vxlz") << "left behind: " << e.path();
}

TEST(VxlzPackCli, PackUnpackVerify) {
  ScratchDir dir;
  const std::string vxl = convert_for_package(test_tractogram(100), dir.file("s.vxl"));
  auto r = test::run_cli("pack '" + vxl + "' '" + dir.file("s.vxlz") + "' --bits 11");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("error bound"), std::string::npos) << r.output;
  r = test::run_cli("unpack '" + dir.file("s.vxlz") + "' '" + dir.file("u.vxl") + "'");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = test::run_cli("verify '" + dir.file("u.vxl") + "'");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  // A memory limit the decoded positions do not fit: the package decoded twice, the same bytes; a limit that is not a
  // size of memory is a usage error.
  r = test::run_cli("unpack '" + dir.file("s.vxlz") + "' '" + dir.file("twice.vxl") + "' --memory-limit 1K --verbose");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("decoded twice"), std::string::npos) << r.output;
  EXPECT_EQ(slurp(dir.file("u.vxl")), slurp(dir.file("twice.vxl")));
  r = test::run_cli("unpack '" + dir.file("s.vxlz") + "' '" + dir.file("x.vxl") + "' --memory-limit lots");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("is not a memory size"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir.file("x.vxl")));
  r = test::run_cli("pack '" + vxl + "' '" + dir.file("t.vxlz") + "' --bits 9");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  r = test::run_cli("unpack '" + vxl + "' '" + dir.file("w.vxl") + "'");  // a .vxl is not a package
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("not a .vxlz package"), std::string::npos) << r.output;
}

// info reads a package from its tables: the .vxl's counts, the quantisation asked for, and, shipped level by level,
// each level's streamlines (those of depth >= level) and the prefix that holds them; shipped in streamline order
// (a file without levels), no levels. A damaged package is refused as unpack refuses it.
TEST(VxlzPackCli, InfoSummarisesAPackage) {
  ScratchDir dir;
  const std::string vxl = convert_for_package(test_tractogram(800), dir.file("s.vxl"));
  ASSERT_EQ(test::run_cli("pack '" + vxl + "' '" + dir.file("s.vxlz") + "' --bits 12").exit_code, 0);
  const test::CommandResult text = test::run_cli("info '" + dir.file("s.vxlz") + "'");
  ASSERT_EQ(text.exit_code, 0) << text.output;
  EXPECT_NE(text.output.find(".vxlz 2.4"), std::string::npos) << text.output;
  EXPECT_NE(text.output.find("12 bits per axis"), std::string::npos) << text.output;
  EXPECT_NE(text.output.find("level by level"), std::string::npos) << text.output;
  const test::CommandResult json = test::run_cli("info --json '" + dir.file("s.vxlz") + "'");
  ASSERT_EQ(json.exit_code, 0) << json.output;
  const auto j = nlohmann::json::parse(json.output);
  const VxlFile f = VxlFile::open(vxl);
  EXPECT_EQ(j["format"], "vxlz");
  EXPECT_EQ(j["streamlines"].get<std::uint64_t>(), f.meta().streamline_count);
  EXPECT_EQ(j["points"].get<std::uint64_t>(), f.meta().point_count);
  EXPECT_EQ(j["positions"]["quantization_bits"].get<std::uint32_t>(), 12u);
  EXPECT_GT(j["positions"]["error_bound_mm"].get<double>(), 0);
  EXPECT_EQ(j["shipping_order"], "level");
  EXPECT_TRUE(j["chunks"]["checksums"].get<bool>());
  ASSERT_EQ(j["levels"].size(), f.level_count());
  std::uint64_t previous_bytes = 0;
  for (const auto& level : j["levels"]) {  // the coarsest first
    const std::uint32_t d = level["level"].get<std::uint32_t>();
    std::uint64_t in_level = 0;
    for (std::uint64_t s = 0; s < f.meta().streamline_count; ++s) in_level += streamline_depth(s, f.level_count()) >= d;
    EXPECT_EQ(level["streamlines"].get<std::uint64_t>(), in_level) << d;
    EXPECT_GE(level["bytes"].get<std::uint64_t>(), previous_bytes) << d;
    previous_bytes = level["bytes"].get<std::uint64_t>();
  }
  EXPECT_EQ(previous_bytes, std::filesystem::file_size(dir.file("s.vxlz")));  // level 0: the whole package
  ASSERT_EQ(test::run_cli("unpack '" + dir.file("s.vxlz") + "' '" + dir.file("u.vxl") + "'").exit_code, 0);
  EXPECT_EQ(j["unpacked_bytes"].get<std::uint64_t>(), std::filesystem::file_size(dir.file("u.vxl")));
  EXPECT_NE(
      text.output.find("makes a .vxl of " + std::to_string(std::filesystem::file_size(dir.file("u.vxl"))) + " bytes"),
      std::string::npos)
      << text.output;

  ConvertSettings one_level;
  one_level.levels = 1;
  convert_tractogram(test_tractogram(200), dir.file("flat.vxl"), one_level);
  ASSERT_EQ(test::run_cli("pack '" + dir.file("flat.vxl") + "' '" + dir.file("flat.vxlz") + "'").exit_code, 0);
  const auto flat = nlohmann::json::parse(test::run_cli("info --json '" + dir.file("flat.vxlz") + "'").output);
  EXPECT_EQ(flat["shipping_order"], "streamline");
  EXPECT_FALSE(flat["chunks"]["checksums"].get<bool>());
  EXPECT_FALSE(flat.contains("levels"));

  std::vector<char> bytes = slurp(dir.file("s.vxlz"));
  bytes[bytes.size() / 2] ^= 0x10;
  dump_bytes(dir.file("bad.vxlz"), bytes, bytes.size());
  const test::CommandResult bad = test::run_cli("info '" + dir.file("bad.vxlz") + "'");
  EXPECT_EQ(bad.exit_code, 3) << bad.output;
  EXPECT_NE(bad.output.find("checksum mismatch"), std::string::npos) << bad.output;
}

TEST(VxlzPackageReal, StrokeAndAfqRoundTrip) {
  VXL_REQUIRE_REAL_DATA();
  ScratchDir dir;
  for (const char* name : {"TractographyFormat__stroke.tck",
                           "niivue__sub-01_ses-01_dwi_space-RASMM_model-probCSD_algo-AFQ_tractography.trx",
                           "niivue__C_PHP.trk.gz", "mrtrix3__tmp.tck", "nibabel__empty.tck"}) {
    SCOPED_TRACE(name);
    const std::string vxl = convert_for_package(read_tractogram(test::real(name)), dir.file("real.vxl"));
    for (std::uint32_t bits : {11u, 14u, 16u}) round_trip(dir, vxl, bits);
  }
}

}  // namespace
}  // namespace vxl

namespace vxl {
namespace {

// `unpack` packs the positions it writes again by default: the bound it prints must cover both steps, as
// measured between the .vxl that was packed and the unpacked one.
TEST(VxlzPackageOptions, UnpackPrintsABoundThatHoldsForWhatItWrote) {
  ScratchDir dir;
  const std::string vxl = convert_for_package(test_tractogram(), dir.file("s.vxl"));
  ASSERT_EQ(test::run_cli("pack " + test::q(vxl) + " " + test::q(dir.file("s.vxlz"))).exit_code, 0);
  const VxlFile original = VxlFile::open(vxl);
  auto printed_bound = [](const std::string& output) {
    const std::size_t at = output.find("positions within ");
    EXPECT_NE(at, std::string::npos) << output;
    return at == std::string::npos ? 0.0 : std::stod(output.substr(at + 17));
  };
  for (const char* positions : {"packed", "float32"}) {
    SCOPED_TRACE(positions);
    const std::string out = dir.file(std::string("u_") + positions + ".vxl");
    const auto r =
        test::run_cli("unpack " + test::q(dir.file("s.vxlz")) + " " + test::q(out) + " --positions " + positions);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const double bound = printed_bound(r.output);
    const double error = max_vertex_error(original, VxlFile::open(out));
    EXPECT_LE(error, bound) << r.output;
    const UnpackSummary s = unpack_vxlz(dir.file("s.vxlz"), dir.file("again.vxl"), [&] {
      UnpackSettings u;
      u.positions = std::string(positions) == "packed" ? PositionEncoding::Packed : PositionEncoding::Float32;
      return u;
    }());
    if (std::string(positions) == "packed") {
      EXPECT_GT(s.repack_error_bound, 0.0);
      EXPECT_GT(error, s.pack.error_bound) << "re-packing moves points beyond the package's own bound";
    } else {
      EXPECT_EQ(s.repack_error_bound, 0.0);
    }
    EXPECT_NEAR(bound, s.error_bound(), 1e-6) << r.output;
  }
}

}  // namespace
}  // namespace vxl
