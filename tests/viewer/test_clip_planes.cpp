// Crop to slab and clip planes: voxels wholly outside are culled by the frame plan, what remains is cut
// exactly by the line shader; the voxview options parse and refuse as documented.
#include <filesystem>

#include "tests/viewer/render_support.h"

namespace vxl {
namespace {

using test::gl_context;
using test::make_scene;
using test::render_image;
using test::ScratchDir;

// Seen from above on a 64 x 64 image at 1 mm per pixel, world (x, y) = (c - 31.5, 31.5 - r) is the centre
// of pixel (c, r). Five lines along x at depths z = -20 ... 20, each on its own row (y = -16 ... 16), and
// one slanted line z = x - 0.5 on row 7 (y = 24.5), so that a slab shows up as a run of lit pixels.
Tractogram depth_lines() {
  Tractogram t;
  auto add = [&](std::initializer_list<float> xyz) {
    std::vector<float> p(xyz);
    t.add_streamline(p.data(), p.size() / 3);
  };
  for (int k = -2; k <= 2; ++k) {
    const float y = 0.5f + 8.0f * k, z = 10.0f * k;
    add({-19.5f, y, z, 20.5f, y, z});
  }
  add({-19.5f, 24.5f, -20.0f, 20.5f, 24.5f, 20.0f});
  t.source.path = "depth_lines";
  return t;
}

using test::column_of;
using test::row_of;

using test::top_view;

RenderSettings opaque_fixed() {
  RenderSettings s;
  s.mode = RenderMode::Opaque;
  s.color = ColorMode::Fixed;
  s.fixed_color = {1, 1, 1};
  return s;
}

bool lit(const Image& img, int c, int r) { return img.pixel(c, r)[0] > 128; }
bool background(const Image& img, int c, int r) {
  const std::uint8_t* p = img.pixel(c, r);
  return p[0] == 0 && p[1] == 0 && p[2] == 0;
}

class ClipPlanes : public ::testing::Test {
 protected:
  void SetUp() override { gl_context(); }
  ScratchDir dir;
};

TEST_F(ClipPlanes, ParseAndPrint) {
  auto a = parse_axis_clip("x,12.5");
  ASSERT_TRUE(a);
  EXPECT_EQ(a->axis, 0);
  EXPECT_TRUE(a->keep_above);
  EXPECT_EQ(a->position, 12.5);
  auto b = parse_axis_clip("-z,-3");
  ASSERT_TRUE(b);
  EXPECT_EQ(b->axis, 2);
  EXPECT_FALSE(b->keep_above);
  EXPECT_EQ(b->position, -3);
  EXPECT_TRUE(parse_axis_clip("+Y,0"));
  for (const char* bad : {"", "x", "x,", "w,1", "x 1", "x,1mm", "--x,1", "x,nan", "-,1"})
    EXPECT_FALSE(parse_axis_clip(bad)) << bad;
  EXPECT_EQ(parse_axis_clip(axis_clip_text(*b))->position, -3);
  EXPECT_EQ(axis_clip_text(*b), "-z,-3");
}

TEST_F(ClipPlanes, SlabShowsOnlyTheLinesInsideAndDrawsFewerVoxels) {
  VxlFile f = make_scene(dir, depth_lines(), 5.0);
  Renderer r(f);
  for (RenderMode mode : {RenderMode::Opaque, RenderMode::Axis, RenderMode::Segsort, RenderMode::Exact}) {
    RenderSettings s = opaque_fixed();
    s.mode = mode;
    s.opacity = 1.0f;
    Image all = render_image(r, top_view(), s, 64, 64);
    const std::uint64_t voxels_all = r.stats().voxels_drawn;
    for (int k = -2; k <= 2; ++k) EXPECT_TRUE(lit(all, column_of(0.5), row_of(0.5 + 8 * k))) << k;

    s.clipping.slab_mm = 6;  // |z| <= 3 around the target at the origin
    Image slab = render_image(r, top_view(), s, 64, 64);
    EXPECT_LT(r.stats().voxels_drawn, voxels_all) << render_mode_name(mode);
    for (int k = -2; k <= 2; ++k) {
      for (double x : {-15.5, 0.5, 15.5}) {
        if (k == 0)
          EXPECT_TRUE(lit(slab, column_of(x), row_of(0.5))) << x;
        else
          EXPECT_TRUE(background(slab, column_of(x), row_of(0.5 + 8 * k))) << "line at z = " << 10 * k << ", x " << x;
      }
    }
    // The slanted line is cut inside its voxels: lit for |x - 0.5| <= 3, background beyond.
    EXPECT_TRUE(lit(slab, column_of(0.5), row_of(24.5)));
    EXPECT_TRUE(lit(slab, column_of(2.5), row_of(24.5)));
    EXPECT_TRUE(background(slab, column_of(5.5), row_of(24.5)));
    EXPECT_TRUE(background(slab, column_of(-4.5), row_of(24.5)));
    EXPECT_TRUE(lit(all, column_of(5.5), row_of(24.5)));

    // The slab follows the focus point: centred on z = 10 it shows the line at y = 8.5 alone.
    Camera moved = top_view();
    moved.target.z = 10;
    Image deeper = render_image(r, moved, s, 64, 64);
    EXPECT_TRUE(lit(deeper, column_of(0.5), row_of(8.5)));
    EXPECT_TRUE(background(deeper, column_of(0.5), row_of(0.5)));
    EXPECT_TRUE(background(deeper, column_of(0.5), row_of(16.5)));
  }
}

TEST_F(ClipPlanes, AxisPlanesKeepTheirSideAndCutThroughVoxels) {
  VxlFile f = make_scene(dir, depth_lines(), 5.0);
  Renderer r(f);
  RenderSettings s = opaque_fixed();
  Image all = render_image(r, top_view(), s, 64, 64);
  const std::uint64_t voxels_all = r.stats().voxels_drawn;

  s.clipping.planes = {*parse_axis_clip("x,0")};
  Image right = render_image(r, top_view(), s, 64, 64);
  EXPECT_LT(r.stats().voxels_drawn, voxels_all);
  s.clipping.planes = {*parse_axis_clip("-x,0")};
  Image left = render_image(r, top_view(), s, 64, 64);
  EXPECT_LT(r.stats().voxels_drawn, voxels_all);
  // x = 0 lies inside a voxel ([-4.5, 0.5) along x): the cut is the shader's, to the pixel.
  for (double x : {-15.5, -1.5, -0.5}) {
    EXPECT_TRUE(lit(all, column_of(x), row_of(0.5))) << x;
    EXPECT_TRUE(background(right, column_of(x), row_of(0.5))) << x;
    EXPECT_TRUE(lit(left, column_of(x), row_of(0.5))) << x;
  }
  for (double x : {0.5, 1.5, 15.5}) {
    EXPECT_TRUE(lit(right, column_of(x), row_of(0.5))) << x;
    EXPECT_TRUE(background(left, column_of(x), row_of(0.5))) << x;
  }

  // Three planes together: x >= 0, y <= 10, z >= -5 leave the lines at z = 0 and 10, right half.
  s.clipping.planes = {*parse_axis_clip("x,0"), *parse_axis_clip("-y,10"), *parse_axis_clip("z,-5")};
  Image three = render_image(r, top_view(), s, 64, 64);
  EXPECT_TRUE(lit(three, column_of(10.5), row_of(0.5)));
  EXPECT_TRUE(lit(three, column_of(10.5), row_of(8.5)));
  EXPECT_TRUE(background(three, column_of(10.5), row_of(16.5)));  // z = 20 but y = 16.5 > 10
  EXPECT_TRUE(background(three, column_of(10.5), row_of(-7.5)));  // z = -10 < -5
  EXPECT_TRUE(background(three, column_of(-10.5), row_of(0.5)));  // x < 0
  // A disabled plane is forgotten by the picture, not by the settings.
  for (AxisClip& p : s.clipping.planes) p.enabled = false;
  Image none = render_image(r, top_view(), s, 64, 64);
  EXPECT_EQ(compare_images(none, all).differing_pixels, 0u);
  EXPECT_EQ(r.stats().voxels_drawn, voxels_all);
}

TEST_F(ClipPlanes, VoxviewOptions) {
  ASSERT_TRUE(std::filesystem::exists(VOXVIEW_CLI)) << VOXVIEW_CLI;
  make_scene(dir, depth_lines(), 5.0, "lines.vxl");
  const std::string in = "'" + dir.file("lines.vxl") + "'";
  auto render = [&](const std::string& extra, const std::string& png) {
    return test::run_program(
        VOXVIEW_CLI, in + " --render '" + dir.file(png) + "' --size 64x64 --view axial --ortho --mode opaque " + extra);
  };
  auto plain = render("", "plain.png");
  ASSERT_EQ(plain.exit_code, 0) << plain.output;
  auto clipped = render("--clip -x,0 --clip z,-5", "clipped.png");
  ASSERT_EQ(clipped.exit_code, 0) << clipped.output;
  auto slab = render("--slab 4", "slab.png");
  ASSERT_EQ(slab.exit_code, 0) << slab.output;
  Image a = read_image(dir.file("plain.png")), b = read_image(dir.file("clipped.png")),
        c = read_image(dir.file("slab.png"));
  int lit_a = 0, lit_b = 0, lit_c = 0;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      lit_a += !background(a, x, y);
      lit_b += !background(b, x, y);
      lit_c += !background(c, x, y);
    }
  EXPECT_GT(lit_a, 100);
  EXPECT_LT(lit_b, lit_a * 0.6);
  EXPECT_LT(lit_c, lit_a * 0.4);
  EXPECT_GT(lit_c, 5);

  auto bad_axis = render("--clip w,3", "bad.png");
  EXPECT_EQ(bad_axis.exit_code, 2);
  EXPECT_NE(bad_axis.output.find("--clip"), std::string::npos) << bad_axis.output;
  EXPECT_NE(bad_axis.output.find("'w,3'"), std::string::npos) << bad_axis.output;
  auto four = render("--clip x,0 --clip y,0 --clip z,0 --clip -x,1", "four.png");
  EXPECT_EQ(four.exit_code, 2);
  EXPECT_NE(four.output.find("at most 3"), std::string::npos) << four.output;
  auto thin = render("--slab 0", "thin.png");
  EXPECT_EQ(thin.exit_code, 2) << thin.output;
}

}  // namespace
}  // namespace vxl
