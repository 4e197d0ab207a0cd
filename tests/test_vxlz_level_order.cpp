// A package of a file with levels ships its points level by level (spec/vxlz-package-v2.md §5.1, predictor 2): the
// first bytes of the package hold a level whole, and a level unpacked from them alone is the level's streamlines of
// the whole package, point for point. A prefix that does not hold what is asked for is refused, never read past.
#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "converter/convert/convert.h"
#include "converter/package/pack.h"
#include "converter/package/unpack.h"
#include "converter/synth/synth.h"
#include "format/base/direct_region_writer.h"
#include "format/base/error.h"
#include "format/base/mapped_file.h"
#include "format/vxl_file.h"
#include "format/vxl_levels.h"
#include "format/vxl_streamlines.h"
#include "format/vxl_verify.h"
#include "format/vxlz_package.h"
#include "format/vxlz_streams.h"
#include "tests/hostile_inputs.h"
#include "tests/reseal_checksums.h"
#include "tests/test_support.h"

namespace vxl {
namespace {

using test::ScratchDir;
using test::slurp;
using test::hostile::error_of;

constexpr std::uint32_t kLevels = 4;

// Each streamline's points, in streamline order.
std::vector<std::vector<float>> streamlines_of(const std::string& path) {
  const VxlFile file = VxlFile::open(path);
  std::vector<std::vector<float>> out;
  WalkCallbacks callbacks;
  callbacks.streamline = [&](std::uint64_t, std::span<const float> xyz) { out.emplace_back(xyz.begin(), xyz.end()); };
  walk_streamlines(file, callbacks);
  return out;
}

// The first `n` bytes of the file at `path`, as a package still arriving.
VxlzFile prefix_of(const std::string& path, std::uint64_t n) {
  const std::vector<char> bytes = slurp(path);
  auto* copy = static_cast<std::uint8_t*>(std::malloc(std::max<std::uint64_t>(n, 1)));
  std::memcpy(copy, bytes.data(), n);
  return VxlzFile::open_prefix(MappedFile::adopt(path, copy, n));
}

class LevelOrder : public ::testing::Test {
 protected:
  void SetUp() override {
    SynthSettings synth;
    synth.streamlines = 3000;
    synth.seed = 11;
    ConvertSettings convert;
    convert.voxel_size = 8.0;
    convert.levels = kLevels;
    convert_tractogram(synthesize_tractogram(synth), dir.file("s.vxl"), convert);
    PackSettings pack;
    pack.chunk_points = 4000;  // several chunks per level
    pack_vxl(VxlFile::open(dir.file("s.vxl")), dir.file("s.vxlz"), pack);
    UnpackSettings whole;
    whole.positions = PositionEncoding::Float32;  // a level alone packs its voxels' blocks differently
    unpack_vxlz(dir.file("s.vxlz"), dir.file("whole.vxl"), whole);
  }
  // flat.vxlz: `streamlines` synthetic streamlines converted without levels, packed (in streamline order).
  void pack_flat(std::uint64_t streamlines, double voxel_size = 8.0) {
    ConvertSettings convert;
    convert.voxel_size = voxel_size;
    convert.levels = 1;
    SynthSettings synth;
    synth.streamlines = streamlines;
    convert_tractogram(synthesize_tractogram(synth), dir.file("flat.vxl"), convert);
    pack_vxl(VxlFile::open(dir.file("flat.vxl")), dir.file("flat.vxlz"), {});
  }
  ScratchDir dir;
};

TEST_F(LevelOrder, EachLevelIsAPrefixOfThePackage) {
  const VxlzFile package = VxlzFile::open(dir.file("s.vxlz"));
  EXPECT_EQ(package.pack().predictor, kVxlzPredictorLinearLevelOrder);
  EXPECT_EQ(package.pack().level_count, kLevels);
  const std::vector<ShippedLevel> levels = shipped_levels(package);
  ASSERT_EQ(levels.size(), kLevels);
  std::uint64_t streamlines[kLevels] = {};
  for (std::uint64_t s = 0; s < package.meta().streamline_count; ++s)
    for (std::uint32_t d = 0; d <= streamline_depth(s, kLevels); ++d) ++streamlines[d];
  for (std::size_t i = 0; i < levels.size(); ++i) {
    const ShippedLevel& l = levels[i];
    EXPECT_EQ(l.level, kLevels - 1 - i) << "coarsest first";
    EXPECT_EQ(l.streamlines, streamlines[l.level]);
    if (i > 0) {
      EXPECT_GE(l.bytes, levels[i - 1].bytes) << "nested: each level holds the coarser ones";
    }
  }
  EXPECT_EQ(levels.back().points, package.pack().point_count);
  EXPECT_EQ(levels.back().bytes, package.size()) << "level 0 is everything";
  EXPECT_LT(levels[0].bytes, package.size() / 2) << "the coarsest level arrives long before the rest";
}

TEST_F(LevelOrder, ALevelFromItsPrefixAloneIsThatLevelOfTheWholePackage) {
  const std::vector<std::vector<float>> whole = streamlines_of(dir.file("whole.vxl"));
  for (const ShippedLevel& l : shipped_levels(VxlzFile::open(dir.file("s.vxlz")))) {
    if (l.level == 0) continue;
    SCOPED_TRACE("level " + std::to_string(l.level));
    UnpackSettings settings;
    settings.level = l.level;
    settings.positions = PositionEncoding::Float32;
    const UnpackSummary s = unpack_vxlz(prefix_of(dir.file("s.vxlz"), l.bytes), dir.file("level.vxl"), settings);
    EXPECT_EQ(s.streamlines, l.streamlines);
    const VerifyResult verified = verify_vxl(dir.file("level.vxl"));
    ASSERT_TRUE(verified.valid) << verified.problem;
    EXPECT_EQ(VxlFile::open(dir.file("level.vxl")).level_count(), 1u);
    std::vector<std::vector<float>> expected;
    for (std::uint64_t st = 0; st < whole.size(); ++st)
      if (streamline_depth(st, kLevels) >= l.level) expected.push_back(whole[st]);
    EXPECT_EQ(streamlines_of(dir.file("level.vxl")), expected);
  }
}

TEST_F(LevelOrder, APrefixThatDoesNotHoldTheLevelIsRefused) {
  const std::vector<ShippedLevel> levels = shipped_levels(VxlzFile::open(dir.file("s.vxlz")));
  UnpackSettings settings;
  settings.level = levels[0].level;
  const Error short_of_a_chunk = error_of(
      [&] { unpack_vxlz(prefix_of(dir.file("s.vxlz"), levels[0].bytes - 1), dir.file("level.vxl"), settings); });
  EXPECT_EQ(short_of_a_chunk.kind(), ErrorKind::Input);
  EXPECT_TRUE(test::contains(short_of_a_chunk.what(), "chunks")) << short_of_a_chunk.what();
  EXPECT_FALSE(std::filesystem::exists(dir.file("level.vxl"))) << "nothing is left behind";
  // Short of the exact part: the prefix says how many bytes opening it needs.
  const VxlzFile package = VxlzFile::open(dir.file("s.vxlz"));
  const std::uint64_t tables_end = package.chunks_end(0) - 1;
  const Error short_of_the_tables = error_of([&] { (void)prefix_of(dir.file("s.vxlz"), tables_end); });
  EXPECT_EQ(short_of_the_tables.kind(), ErrorKind::Input);
  EXPECT_TRUE(test::contains(short_of_the_tables.what(), "needs the first")) << short_of_the_tables.what();
}

// Each chunk has its own checksum (CHKS, version 2.4): a prefix whose chunks were damaged in transit is refused before
// its level is unpacked (the positions' checksum covers the whole, which a prefix cannot check); damage past the
// prefix does not concern it, and the whole package is refused for it. CHKS of the wrong size is refused too.
TEST_F(LevelOrder, APrefixsChunksAreCheckedAgainstTheirOwnChecksums) {
  const VxlzFile package = VxlzFile::open(dir.file("s.vxlz"));
  ASSERT_TRUE(package.has_chunk_checksums());
  const ShippedLevel coarsest = shipped_levels(package)[0];
  ASSERT_LT(coarsest.bytes, package.size());
  std::vector<char> bytes = slurp(dir.file("s.vxlz"));
  const std::uint64_t in_first_chunk = package.chunk(0).symbols_offset + 5;
  bytes[in_first_chunk] ^= 0x20;
  test::hostile::write_file(dir.file("damaged.vxlz"), std::string(bytes.begin(), bytes.end()));
  UnpackSettings settings;
  settings.level = coarsest.level;
  const Error e = error_of(
      [&] { unpack_vxlz(prefix_of(dir.file("damaged.vxlz"), coarsest.bytes), dir.file("level.vxl"), settings); });
  EXPECT_EQ(e.kind(), ErrorKind::Input);
  EXPECT_TRUE(test::contains(e.what(), "checksum mismatch in position chunk 0")) << e.what();
  EXPECT_FALSE(std::filesystem::exists(dir.file("level.vxl")));

  bytes = slurp(dir.file("s.vxlz"));
  bytes[bytes.size() - 3] ^= 0x20;  // in the last chunk, past the coarsest level's prefix
  test::hostile::write_file(dir.file("late.vxlz"), std::string(bytes.begin(), bytes.end()));
  EXPECT_EQ(unpack_vxlz(prefix_of(dir.file("late.vxlz"), coarsest.bytes), dir.file("level.vxl"), settings).streamlines,
            coarsest.streamlines);
  EXPECT_EQ(error_of([&] { (void)VxlzFile::open(dir.file("late.vxlz")); }).kind(), ErrorKind::Input);

  // CHKS one entry short, every checksum resealed: refused for its size.
  bytes = slurp(dir.file("s.vxlz"));
  FileHeader h;
  std::memcpy(&h, bytes.data(), sizeof h);
  for (std::uint32_t i = 0; i < h.section_count; ++i) {
    SectionEntry entry;
    std::memcpy(&entry, bytes.data() + sizeof h + i * sizeof entry, sizeof entry);
    if (std::memcmp(entry.id, "CHKS", 4) != 0) continue;
    entry.size -= 8;  // its last 8 bytes given to the next section, POSD, ...
    std::memcpy(bytes.data() + sizeof h + i * sizeof entry, &entry, sizeof entry);
    SectionEntry next;
    std::memcpy(&next, bytes.data() + sizeof h + (i + 1) * sizeof next, sizeof next);
    next.offset -= 8, next.size += 8;
    std::memcpy(bytes.data() + sizeof h + (i + 1) * sizeof next, &next, sizeof next);
    // ... and to chunk 0's symbols in CHNK, whose sizes then still add up to POSD's.
    SectionEntry chnk;
    std::memcpy(&chnk, bytes.data() + sizeof h + (i - 1) * sizeof chnk, sizeof chnk);
    ASSERT_EQ(std::string(chnk.id, 4), "CHNK");
    std::uint64_t first_size;
    std::memcpy(&first_size, bytes.data() + chnk.offset, 8);
    first_size += 8;
    std::memcpy(bytes.data() + chnk.offset, &first_size, 8);
  }
  test::reseal_checksums(bytes.data(), bytes.size());
  test::hostile::write_file(dir.file("short.vxlz"), std::string(bytes.begin(), bytes.end()));
  const Error short_table = error_of([&] { (void)VxlzFile::open(dir.file("short.vxlz")); });
  EXPECT_EQ(short_table.kind(), ErrorKind::Input);
  EXPECT_TRUE(test::contains(short_table.what(), "CHKS must hold one 8-byte checksum per chunk")) << short_table.what();
}

// A package whose tables claim 2^40 voxlines, all in its first streamline (STRL sums to META's count, checksums
// valid): the levels' plan refuses it before allocating for them, as the unpack does.
TEST_F(LevelOrder, AVoxlineCountTheStreamsCannotHoldIsRefusedBeforeAllocating) {
  const VxlzFile good = VxlzFile::open(dir.file("s.vxlz"));
  VxlzContent c;
  c.pack = good.pack();
  c.meta = good.meta();
  c.directions.assign(good.directions().begin(), good.directions().end());
  c.voxel_coords = good.inflate(section_id("VOXC"));
  c.voxline_voxels = good.inflate(section_id("VXLV"));
  c.voxline_counts = good.inflate(section_id("VXLC"));
  for (std::uint64_t i = 0; i < good.chunk_count(); ++i)
    c.chunks.push_back({std::vector<std::uint8_t>(good.chunk(i).symbols.begin(), good.chunk(i).symbols.end()),
                        std::vector<std::uint8_t>(good.chunk(i).escapes.begin(), good.chunk(i).escapes.end())});
  const std::uint64_t huge = std::uint64_t(1) << 40;
  VarintWriter strl;
  strl.put(huge);
  for (std::uint64_t s = 1; s < c.meta.streamline_count; ++s) strl.put(0);
  c.streamline_voxlines = strl.bytes();
  c.meta.voxline_count = huge;
  write_vxlz(dir.file("crafted.vxlz"), c);
  const Error e = error_of([&] { (void)shipped_levels(VxlzFile::open(dir.file("crafted.vxlz"))); });
  EXPECT_EQ(e.kind(), ErrorKind::Input);
  EXPECT_TRUE(test::contains(e.what(), "stream too short")) << e.what();
}

TEST_F(LevelOrder, AFileWithoutLevelsIsShippedInStreamlineOrderAndHasNoLevelAlone) {
  pack_flat(200);
  const VxlzFile package = VxlzFile::open(dir.file("flat.vxlz"));
  EXPECT_EQ(package.pack().predictor, kVxlzPredictorLinear);
  EXPECT_TRUE(shipped_levels(package).empty());
  UnpackSettings settings;
  settings.level = 1;
  EXPECT_EQ(error_of([&] { unpack_vxlz(package, dir.file("level.vxl"), settings); }).kind(), ErrorKind::Usage)
      << "a level of a package in streamline order";
}

// Where VERT is written block by block (an unpack within a tight memory limit, the web page's), each voxel's block of
// each depth is filled from its first vertex on as the points arrive, in level order and in streamline order: the file
// is the one VERT held whole gives, byte for byte, whatever the threads and the stagings' size (the smallest, one 4 KiB
// block, under a limit of a byte: blocks are written out part by part).
TEST_F(LevelOrder, VertexBlocksFilledAsThePointsArriveGiveTheSameFile) {
  pack_flat(2000, 40.0);  // large voxels: blocks of several 4 KiB stagings
  for (const char* name : {"s", "flat"}) {
    SCOPED_TRACE(name);
    const std::string package = dir.file(std::string(name) + ".vxlz");
    UnpackSettings held;
    held.threads = 2;
    const UnpackSummary whole = unpack_vxlz(package, dir.file("held.vxl"), held);
    ASSERT_FALSE(whole.vertices_read_back);
    if (std::string(name) == "flat") {
      const VxlFile f = VxlFile::open(dir.file("held.vxl"));
      ASSERT_GT(f.meta().vertex_count * 4 / f.voxels().size(), 3 * DirectRegionWriter::kBlock)
          << "voxels whose blocks a 4 KiB staging writes out in parts";
    }
    for (const std::uint64_t limit : {std::uint64_t(0), std::uint64_t(1)})
      for (const unsigned threads : {1u, 3u}) {
        UnpackSettings blocks;
        blocks.threads = threads;
        blocks.vertex_blocks = true;
        blocks.memory_limit = limit;
        EXPECT_TRUE(unpack_vxlz(package, dir.file("blocks.vxl"), blocks).vertices_read_back);
        EXPECT_EQ(slurp(dir.file("blocks.vxl")), slurp(dir.file("held.vxl")))
            << threads << " threads, memory limit " << limit;
      }
  }
  EXPECT_EQ(VxlzFile::open(dir.file("s.vxlz")).pack().level_count, kLevels) << "the first in level order";
  // Fewer levels than a package in level order ships by interleave the coarsest block's streamlines: VERT is then held
  // whole. As many or more fill each block in order.
  for (const std::uint32_t levels : {1u, kLevels - 1, kLevels, kLevels + 1}) {
    SCOPED_TRACE(std::to_string(levels) + " levels");
    UnpackSettings held, blocks;
    held.levels = blocks.levels = levels;
    blocks.vertex_blocks = true;
    unpack_vxlz(dir.file("s.vxlz"), dir.file("held.vxl"), held);
    EXPECT_EQ(unpack_vxlz(dir.file("s.vxlz"), dir.file("blocks.vxl"), blocks).vertices_read_back, levels >= kLevels);
    EXPECT_EQ(slurp(dir.file("blocks.vxl")), slurp(dir.file("held.vxl")));
  }
}

// Many small voxels: each open block's staging (a 4 KiB block at least) would take more than a quarter of VERT and more
// than 16 MiB, so VERT is held whole, and the file is the same.
TEST_F(LevelOrder, ManySmallVoxelsKeepVertexBlocksHeldWhole) {
  SynthSettings synth;
  synth.streamlines = 2000;
  ConvertSettings convert;
  convert.voxel_size = 1.0;
  convert_tractogram(synthesize_tractogram(synth), dir.file("fine.vxl"), convert);
  pack_vxl(VxlFile::open(dir.file("fine.vxl")), dir.file("fine.vxlz"), {});
  ASSERT_GT(VxlFile::open(dir.file("fine.vxl")).voxels().size(), 4096u);
  UnpackSettings held, blocks;
  blocks.vertex_blocks = true;
  blocks.memory_limit = 1;
  unpack_vxlz(dir.file("fine.vxlz"), dir.file("held.vxl"), held);
  const UnpackSummary s = unpack_vxlz(dir.file("fine.vxlz"), dir.file("blocks.vxl"), blocks);
  EXPECT_FALSE(s.vertices_read_back);
  EXPECT_TRUE(s.decoded_twice);
  EXPECT_EQ(slurp(dir.file("blocks.vxl")), slurp(dir.file("held.vxl")));
}

}  // namespace
}  // namespace vxl
