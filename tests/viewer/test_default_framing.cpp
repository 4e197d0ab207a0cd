// voxview's default view (no --camera): the tractogram fills the window along its tighter side, whatever
// the window's shape, view direction and projection, and nothing is cut off; a turntable keeps every
// frame whole. Rendered through the program, as a user gets it.
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "tests/test_support.h"
#include "viewer/platform/image_io.h"

namespace vxl {
namespace {

using test::ScratchDir;

struct LitExtent {
  int rows = 0, cols = 0;       // rows / columns with any lit pixel, first to last
  bool touches_border = false;  // a lit pixel in the outermost row or column
};

LitExtent lit_extent(const Image& img) {
  int top = img.height, bottom = -1, left = img.width, right = -1;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const std::uint8_t* p = &img.rgba[(std::size_t(y) * img.width + x) * 4];
      if (p[0] == 0 && p[1] == 0 && p[2] == 0) continue;
      top = std::min(top, y), bottom = std::max(bottom, y), left = std::min(left, x), right = std::max(right, x);
    }
  LitExtent e;
  if (bottom < 0) return e;
  e.rows = bottom - top + 1;
  e.cols = right - left + 1;
  e.touches_border = top == 0 || left == 0 || bottom == img.height - 1 || right == img.width - 1;
  return e;
}

class DefaultFraming : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(std::filesystem::exists(VOXVIEW_CLI)) << VOXVIEW_CLI;
    auto synth = test::run_cli("synth --streamlines 400 --seed 3 '" + dir.file("s.tck") + "'");
    ASSERT_EQ(synth.exit_code, 0) << synth.output;
    auto convert = test::run_cli("convert '" + dir.file("s.tck") + "' '" + vxl + "'");
    ASSERT_EQ(convert.exit_code, 0) << convert.output;
  }
  Image render(const std::string& args) {
    const std::string png = dir.file("f.png");
    auto r = test::run_program(VOXVIEW_CLI, "'" + vxl + "' --render '" + png + "' " + args);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return read_image(png);
  }

  ScratchDir dir;
  std::string vxl = dir.file("s.vxl");
};

TEST_F(DefaultFraming, FillsTheTighterSideOfAnyWindowWithoutCuttingOff) {
  for (const std::string projection : {"", "--ortho"})
    for (const std::string view : {"", "--view axial", "--view sagittal", "--view 60,-40"}) {
      SCOPED_TRACE(projection + " " + view);
      const LitExtent wide = lit_extent(render("--size 320x160 " + projection + " " + view));
      EXPECT_GE(wide.rows, 0.85 * 160) << "a wide window's height is not filled";
      EXPECT_FALSE(wide.touches_border) << "cut off";
      const LitExtent tall = lit_extent(render("--size 160x320 " + projection + " " + view));
      EXPECT_GE(tall.cols, 0.85 * 160) << "a tall window's width is not filled";
      EXPECT_FALSE(tall.touches_border) << "cut off";
    }
}

TEST_F(DefaultFraming, EveryTurntableFrameIsWhole) {
  auto r =
      test::run_program(VOXVIEW_CLI, "'" + vxl + "' --render '" + dir.file("t.png") + "' --size 240x120 --turntable 6");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  int filled_most = 0;
  for (int i = 0; i < 6; ++i) {
    const LitExtent e = lit_extent(read_image(dir.file("t_00" + std::to_string(i) + ".png")));
    EXPECT_FALSE(e.touches_border) << "frame " << i << " is cut off";
    EXPECT_GT(e.rows, 0) << "frame " << i << " is empty";
    filled_most = std::max(filled_most, e.rows);
  }
  // Framed for all frames at once, so less tightly than one view, but still most of the height.
  EXPECT_GE(filled_most, 0.7 * 120);
}

}  // namespace
}  // namespace vxl
