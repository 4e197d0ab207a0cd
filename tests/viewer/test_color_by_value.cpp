// Colour by value and by group: pixels of hand-made scenes against the colour maps and the palette, and the
// real TSF / TRX fixtures through voxview.
#include <cmath>
#include <filesystem>
#include <set>

#include "tests/viewer/render_support.h"
#include "viewer/render/scene_groups.h"

namespace vxl {
namespace {

using test::gl_context;
using test::make_scene;
using test::real;
using test::render_image;
using test::ScratchDir;

using test::column_of;
using test::row_of;
using test::top_view;

RenderSettings opaque(ColorMode color) {
  RenderSettings s;
  s.mode = RenderMode::Opaque;
  s.color = color;
  s.fixed_color = {1, 1, 1};
  return s;
}

void expect_colour(const Image& img, int c, int r, const glm::vec3& rgb, int tolerance, const std::string& what) {
  const std::uint8_t* p = img.pixel(c, r);
  for (int k = 0; k < 3; ++k)
    EXPECT_NEAR(p[k], rgb[k] * 255.0f, tolerance) << what << " channel " << k << " at " << c << "," << r;
}

bool is_background(const Image& img, int c, int r) {
  return (img.pixel(c, r)[0] | img.pixel(c, r)[1] | img.pixel(c, r)[2]) == 0;
}

// A 40 mm line along x on row y = 0.5, valued 0 at x = -19.5 and 1 at x = 20.5; two points only, so the
// values of the points inserted at the 5 mm voxel faces are interpolated.
Tractogram ramp() {
  Tractogram t;
  const float p[] = {-19.5f, 0.5f, 0, 20.5f, 0.5f, 0};
  t.add_streamline(p, 2);
  t.point_values.push_back({"t", {0.0f, 1.0f}});
  t.source.path = "ramp";
  return t;
}

// Four lines along x on rows y = 12.5, 4.5, -3.5, -11.5, with per-streamline values 0, 0.5, 1, NaN and
// groups A = {0, 2}, B = {1}; line 3 is in no group.
Tractogram four_lines() {
  Tractogram t;
  for (int k = 0; k < 4; ++k) {
    const float y = 12.5f - 8.0f * k;
    const float p[] = {-15.5f, y, 0, 16.5f, y, 0};
    t.add_streamline(p, 2);
  }
  t.streamline_values.push_back({"score", {0.0f, 0.5f, 1.0f, NAN}});
  t.groups = {{"A", {0, 2}}, {"B", {1}}};
  t.source.path = "four_lines";
  return t;
}
double line_y(int k) { return 12.5 - 8.0 * k; }

class ColorByValue : public ::testing::Test {
 protected:
  void SetUp() override { gl_context(); }
  ScratchDir dir;
};

TEST_F(ColorByValue, PointValuesFollowTheColourMapAlongTheLine) {
  VxlFile f = make_scene(dir, ramp(), 5.0);
  ASSERT_GT(f.meta().synthetic_point_count, 3u);
  Renderer r(f);
  EXPECT_EQ(r.value_set_names(), std::vector<std::string>{"t"});
  RenderSettings s = opaque(ColorMode::Scalar);
  for (Colormap map : {Colormap::Grey, Colormap::Hot, Colormap::Viridis}) {
    s.colormap = map;
    Image img = render_image(r, top_view(), s, 64, 64);
    for (double x : {-18.5, -10.5, -0.5, 4.5, 12.5, 19.5}) {
      const float t = static_cast<float>((x + 19.5) / 40.0);
      expect_colour(img, column_of(x), row_of(0.5), colormap_rgb(map, t), 3, colormap_name(map));
    }
  }
  // The range maps values to the map's ends and clamps beyond.
  s.colormap = Colormap::Grey;
  s.range = std::array<float, 2>{0.25f, 0.75f};
  Image ranged = render_image(r, top_view(), s, 64, 64);
  expect_colour(ranged, column_of(-15.5), row_of(0.5), glm::vec3(0.0f), 2, "below the range");
  expect_colour(ranged, column_of(0.5), row_of(0.5), glm::vec3(0.5f), 3, "mid range");
  expect_colour(ranged, column_of(15.5), row_of(0.5), glm::vec3(1.0f), 2, "above the range");
  // The other colour modes ignore the values.
  Image fixed = render_image(r, top_view(), opaque(ColorMode::Fixed), 64, 64);
  expect_colour(fixed, column_of(-15.5), row_of(0.5), glm::vec3(1.0f), 0, "fixed");
}

TEST_F(ColorByValue, StreamlineValuesAndMissingOnes) {
  VxlFile f = make_scene(dir, four_lines(), 5.0);
  Renderer r(f);
  RenderSettings s = opaque(ColorMode::Scalar);
  s.colormap = Colormap::Hot;
  s.fixed_color = {0.2f, 0.4f, 0.6f};
  Image img = render_image(r, top_view(), s, 64, 64);
  EXPECT_EQ(r.scalar_range(s), (std::array<float, 2>{0.0f, 1.0f}));  // the stored extremes, NaN left out
  for (int k = 0; k < 3; ++k)
    for (double x : {-12.5, 0.5, 13.5})
      expect_colour(img, column_of(x), row_of(line_y(k)), colormap_rgb(Colormap::Hot, 0.5f * k), 3,
                    "line " + std::to_string(k));
  expect_colour(img, column_of(0.5), row_of(line_y(3)), s.fixed_color, 1, "a NaN value keeps the fixed colour");
}

TEST_F(ColorByValue, GroupsHaveTheirColourAndOpacity) {
  VxlFile f = make_scene(dir, four_lines(), 5.0);
  Renderer r(f);
  const auto& groups = r.groups().groups();
  ASSERT_EQ(groups.size(), 3u);
  EXPECT_EQ(groups[0].name, "A");
  EXPECT_EQ(groups[1].name, "B");
  EXPECT_EQ(groups[2].name, "(ungrouped)");
  EXPECT_EQ(groups[0].streamlines, 2u);
  RenderSettings s = opaque(ColorMode::Group);
  Image img = render_image(r, top_view(), s, 64, 64);
  const int group_of_line[4] = {0, 1, 0, 2};
  for (int k = 0; k < 4; ++k)
    expect_colour(img, column_of(0.5), row_of(line_y(k)), group_palette(group_of_line[k]), 1, "group");
  EXPECT_NE(group_palette(0), group_palette(1));

  // A chosen colour, and a hidden group: gone even in the opaque mode, and fewer segments on screen.
  s.style_of("A").color = glm::vec3(1, 0, 0);
  s.style_of("B").opacity = 0;
  Image styled = render_image(r, top_view(), s, 64, 64);
  expect_colour(styled, column_of(0.5), row_of(line_y(0)), glm::vec3(1, 0, 0), 0, "A");
  expect_colour(styled, column_of(0.5), row_of(line_y(2)), glm::vec3(1, 0, 0), 0, "A");
  for (double x : {-12.5, 0.5, 13.5}) EXPECT_TRUE(is_background(styled, column_of(x), row_of(line_y(1)))) << x;
  expect_colour(styled, column_of(0.5), row_of(line_y(3)), group_palette(2), 1, "ungrouped");

  // Group opacity is a factor on the opacity, in every colour mode: B at half of 1, blended over black.
  s.style_of("B").opacity = 0.5f;
  s.mode = RenderMode::Axis;
  s.opacity = 1.0f;
  s.color = ColorMode::Fixed;
  Image half = render_image(r, top_view(), s, 64, 64);
  expect_colour(half, column_of(0.5), row_of(line_y(1)), glm::vec3(0.5f), 2, "B at half opacity");
  expect_colour(half, column_of(0.5), row_of(line_y(0)), glm::vec3(1.0f), 1, "A at full opacity");
}

TEST_F(ColorByValue, ManyTextureSpansColourLikeOne) {
  Tractogram t;
  std::vector<float> along;
  for (int s = 0; s < 40; ++s) {
    std::vector<float> p;
    for (int i = 0; i < 30; ++i) {
      p.insert(p.end(), {float(-25 + 1.7 * i), float(-20 + s), float(std::sin(0.3 * i + s) * 8)});
      along.push_back(float(i + s));
    }
    t.add_streamline(p.data(), 30);
  }
  t.point_values.push_back({"along", along});
  VxlFile f = make_scene(dir, std::move(t), 6.0);
  // Spans of a few voxels each.
  Renderer one(f), many(f, 4 * SceneLayout::largest_voxel_texels(std::vector<const VxlFile*>{&f}));
  EXPECT_GT(many.layout().texture_spans().size(), 3u);
  Camera cam = top_view();
  cam.azimuth_deg = 30;
  cam.elevation_deg = 40;
  RenderSettings s = opaque(ColorMode::Scalar);
  Image a = render_image(one, cam, s, 64, 64), b = render_image(many, cam, s, 64, 64);
  EXPECT_EQ(compare_images(a, b).differing_pixels, 0u);
  std::set<int> reds;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) reds.insert(a.pixel(x, y)[0]);
  EXPECT_GT(reds.size(), 20u) << "a spread of values, not one colour";
}

// voxview on the real fixtures: the TSFs colour their tractograms, the AFQ TRX shows its two groups.
class ColorByValueReal : public ::testing::Test {
 protected:
  void SetUp() override {
    VXL_REQUIRE_REAL_DATA();
    ASSERT_TRUE(std::filesystem::exists(VOXVIEW_CLI)) << VOXVIEW_CLI;
  }
  Image render(const std::string& args) {
    const std::string png = dir.file("out.png");
    std::filesystem::remove(png);
    auto r = test::run_program(VOXVIEW_CLI, args + " --render '" + png + "' --size 128x128 --mode opaque");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return std::filesystem::exists(png) ? read_image(png) : Image{};
  }
  ScratchDir dir;
};

struct Colours {
  std::set<std::array<int, 3>> distinct;
  int lit = 0, not_grey = 0, not_hot = 0;
};
Colours colours_of(const Image& img) {
  Colours c;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const std::uint8_t* p = img.pixel(x, y);
      if ((p[0] | p[1] | p[2]) == 0) continue;
      ++c.lit;
      c.distinct.insert({p[0], p[1], p[2]});
      c.not_grey += !(p[0] == p[1] && p[1] == p[2]);
      c.not_hot += !(p[0] + 1 >= p[1] && p[1] + 1 >= p[2]);  // hot: red >= green >= blue
    }
  return c;
}

