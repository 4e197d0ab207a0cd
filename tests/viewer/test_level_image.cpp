// A file's coarser levels as a .vxl of their own (format/vxl_level_image.h), made from its tables and filled from the
// file's bytes where its placements say, as the web viewer does for a file larger than its memory: the finest level
// that fits, every level holding the file's vertices and orders, drawn as the file draws that level; damaged tables
// refused, naming the file's byte.
#include <cstdlib>
#include <cstring>

#include "converter/synth/synth.h"
#include "format/base/error.h"
#include "format/vxl_fetch_plan.h"
#include "format/vxl_level_image.h"
#include "tests/reseal_checksums.h"
#include "tests/viewer/render_support.h"
#include "viewer/platform/image_metrics.h"

namespace vxl {
namespace {

using test::gl_context;
using test::render_image;
using test::ScratchDir;

constexpr std::uint32_t kLevels = 4;

// The bytes of ranges_for_level_image one after another, as a reader fetches them.
std::vector<std::uint8_t> gather(const std::vector<std::uint8_t>& whole) {
  std::vector<std::uint8_t> out;
  for (const ByteRange& r : ranges_for_level_image("scene.vxl", whole, whole.size()))
    out.insert(out.end(), whole.begin() + static_cast<std::ptrdiff_t>(r.begin),
               whole.begin() + static_cast<std::ptrdiff_t>(r.end));
  return out;
}

LevelImage image_of(const std::vector<std::uint8_t>& whole, std::uint64_t max_bytes) {
  return make_level_image("scene.vxl", gather(whole), whole.size(), max_bytes);
}

// The image with its vertex and order bytes where its placements take them from; the rest of them garbage, as a
// reader's buffer before they arrive.
VxlFile filled(LevelImage& image, const std::vector<std::uint8_t>& whole) {
  // The reader writes into the image's buffer (the web page's fetches do, from outside the WebAssembly).
  auto* bytes = const_cast<std::uint8_t*>(image.bytes.data());
  for (const ImagePlacement& p : image.data) std::memset(bytes + p.at, 0xA5, p.size);
  for (const ImagePlacement& p : image.data) std::memcpy(bytes + p.at, whole.data() + p.source, p.size);
  return VxlFile::open(std::move(image.bytes));
}

class LevelImageTest : public ::testing::TestWithParam<bool> {
 protected:
  void SetUp() override {
    SynthSettings synth;
    synth.streamlines = 12000;
    ConvertSettings s;
    s.voxel_size = 10;
    s.levels = kLevels;
    s.positions = GetParam() ? PositionEncoding::Packed : PositionEncoding::Float32;
    convert_tractogram(synthesize_tractogram(synth), dir.file("scene.vxl"), s);
    whole = test::slurp<std::vector<std::uint8_t>>(dir.file("scene.vxl"));
  }
  ScratchDir dir;
  std::vector<std::uint8_t> whole;
};

// Each image holds, voxel by voxel, the file's vertices and orders of its levels: level d of the image is the file's
// level + d, its voxels those with vertices at that level.
void expect_levels_as_the_file(const VxlFile& image, const VxlFile& file, std::uint32_t level) {
  ASSERT_EQ(image.level_count(), kLevels - level);
  const std::uint32_t k = file.meta().stored_order_count;
  std::size_t next = 0;
  for (std::size_t i = 0; i < file.voxels().size(); ++i) {
    if (file.level(i, level).vertex_count == 0) continue;
    ASSERT_LT(next, image.voxels().size());
    const std::size_t j = next++;
    for (std::uint32_t d = 0; d < image.level_count(); ++d) {
      const LevelEntry a = image.level(j, d), b = file.level(i, level + d);
      ASSERT_EQ(a.vertex_count, b.vertex_count) << "voxel " << i << " level " << level + d;
      ASSERT_EQ(a.segment_count, b.segment_count);
      std::vector<float> xyz_a(3 * a.vertex_count), xyz_b(3 * b.vertex_count);
      image.read_vertices(j, image.voxels()[j].vertex_first, a.vertex_count, xyz_a.data());
      file.read_vertices(i, file.voxels()[i].vertex_first, b.vertex_count, xyz_b.data());
      ASSERT_EQ(xyz_a, xyz_b) << "voxel " << i << " level " << level + d;
      for (std::uint32_t o = 0; o < k; ++o) {
        const OrderView oa = image.order(j, o, d), ob = file.order(i, o, level + d);
        ASSERT_EQ(oa.bits, ob.bits);
        ASSERT_EQ(0, std::memcmp(oa.data, ob.data, order_array_bytes(oa.count, oa.bits)));
      }
    }
  }
  EXPECT_EQ(next, image.voxels().size());
}

TEST_P(LevelImageTest, TheFinestLevelThatFitsHoldsTheFilesVerticesAndOrdersAndDrawsAsTheFileDoes) {
  gl_context();
  const VxlFile file = VxlFile::open(dir.file("scene.vxl"));
  RenderSettings settings;
  settings.opacity = 0.3f;
  std::uint64_t max_bytes = whole.size();
  for (std::uint32_t level = 0; level < kLevels; ++level) {
    LevelImage image = image_of(whole, max_bytes);
    ASSERT_EQ(image.level, level) << "the finest level whose image takes at most " << max_bytes << " bytes";
    const std::uint64_t image_bytes = image.bytes.size();
    EXPECT_LE(image_bytes, max_bytes);
    EXPECT_EQ(image.file_meta.streamline_count, file.meta().streamline_count);
    const VxlFile opened = filled(image, whole);
    EXPECT_EQ(opened.meta().streamline_count, 0u) << "nothing per streamline in an image";
    expect_levels_as_the_file(opened, file, level);

    // Level 0 of the image at the opacity the file's level gets: the file's picture of that level, to the byte.
    Renderer from_image(opened, 0, 0), from_file(file, 0, level);
    RenderSettings compensated = settings;
    compensated.opacity = SceneLayout::level_opacity(settings.opacity, level);
    const Image a = render_image(from_image, test::synth_brain_view(), compensated, 96, 96);
    from_image.check_uploaded(true);  // throws on a damaged block or order
    const Image b = render_image(from_file, test::synth_brain_view(), settings, 96, 96);
    EXPECT_GT(test::lit_pixels(b), 100) << "level " << level;
    EXPECT_EQ(compare_images(a, b).differing_pixels, 0u) << "level " << level;
    max_bytes = image_bytes - 1;  // the next coarser level
  }
  try {
    image_of(whole, max_bytes);
    FAIL() << "not even the coarsest level's image fits " << max_bytes << " bytes";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Unsupported);
    EXPECT_NE(std::string(e.what()).find("coarsest level of detail (3)"), std::string::npos) << e.what();
  }
}

TEST_P(LevelImageTest, ItsRangesComeFromTheFilesVerticesAndOrdersAlone) {
  const VxlFile file = VxlFile::open(dir.file("scene.vxl"));
  LevelImage image = image_of(whole, whole.size() / 4);
  ASSERT_GE(image.level, 1u);
  const std::vector<ImagePlacement> data = image.data;
  const std::vector<ByteRange> written = image.written;
  const VxlFile opened = filled(image, whole);
  const std::vector<ByteRange> to_come = ranges_missing(written, opened.bytes().size());
  // Only the vertices and orders are still to come, and the image's levels read all of them.
  std::vector<ByteRange> image_levels, file_levels;
  for (std::uint32_t d = 0; d < opened.level_count(); ++d) {
    for (const ByteRange& r : ranges_of_level(opened, d, 0)) image_levels.push_back(r);
    for (const ByteRange& r : ranges_of_level(file, image.level + d, 0)) file_levels.push_back(r);
  }
  EXPECT_EQ(merge_ranges(image_levels, 0), to_come);
  const std::vector<ByteRange> from = source_ranges(data, to_come, 0);
  std::uint64_t bytes = 0, placed = 0;
  const SectionEntry* vert = file.find_section(section_id("VERT"));
  const SectionEntry* ordb = file.find_section(section_id("ORDB"));
  for (const ByteRange& r : from) {
    const bool in_vert = r.begin >= vert->offset && r.end <= vert->offset + vert->size;
    const bool in_ordb = r.begin >= ordb->offset && r.end <= ordb->offset + ordb->size;
    EXPECT_TRUE(in_vert || in_ordb) << r.begin << ".." << r.end;
    bytes += r.end - r.begin;
  }
  for (const ImagePlacement& p : data) placed += p.size;
  EXPECT_EQ(bytes, placed);
  EXPECT_EQ(from, merge_ranges(file_levels, 0)) << "the file's own ranges of those levels";
  // Part of the image: the part of the file it came from.
  const ByteRange some{to_come[0].begin + 4, to_come[0].begin + 12};
  const std::vector<ByteRange> part = source_ranges(data, std::vector<ByteRange>{some}, 0);
  ASSERT_EQ(part.size(), 1u);
  EXPECT_EQ(part[0].begin, data[0].source + 4);
  EXPECT_EQ(part[0].end, data[0].source + 12);
}

// The error make_level_image throws for `bytes` as a file, or "" when it makes an image.
std::string refusal(const std::vector<std::uint8_t>& bytes) {
  try {
    image_of(bytes, bytes.size());
    return "";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input) << e.what();
    return e.what();
  }
}

