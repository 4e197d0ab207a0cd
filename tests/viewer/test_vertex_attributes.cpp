// The line shader's per-vertex words (vertex_attributes.h), made voxel by voxel from the voxel's list of
// voxlines: at every level's prefix they are what a walk of the whole voxline table gives (spec §5.6) — the
// streamline's number in the scene, and its value from VVAL or SVAL.
#include <bit>
#include <cmath>
#include <cstring>

#include <gtest/gtest.h>

#include "converter/convert/convert.h"
#include "converter/synth/synth.h"
#include "format/level_voxlines.h"
#include "format/vxl_streamlines.h"
#include "tests/hostile_vxl.h"
#include "tests/test_support.h"
#include "viewer/render/vertex_attributes.h"

namespace vxl {
namespace {

// Per vertex, its streamline, from a walk of the voxline table in streamline order.
std::vector<std::uint64_t> streamline_of_vertex(const VxlFile& f) {
  std::vector<std::uint64_t> of(f.meta().vertex_count, ~0ull);
  WalkCallbacks cb;
  cb.voxline = [&](const VoxlineVisit& v) {
    for (std::uint64_t i = v.first_vertex; i < v.first_vertex + v.own_points + (v.connected ? 1 : 0); ++i)
      of[i] = v.streamline;
  };
  walk_streamlines(f, cb);
  return of;
}

// A synthetic set of `streamlines`, converted in `dir`.
VxlFile synthetic_vxl(const test::ScratchDir& dir, std::uint64_t streamlines, double voxel_size, std::uint32_t levels,
                      PositionEncoding positions) {
  SynthSettings synth;
  synth.streamlines = streamlines;
  ConvertSettings c;
  c.voxel_size = voxel_size;
  c.levels = levels;
  c.threads = 2;
  c.positions = positions;
  convert_tractogram(synthesize_tractogram(synth), dir.file("s.vxl"), c);
  return VxlFile::open(dir.file("s.vxl"));
}

TEST(VertexAttributes, EveryLevelsPrefixHoldsTheStreamlinesTheWalkGives) {
  test::ScratchDir dir;
  // Five levels, the coarsest (a 4096th of the streamlines) holding some: the levels placed once for the file.
  const VxlFile f = synthetic_vxl(dir, 20000, 6, 5, PositionEncoding::Packed);
  ASSERT_EQ(f.level_count(), 5u);
  const std::optional<VoxelVoxlines> index = VoxelVoxlines::build(f);
  ASSERT_TRUE(index.has_value());
  const std::vector<std::uint64_t> expected = streamline_of_vertex(f);
  // As the second file of a scene, after 1000 streamlines: each voxel through its list, and the coarse levels
  // placed once for the file (LevelVoxlines).
  VoxelVoxlinesCache cache({&f, &f});
  for (const AttributeSource& source :
       {AttributeSource{{}, 1000, &*index}, AttributeSource{{}, 1000, &*index, &cache, 1}}) {
    std::uint64_t checked = 0, coarsest = 0;
    for (std::size_t v = 0; v < f.voxels().size(); ++v)
      for (std::uint32_t level = 0; level < f.level_count(); ++level) {
        const std::uint32_t n = f.level(v, level).vertex_count;
        std::vector<std::uint32_t> words(2 * std::size_t(n) + 2, 0xABCDEF01u);
        voxel_attributes(f, v, source, n, words.data());
        EXPECT_EQ(words[2 * n], 0xABCDEF01u) << "wrote past the prefix";
        for (std::uint32_t i = 0; i < n; ++i) {
          ASSERT_EQ(words[2 * i + 1], 1000 + expected[f.voxels()[v].vertex_first + i])
              << "voxel " << v << " level " << level << " vertex " << i;
          ASSERT_TRUE(std::isnan(std::bit_cast<float>(words[2 * i])));  // no value set asked for
        }
        checked += n;
        if (level == 4) coarsest += n;
      }
    EXPECT_GT(checked, f.meta().vertex_count);  // the coarse levels too
    EXPECT_GT(coarsest, 0u);
  }
}

// A level placed for the whole file from its own streamlines (LevelVoxlines) is what each voxel's list places:
// the same voxlines in the same order at the same places, with packed and with float32 positions.
TEST(VertexAttributes, ALevelPlacedFromItsStreamlinesIsWhatTheVoxelsListsPlace) {
  for (const PositionEncoding positions : {PositionEncoding::Packed, PositionEncoding::Float32}) {
    test::ScratchDir dir;
    const VxlFile f = synthetic_vxl(dir, 3000, 6, 4, positions);
    const std::optional<VoxelVoxlines> index = VoxelVoxlines::build(f);
    ASSERT_TRUE(index.has_value());
    std::vector<std::uint8_t> ends;
    std::vector<PlacedVoxline> listed;
    for (std::uint32_t level = 0; level < f.level_count(); ++level) {
      const LevelVoxlines placed(f, level);
      std::uint64_t compared = 0;
      for (std::size_t v = 0; v < f.voxels().size(); ++v) {
        place_voxel_voxlines(f, *index, v, ends, listed, level);
        const std::span<const PlacedVoxline> got = placed.of_voxel(v);
        ASSERT_EQ(got.size(), listed.size()) << "voxel " << v << " level " << level;
        for (std::size_t k = 0; k < got.size(); ++k) {
          EXPECT_EQ(got[k].streamline, listed[k].streamline);
          EXPECT_EQ(got[k].first_vertex, listed[k].first_vertex);
          EXPECT_EQ(got[k].own, listed[k].own);
          EXPECT_EQ(got[k].depth, listed[k].depth);
          EXPECT_EQ(got[k].synthetic_first, listed[k].synthetic_first);
          EXPECT_EQ(got[k].first_of_streamline, listed[k].first_of_streamline);
          EXPECT_EQ(got[k].last_of_streamline, listed[k].last_of_streamline);
        }
        compared += got.size();
      }
      EXPECT_GT(compared, 10u) << "level " << level << " holds voxlines to compare";
    }
  }
}

// A voxline of a coarse level that claims more points than its depth's part of the block holds is refused,
// naming the voxel's table entry.
TEST(VertexAttributes, ALevelsVoxlinePastItsBlockIsRefused) {
  test::ScratchDir dir;
  synthetic_vxl(dir, 3000, 6, 4, PositionEncoding::Packed);
  std::vector<char> bytes = test::slurp(dir.file("s.vxl"));
  std::uint64_t at = 0, voxt_at = 0, voxel = 0;
  {
    const VxlFile f = VxlFile::open(dir.file("s.vxl"));
    const LevelVoxlines level2(f, 2);
    for (std::size_t v = 0; v < f.voxels().size() && at == 0; ++v)
      for (const PlacedVoxline& p : level2.of_voxel(v)) {
        const auto strm = f.streamline_first_voxline();
        for (std::uint64_t j = strm[p.streamline]; j < strm[p.streamline + 1]; ++j)
          if (f.voxlines()[j].voxel == v) at = f.find_section(section_id("VXLN"))->offset + 8 * j;
        voxel = v;
        break;
      }
    voxt_at = f.find_section(section_id("VOXT"))->offset;
  }
  ASSERT_GT(at, 0u);
  const std::uint32_t many = kVoxlineCountMask;  // count_flags: the count, no synthetic first point
  std::memcpy(bytes.data() + at + 4, &many, 4);
  test::write_file(dir.file("bad.vxl"), bytes);
  const VxlFile bad = VxlFile::open(dir.file("bad.vxl"));
  try {
    LevelVoxlines(bad, 2);
    FAIL() << "a voxline past its block was placed";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("run past its vertex block"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(std::to_string(voxt_at + 64 * voxel)), std::string::npos) << e.what();
  }
}

// A level's placement reads that level's prefix only, and gives the voxlines that the whole block's placement
// gives for the streamlines of depth >= the level, at the same places: with packed and with float32 positions.
TEST(VertexAttributes, ALevelsPlacementIsTheWholePlacementOfItsStreamlines) {
  for (const PositionEncoding positions : {PositionEncoding::Packed, PositionEncoding::Float32}) {
    test::ScratchDir dir;
    const VxlFile f = synthetic_vxl(dir, 1200, 8, 3, positions);
    const std::optional<VoxelVoxlines> index = VoxelVoxlines::build(f);
    ASSERT_TRUE(index.has_value());
    std::vector<std::uint8_t> ends;
    std::vector<PlacedVoxline> whole, part;
    std::uint64_t compared = 0;
    for (std::size_t v = 0; v < f.voxels().size(); ++v) {
      place_voxel_voxlines(f, *index, v, ends, whole, 0);
      for (std::uint32_t level = 1; level < f.level_count(); ++level) {
        place_voxel_voxlines(f, *index, v, ends, part, level);
        std::vector<PlacedVoxline> expected;
        for (const PlacedVoxline& p : whole)
          if (p.depth >= level) expected.push_back(p);
        ASSERT_EQ(part.size(), expected.size()) << "voxel " << v << " level " << level;
        const std::uint64_t prefix_end = f.voxels()[v].vertex_first + f.level(v, level).vertex_count;
        for (std::size_t k = 0; k < part.size(); ++k) {
          EXPECT_EQ(part[k].streamline, expected[k].streamline);
          EXPECT_EQ(part[k].first_vertex, expected[k].first_vertex);
          EXPECT_EQ(part[k].own, expected[k].own);
          EXPECT_LE(part[k].first_vertex + part[k].vertices(), prefix_end);
        }
        compared += part.size();
      }
    }
    EXPECT_GT(compared, 100u) << "the coarse levels hold voxlines to compare";
  }
}

TEST(VertexAttributes, ValuesComeFromVvalAsTheyAreAndFromSvalThroughTheStreamline) {
  test::ScratchDir dir;
  const test::VxlBytes b = test::VxlBytes::make(dir.file("h.vxl"));
  const VxlFile f = VxlFile::open(dir.file("h.vxl"));
  const std::optional<VoxelVoxlines> index = VoxelVoxlines::build(f);
  ASSERT_TRUE(index.has_value());
  const std::vector<std::uint64_t> streamline = streamline_of_vertex(f);
  const ValueSource fa = find_value_set(f, "fa"), length = find_value_set(f, "length");
  ASSERT_EQ(fa.kind, ValueSource::Kind::Vertex);
  ASSERT_EQ(length.kind, ValueSource::Kind::Streamline);
  for (std::size_t v = 0; v < f.voxels().size(); ++v) {
    const VoxelEntry& e = f.voxels()[v];
    std::vector<std::uint32_t> per_vertex(2 * e.vertex_count), per_streamline(2 * e.vertex_count);
    voxel_attributes(f, v, {fa, 0, &*index}, e.vertex_count, per_vertex.data());
    voxel_attributes(f, v, {length, 0, &*index}, e.vertex_count, per_streamline.data());
    for (std::uint32_t i = 0; i < e.vertex_count; ++i) {
      const std::uint64_t g = e.vertex_first + i;
      EXPECT_EQ(std::bit_cast<float>(per_vertex[2 * i]), f.vertex_values().values(fa.set)[g]);
      EXPECT_EQ(std::bit_cast<float>(per_streamline[2 * i]), f.streamline_values().values(length.set)[streamline[g]]);
    }
  }
}

}  // namespace
}  // namespace vxl