TEST_F(ColorByValueReal, TsfFilesColourTheirTractograms) {
  const std::string slf =
      "'" + real("niivue__tract.SLF1_R.tck") + "' --tsf '" + real("niivue__mni152.SLF1_R.tsf") + "'";
  Colours grey = colours_of(render(slf + " --color scalar --colormap grey --line-width 2"));
  EXPECT_GT(grey.lit, 200);
  EXPECT_EQ(grey.not_grey, 0);
  EXPECT_GT(grey.distinct.size(), 20u) << "the TSF's values, not one colour";
  Colours fixed = colours_of(render(slf + " --color fixed --fixed-color '#ffffff' --line-width 2"));
  EXPECT_EQ(fixed.distinct.size(), 1u);

  // Converted once, then opened as .vxl.
  const std::string vxl = dir.file("tracks.vxl");
  auto c = test::run_cli("convert '" + real("test_data__tracks.tck") + "' '" + vxl + "' --tsf '" +
                         real("test_data__afd.tsf") + "'");
  ASSERT_EQ(c.exit_code, 0) << c.output;
  Colours hot = colours_of(render("'" + vxl + "' --color scalar --colormap hot"));
  EXPECT_GT(hot.lit, 500);
  EXPECT_EQ(hot.not_hot, 0);
  EXPECT_GT(hot.distinct.size(), 30u);

  // A TSF of another tractogram is refused, naming it.
  auto wrong =
      test::run_program(VOXVIEW_CLI, "'" + real("niivue__tract.SLF1_R.tck") + "' --tsf '" + real("test_data__afd.tsf") +
                                         "' --render '" + dir.file("x.png") + "'");
  EXPECT_EQ(wrong.exit_code, 3);
  EXPECT_NE(wrong.output.find("test_data__afd.tsf"), std::string::npos) << wrong.output;
  // Scalar colouring of a file without values says what to do.
  auto none = test::run_program(
      VOXVIEW_CLI, "'" + real("niivue__tract.SLF1_R.tck") + "' --color scalar --render '" + dir.file("x.png") + "'");
  EXPECT_EQ(none.exit_code, 2);
  EXPECT_NE(none.output.find("--tsf"), std::string::npos) << none.output;
}

