// A damaged file reaches the shaders: the GPU gets the file's bytes as they are, and the checks that would
// refuse them run beside the drawing (GpuScene::check_uploaded). The vertex shader clamps what it reads, so
// such a file draws wrong lines of its own voxels, never lines made of another voxel's bytes, and the checks
// then report it (vxl::Error, Input, naming the byte).
#include <bit>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "converter/synth/synth.h"
#include "format/base/error.h"
#include "tests/viewer/render_support.h"

namespace vxl {
namespace {

using test::ScratchDir;

class DamagedDraw : public ::testing::Test {
 protected:
  void SetUp() override { test::gl_context(); }

  // A synthetic scene, its path and bytes.
  std::string convert_scene() {
    SynthSettings synth;
    synth.streamlines = 40;
    ConvertSettings s;
    s.voxel_size = 25;
    const std::string path = dir.file("intact.vxl");
    convert_tractogram(synthesize_tractogram(synth), path, s);
    bytes = test::slurp(path);
    return path;
  }
  VxlFile write_damaged() {
    std::ofstream(dir.file("damaged.vxl"), std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
    return VxlFile::open(dir.file("damaged.vxl"));
  }
  // Writes `value` into the `bits` bits from bit `bit` of the file, least significant first (spec §5.5).
  void put_bits(std::uint64_t bit, std::uint32_t bits, std::uint32_t value) {
    for (std::uint32_t i = 0; i < bits; ++i, ++bit) {
      char& byte = bytes[bit / 8];
      const char mask = static_cast<char>(1u << (bit % 8));
      byte = static_cast<char>(((value >> i) & 1u) ? (byte | mask) : (byte & ~mask));
    }
  }

  ScratchDir dir;
  std::vector<char> bytes;
};

Image draw(const VxlFile& f) {
  Renderer r(f);
  RenderSettings s;
  s.mode = RenderMode::Axis;
  s.color = ColorMode::Fixed;
  s.opacity = 1.0f;
  Camera camera;
  camera.azimuth_deg = 30;
  camera.elevation_deg = 25;
  camera.frame(r.bounds_min(), r.bounds_max(), 1.0);
  return test::render_image(r, camera, s, 320, 320);
}

// The checks of what `r` uploaded refuse it: an input error at byte `at` whose message holds `why`.
void expect_refused(Renderer& r, std::uint64_t at, const std::string& why) {
  try {
    r.check_uploaded(true);
    ADD_FAILURE() << "not refused: " << why;
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    EXPECT_EQ(e.offset(), at) << e.what();
    EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
  }
}

bool any_channel_lit(const Image& img, int x, int y) {
  return (img.pixel(x, y)[0] | img.pixel(x, y)[1] | img.pixel(x, y)[2]) != 0;
}

// Every entry of every stored order of one voxel past its block (by different amounts, within the entries'
// bits): clamped, each draws the block's last segment, which the intact file draws too, so the damaged picture
// lights no pixel the intact one leaves dark; without the clamp the entries would join the padding and the
// next voxels' vertices, decoded in this voxel's box. The checks then refuse the file, naming the voxel's
// orders.
TEST_F(DamagedDraw, OrderEntriesPastTheBlockDrawTheBlocksOwnSegmentsAndAreRefused) {
  const VxlFile intact = VxlFile::open(convert_scene());
  ASSERT_EQ(intact.order_packing(), OrderPacking::Bits);
  // The voxel whose entries can name the most vertices past its block.
  std::uint32_t voxel = 0, slack = 0;
  for (std::uint32_t i = 0; i < intact.voxels().size(); ++i) {
    const VoxelEntry& v = intact.voxels()[i];
    const std::uint32_t bits = order_entry_bits(v.vertex_count, OrderPacking::Bits);
    const std::uint32_t past = static_cast<std::uint32_t>((std::uint64_t(1) << bits) - 1) - (v.vertex_count - 1);
    if (v.segment_count >= 20 && past > slack) voxel = i, slack = past;
  }
  ASSERT_GE(slack, 16u) << "no voxel whose entries can point well past its block";
  const VoxelEntry& v = intact.voxels()[voxel];
  const std::uint32_t bits = order_entry_bits(v.vertex_count, OrderPacking::Bits);
  const std::uint64_t orders_at = intact.orders_offset() + v.order_offset;
  const std::uint64_t array_bytes = order_array_bytes(v.segment_count, bits);
  for (std::uint32_t k = 0; k < intact.meta().stored_order_count; ++k)
    for (std::uint32_t j = 0; j < v.segment_count; ++j)
      put_bits(8 * (orders_at + k * array_bytes) + std::uint64_t(j) * bits, bits, v.vertex_count - 1 + j % slack);
  const VxlFile damaged = write_damaged();

  const Image good = draw(intact), bad = draw(damaged);
  int lost = 0, stray = 0;
  for (int y = 0; y < good.height; ++y)
    for (int x = 0; x < good.width; ++x) {
      lost += any_channel_lit(good, x, y) && !any_channel_lit(bad, x, y);
      stray += any_channel_lit(bad, x, y) && !any_channel_lit(good, x, y);
    }
  EXPECT_GT(lost, 20) << "the damaged voxel's segments are no longer drawn";
  EXPECT_EQ(stray, 0) << "a damaged entry drew a line that is none of the file's segments";

  Renderer r(damaged);
  expect_refused(r, orders_at, "order entry out of range in voxel " + std::to_string(voxel));
  // A scene whose checks failed stays refused.
  EXPECT_THROW(r.check_uploaded(false), Error);
}

// A packed word's reserved bit is not drawn (the decoder reads the 30 coordinate bits and the voxline end):
// the picture is the intact one, and the checks refuse the file, naming the word's byte.
TEST_F(DamagedDraw, AReservedBitIsNotDrawnAndIsRefused) {
  const VxlFile intact = VxlFile::open(convert_scene());
  const std::uint64_t word_at = intact.find_section(section_id("VERT"))->offset + 4 * 7;
  bytes[word_at + 3] = static_cast<char>(bytes[word_at + 3] | 0x80);  // bit 31, little-endian
  const VxlFile damaged = write_damaged();
  EXPECT_EQ(compare_images(draw(intact), draw(damaged)).differing_pixels, 0u);
  Renderer r(damaged);
  expect_refused(r, word_at, "reserved bit set");
}

}  // namespace
}  // namespace vxl
