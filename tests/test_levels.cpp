// Levels of detail (spec §5.12, §6.5): which streamlines a level holds, that each level of a voxel is a
// prefix of its block holding exactly those streamlines' voxlines, that each level's orders are its
// segments in back-to-front order, and that every writer (in memory, streamed, unpacked) agrees.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "converter/convert/convert.h"
#include "converter/convert/streaming_convert.h"
#include "converter/export/tck_writer.h"
#include "converter/package/pack.h"
#include "converter/package/unpack.h"
#include "converter/synth/synth.h"
#include "format/base/error.h"
#include "format/vxl_file.h"
#include "format/vxl_levels.h"
#include "format/vxl_streamlines.h"
#include "format/vxl_verify.h"
#include "tests/reseal_checksums.h"
#include "tests/test_support.h"

namespace vxl {
namespace {

using test::ScratchDir;

// The hash is part of the format: a second implementation must find the same depths (spec §6.5).
TEST(Levels, DepthsArePinnedByTheSpec) {
  for (std::uint64_t i : {0, 1, 2, 3, 4, 5, 7, 28}) EXPECT_EQ(streamline_depth(i, 8), 0u) << i;
  EXPECT_EQ(streamline_depth(6, 8), 4u);
  for (std::uint64_t i : {29, 33, 38, 43}) EXPECT_EQ(streamline_depth(i, 8), 1u) << i;
  for (std::uint64_t i : {149, 155, 160, 209}) EXPECT_EQ(streamline_depth(i, 8), 2u) << i;
  for (std::uint64_t i : {575, 1625, 2028, 2565}) EXPECT_EQ(streamline_depth(i, 8), 3u) << i;
  // Capped at the file's deepest level.
  EXPECT_EQ(streamline_depth(6, 3), 2u);
  EXPECT_EQ(streamline_depth(6, 1), 0u);
}

TEST(Levels, EachLevelHoldsAnEighthOfTheNextFinerOne) {
  std::uint64_t at_least[8] = {};
  const std::uint64_t n = 1 << 22;
  for (std::uint64_t i = 0; i < n; ++i)
    for (std::uint32_t d = 0; d <= streamline_depth(i, 8); ++d) ++at_least[d];
  EXPECT_EQ(at_least[0], n);
  for (std::uint32_t d = 1; d < 6; ++d) {
    const double expected = double(at_least[d - 1]) / kLevelRatio;
    EXPECT_NEAR(double(at_least[d]), expected, 5 * std::sqrt(expected)) << "level " << d;
  }
}

Tractogram synth(std::uint64_t streamlines) {
  Tractogram t = synthesize_tractogram({streamlines, 3});
  t.source.path = "synth.tck";
  return t;
}

ConvertSettings exact_settings(std::uint32_t levels) {
  ConvertSettings s;
  s.voxel_size = 10;
  s.levels = levels;
  s.positions = PositionEncoding::Float32;  // orders compared by exact keys below
  s.threads = 2;
  return s;
}

// Every voxline lies in its voxel's block after the deeper streamlines' voxlines and before the
// shallower ones': level d of a voxel is the prefix holding the streamlines of depth >= d.
TEST(Levels, EachLevelIsAPrefixHoldingItsStreamlines) {
  ScratchDir dir;
  const std::string out = dir.file("l4.vxl");
  convert_tractogram(synth(6000), out, exact_settings(4));
  const VerifyResult verified = verify_vxl(out);
  ASSERT_TRUE(verified.valid) << verified.problem;
  const VxlFile f = VxlFile::open(out);
  ASSERT_EQ(f.level_count(), 4u);
  EXPECT_EQ(f.header().version_major, 2);
  EXPECT_EQ(f.header().version_minor, 4);  // streamline lengths (spec §10)

  std::uint64_t checked = 0, streamline = 0;
  const auto strm = f.streamline_first_voxline();
  std::uint64_t voxline = 0;
  WalkCallbacks cb;
  cb.voxline = [&](const VoxlineVisit& visit) {
    const std::uint32_t voxel = visit.voxel;
    const std::uint64_t first = visit.first_vertex;
    const std::uint32_t own = visit.own_points;
    const bool connected = visit.connected;
    while (strm[streamline + 1] <= voxline) ++streamline;
    const std::uint32_t depth = streamline_depth(streamline, 4);
    const VoxelEntry& v = f.voxels()[voxel];
    const std::uint64_t begin = first - v.vertex_first, end = begin + own + (connected ? 1 : 0);
    EXPECT_LE(end, f.level(voxel, depth).vertex_count) << "voxline " << voxline;
    if (depth + 1 < f.level_count()) {
      EXPECT_GE(begin, f.level(voxel, depth + 1).vertex_count) << "voxline " << voxline;
    }
    ++voxline;
    ++checked;
  };
  walk_streamlines(f, cb);
  EXPECT_EQ(checked, f.meta().voxline_count);

  // Segment totals per level follow the streamlines kept (1/8 each, within sampling noise).
  std::uint64_t segments[4] = {};
  for (std::size_t i = 0; i < f.voxels().size(); ++i)
    for (std::uint32_t d = 0; d < 4; ++d) segments[d] += f.level(i, d).segment_count;
  EXPECT_EQ(segments[0], f.meta().segment_count);
  for (std::uint32_t d = 1; d < 3; ++d) {
    EXPECT_GT(segments[d], segments[d - 1] / 16) << "level " << d;
    EXPECT_LT(segments[d], segments[d - 1] / 4) << "level " << d;
  }
}

// A level's order is the full order with the other levels' segments left out: the same back-to-front
// sequence for the streamlines it keeps (keys and ties do not depend on the level).
TEST(Levels, LevelOrdersAreTheFullOrdersRestrictedToTheLevel) {
  ScratchDir dir;
  const std::string out = dir.file("l3.vxl");
  convert_tractogram(synth(6000), out, exact_settings(3));
  const VxlFile f = VxlFile::open(out);
  std::uint64_t compared = 0;
  for (std::size_t i = 0; i < f.voxels().size(); ++i)
    for (std::uint32_t d = 1; d < f.level_count(); ++d) {
      const LevelEntry level = f.level(i, d);
      for (std::uint32_t k = 0; k < f.meta().stored_order_count; ++k) {
        const OrderView full = f.order(i, k, 0), coarse = f.order(i, k, d);
        ASSERT_EQ(coarse.count, level.segment_count);
        EXPECT_EQ(coarse.bits, order_entry_bits(level.vertex_count, OrderPacking::Bits));
        std::vector<std::uint32_t> expected, got;
        for (std::uint32_t n = 0; n < full.count; ++n)
          if (full[n] < level.vertex_count) expected.push_back(full[n]);
        for (std::uint32_t n = 0; n < coarse.count; ++n) got.push_back(coarse[n]);
        ASSERT_EQ(got, expected) << "voxel " << i << " level " << d << " order " << k;
        compared += got.size();
      }
    }
  EXPECT_GT(compared, 1000u);
}

TEST(Levels, OneLevelWritesNoLods) {
  ScratchDir dir;
  ConvertSettings settings;
  settings.levels = 1;
  convert_tractogram(synth(300), dir.file("one.vxl"), settings);
  const VxlFile f = VxlFile::open(dir.file("one.vxl"));
  EXPECT_EQ(f.level_count(), 1u);
  EXPECT_EQ(f.meta().level_count, 0u);
  EXPECT_EQ(f.find_section(section_id("LODS")), nullptr);
  EXPECT_EQ(f.header().version_major, 2);  // packed positions
  EXPECT_EQ(f.header().version_minor, 4);  // streamline lengths, with or without levels (spec §10)
  EXPECT_TRUE(verify_vxl(dir.file("one.vxl")).valid);
  EXPECT_THROW(convert_tractogram(synth(10), dir.file("nine.vxl"),
                                  [] {
                                    ConvertSettings s;
                                    s.levels = kMaxLevels + 1;
                                    return s;
                                  }()),
               Error);
  EXPECT_FALSE(std::filesystem::exists(dir.file("nine.vxl")));
}

std::vector<char> section_bytes(const VxlFile& f, const char (&id)[5]) {
  const SectionEntry* e = f.find_section(section_id(id));
  if (!e) return {};
  return {f.bytes().begin() + static_cast<std::ptrdiff_t>(e->offset),
          f.bytes().begin() + static_cast<std::ptrdiff_t>(e->offset + e->size)};
}

// The three writers place the same voxlines in the same places: the streamed conversion (which sees each
// streamline once per range) and the unpacker (which rebuilds the blocks from a package) give the same
// LODS and voxline placement as the conversion in memory.
TEST(Levels, StreamedAndUnpackedFilesHaveTheSameLevels) {
  ScratchDir dir;
  const std::string tck = dir.file("s.tck");
  {
    Tractogram t = synth(3000);
    TckWriter w(tck, t.streamline_count());
    for (std::uint64_t i = 0; i < t.streamline_count(); ++i)
      w.add({t.positions.data() + 3 * t.offsets[i], 3 * (t.offsets[i + 1] - t.offsets[i])});
    w.finish();
  }
  ConvertSettings settings;
  settings.voxel_size = 6;
  convert_streaming(tck, dir.file("streamed.vxl"), [&] {
    ConvertSettings s = settings;
    s.memory_limit = 24ull << 20;
    return s;
  }());
  convert_tractogram(synth(3000), dir.file("memory.vxl"), settings);
  const VxlFile memory = VxlFile::open(dir.file("memory.vxl")), streamed = VxlFile::open(dir.file("streamed.vxl"));
  ASSERT_EQ(memory.level_count(), kDefaultLevels);
  EXPECT_FALSE(section_bytes(memory, "LODS").empty());
  EXPECT_EQ(section_bytes(memory, "LODS"), section_bytes(streamed, "LODS"));
  EXPECT_EQ(section_bytes(memory, "ORDB"), section_bytes(streamed, "ORDB"));
  EXPECT_EQ(section_bytes(memory, "VXIX"), section_bytes(streamed, "VXIX"));
  EXPECT_EQ(section_bytes(memory, "SLEN").size(), 4u * 3000);
  EXPECT_EQ(section_bytes(memory, "SLEN"), section_bytes(streamed, "SLEN"));

  PackSettings pack;
  pack.threads = 2;
  pack_vxl(memory, dir.file("p.vxlz"), pack);
  UnpackSettings unpack;
  unpack.threads = 2;
  unpack_vxlz(dir.file("p.vxlz"), dir.file("unpacked.vxl"), unpack);
  const VxlFile unpacked = VxlFile::open(dir.file("unpacked.vxl"));
  EXPECT_EQ(section_bytes(memory, "LODS"), section_bytes(unpacked, "LODS"));
  EXPECT_EQ(section_bytes(memory, "VXLN"), section_bytes(unpacked, "VXLN"));
  const VerifyResult verified = verify_vxl(dir.file("unpacked.vxl"));
  EXPECT_TRUE(verified.valid) << verified.problem;

  unpack.levels = kMaxLevels + 1;
  EXPECT_THROW(unpack_vxlz(dir.file("p.vxlz"), dir.file("nine.vxl"), unpack), Error);
  EXPECT_FALSE(std::filesystem::exists(dir.file("nine.vxl")));
  unpack.levels = 1;
  unpack_vxlz(dir.file("p.vxlz"), dir.file("one.vxl"), unpack);
  EXPECT_EQ(VxlFile::open(dir.file("one.vxl")).level_count(), 1u);
  EXPECT_TRUE(verify_vxl(dir.file("one.vxl")).valid);
}

// verify checks every level's orders: a coarse order out of sort is caught (behind valid checksums).
TEST(Levels, VerifyRefusesACoarseOrderOutOfSort) {
  ScratchDir dir;
  const std::string out = dir.file("l.vxl");
  convert_tractogram(synth(6000), out, exact_settings(3));
  std::vector<char> bytes = test::slurp(out);
  std::uint64_t at = 0;
  std::uint32_t bits = 0, first = 0, second = 0;
  {
    const VxlFile f = VxlFile::open(out);
    for (std::size_t i = 0; i < f.voxels().size() && at == 0; ++i) {
      const OrderView o = f.order(i, 0, 1);
      if (o.count >= 2)
        at = static_cast<std::uint64_t>(o.data - f.bytes().data()), bits = o.bits, first = o[0], second = o[1];
    }
    ASSERT_NE(at, 0u) << "no voxel with two level-1 segments";
  }
  // Swap the first two entries of that order (bit-packed, spec §5.5): distinct segments, so no longer in sort order.
  auto put = [&](std::uint64_t bit, std::uint32_t value) {
    for (std::uint32_t b = 0; b < bits; ++b, ++bit) {
      char& byte = bytes[at + bit / 8];
      byte = static_cast<char>((byte & ~(1 << (bit % 8))) | (((value >> b) & 1) << (bit % 8)));
    }
  };
  put(0, second);
  put(bits, first);
  test::reseal_checksums(bytes.data(), bytes.size());
  std::ofstream(dir.file("bad.vxl"), std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  const VerifyResult r = verify_vxl(dir.file("bad.vxl"));
  EXPECT_FALSE(r.valid);
  EXPECT_NE(r.problem.find("level 1 order 0 is not sorted"), std::string::npos) << r.problem;
}

}  // namespace
}  // namespace vxl