TEST_F(ColorByValueReal, AfqTrxShowsItsTwoGroupsInTwoColours) {
  const std::string afq =
      "'" + real("niivue__sub-01_ses-01_dwi_space-RASMM_model-probCSD_algo-AFQ_tractography.trx") + "'";
  auto count_near = [](const Image& img, const glm::vec3& rgb) {
    int n = 0;
    for (int y = 0; y < img.height; ++y)
      for (int x = 0; x < img.width; ++x) {
        const std::uint8_t* p = img.pixel(x, y);
        bool near = true;
        for (int k = 0; k < 3; ++k) near &= std::abs(p[k] - rgb[k] * 255.0f) <= 2;
        n += near;
      }
    return n;
  };
  Image both = render(afq + " --color group");
  const int arc_l = count_near(both, group_palette(0)), arc_r = count_near(both, group_palette(1));
  EXPECT_GT(arc_l, 100);
  EXPECT_GT(arc_r, 50);
  EXPECT_EQ(arc_l + arc_r, colours_of(both).lit) << "every line pixel is one of the two group colours";
  Image one = render(afq + " --color group --group 'ARC_R=:0' --group 'ARC_L=#ff0000'");
  EXPECT_EQ(count_near(one, group_palette(1)), 0);
  EXPECT_EQ(count_near(one, glm::vec3(1, 0, 0)), colours_of(one).lit);
  auto unknown = test::run_program(VOXVIEW_CLI, afq + " --group 'CST=#00ff00' --render '" + dir.file("x.png") + "'");
  EXPECT_EQ(unknown.exit_code, 2);
  EXPECT_NE(unknown.output.find("ARC_L, ARC_R"), std::string::npos) << unknown.output;
}

}  // namespace
}  // namespace vxl