TEST_P(LevelImageTest, DamagedTablesAreRefusedNamingTheirByte) {
  const VxlFile file = VxlFile::open(dir.file("scene.vxl"));
  const std::uint64_t voxt = file.find_section(section_id("VOXT"))->offset;
  const std::uint64_t lods = file.find_section(section_id("LODS"))->offset;
  auto damaged = [&](std::uint64_t at, std::uint8_t value, bool reseal) {
    std::vector<std::uint8_t> bytes = whole;
    bytes[at] = value;
    if (reseal) test::reseal_checksums(bytes.data(), bytes.size());
    return refusal(bytes);
  };
  EXPECT_EQ(refusal(whole), "");
  EXPECT_NE(damaged(voxt + 70, whole[voxt + 70] ^ 1, false).find("checksum mismatch in section VOXT"),
            std::string::npos);
  EXPECT_NE(damaged(64 + 24, whole[64 + 24] ^ 1, false).find("header checksum mismatch"), std::string::npos);
  // Past the checksums: a voxel's orders beyond their section, a level larger than the finer one.
  const std::uint64_t order_offset = voxt + file.voxels().size() / 2 * sizeof(VoxelEntry) + 63;
  EXPECT_NE(damaged(order_offset, 0x7F, true).find("voxel orders are not in order"), std::string::npos);
  EXPECT_NE(damaged(lods + 3, 0x7F, true).find("is not a prefix of level 0"), std::string::npos);
  // The random order set without per-voxel directions: open() refuses it, and so does the image.
  const std::uint64_t meta = file.find_section(section_id("META"))->offset;
  EXPECT_NE(damaged(meta + 100, 2, true).find("a VDIR section exactly when the order set is random"),
            std::string::npos);
  const std::uint64_t vertex_first = voxt + sizeof(VoxelEntry) + 44;
  EXPECT_NE(damaged(vertex_first, 0x01, true).find("not contiguous"), std::string::npos);
}

INSTANTIATE_TEST_SUITE_P(Positions, LevelImageTest, ::testing::Values(true, false),
                         [](const auto& info) { return info.param ? "Packed" : "Float32"; });

}  // namespace
}  // namespace vxl
