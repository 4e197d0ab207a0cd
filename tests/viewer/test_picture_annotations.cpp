// What voxview draws over a picture when asked (picture_annotations.h): the orientation letters at the
// edges and the axes triad, the colour bar, and --background in any colour; each checked on the pixels of
// headless pictures, and through voxview itself with saved views.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>

#include "tests/viewer/render_support.h"
#include "viewer/app/picture_annotations.h"
#include "viewer/render/background_color.h"
#include "viewer/render/colormap.h"

namespace vxl {
namespace {

using app::PictureAnnotations;
using app::PixelBox;
using test::gl_context;
using test::make_scene;
using test::ScratchDir;

constexpr int kSize = 256;

// A short ramp of values along x in the middle of the picture: the edges and corners stay background.
Tractogram small_ramp() {
  Tractogram t;
  const float p[] = {-20.5f, 0.5f, 0, 20.5f, 0.5f, 0};
  t.add_streamline(p, 2);
  t.point_values.push_back({"fa", {0.0f, 1.0f}});
  t.source.path = "ramp";
  return t;
}

RenderSettings opaque(ColorMode color) {
  RenderSettings s;
  s.mode = RenderMode::Opaque;
  s.color = color;
  return s;
}

Image read_back(const OffscreenTarget& target) {
  Image img;
  img.width = target.width();
  img.height = target.height();
  img.rgba = target.read_rgba();
  return img;
}

// The scene from above (axial), then what `annotations` draws over it.
Image annotated(Renderer& r, PictureAnnotations& annotations, const RenderSettings& s, const Camera& camera) {
  OffscreenTarget target(kSize, kSize);
  target.bind();
  r.draw(camera, s, kSize, kSize, target.framebuffer());
  target.bind();
  annotations.draw(camera, s, r, kSize, kSize);
  glFinish();
  EXPECT_EQ(glGetError(), static_cast<GLenum>(GL_NO_ERROR));
  return read_back(target);
}

bool inside(const PixelBox& b, int x, int y, int slack) {
  return x >= b.x0 - slack && x < b.x1 + slack && y >= b.y0 - slack && y < b.y1 + slack;
}

bool differs(const Image& a, const Image& b, int x, int y) {
  return !std::equal(a.pixel(x, y), a.pixel(x, y) + 3, b.pixel(x, y));
}

int differing_in(const Image& a, const Image& b, const PixelBox& box) {
  int n = 0;
  for (int y = std::max(0, int(box.y0)); y < std::min(a.height, int(std::ceil(box.y1))); ++y)
    for (int x = std::max(0, int(box.x0)); x < std::min(a.width, int(std::ceil(box.x1))); ++x) n += differs(a, b, x, y);
  return n;
}

TEST(PictureAnnotations, EdgeLettersNameTheAnatomicalDirections) {
  auto letters = [](const char* view) {
    Camera c;
    const auto v = parse_view(view);
    c.azimuth_deg = (*v)[0];
    c.elevation_deg = (*v)[1];
    const app::EdgeLetters e = app::edge_letters(c);
    return std::string{e.right, e.left, e.top, e.bottom};
  };
  // Right, left, top, bottom. From above, anterior up and the patient's right on the right; from the front
  // (coronal) the patient faces the viewer, so the patient's left is on the screen's right.
  EXPECT_EQ(letters("axial"), "RLAP");
  EXPECT_EQ(letters("inferior"), "LRAP");
  EXPECT_EQ(letters("coronal"), "LRSI");
  EXPECT_EQ(letters("posterior"), "RLSI");
  EXPECT_EQ(letters("sagittal"), "PASI");
  EXPECT_EQ(letters("right"), "APSI");
  EXPECT_EQ(app::anatomical_letter({0.2, -0.9, 0.3}), 'P');
  EXPECT_EQ(app::anatomical_letter({0.1, 0.2, -0.5}), 'I');
}

class Annotations : public ::testing::Test {
 protected:
  void SetUp() override { gl_context(); }
  ScratchDir dir;
};

TEST_F(Annotations, OrientationLabelsAndTriadDrawOnlyWhereTheLayoutPutsThemAndOnlyWhenAsked) {
  VxlFile f = make_scene(dir, small_ramp(), 5.0);
  Renderer r(f);
  PictureAnnotations annotations;
  const Camera camera = test::top_view(kSize);
  RenderSettings s = opaque(ColorMode::Direction);
  OffscreenTarget plain_target(kSize, kSize);
  plain_target.bind();
  r.draw(camera, s, kSize, kSize, plain_target.framebuffer());
  const Image plain = read_back(plain_target);
  ASSERT_GT(test::lit_pixels(plain), 20);

  // Off (the default): not one pixel changes, the colour bar alone not either (the lines are not coloured
  // by value).
  s.colorbar = true;
  EXPECT_EQ(compare_images(annotated(r, annotations, s, camera), plain).differing_pixels, 0u);
  EXPECT_EQ(annotations.layout().colorbar.x1, 0);
  s.colorbar = false;

  s.orientation_labels = true;
  const Image labelled = annotated(r, annotations, s, camera);
  const app::AnnotationLayout layout = annotations.layout();
  // Every changed pixel belongs to a letter or the triad (1 pixel of anti-aliasing around them) ...
  int changed = 0;
  for (int y = 0; y < kSize; ++y)
    for (int x = 0; x < kSize; ++x) {
      if (!differs(labelled, plain, x, y)) continue;
      ++changed;
      const bool placed =
          inside(layout.triad, x, y, 1) || std::any_of(layout.edge_labels.begin(), layout.edge_labels.end(),
                                                       [&](const PixelBox& b) { return inside(b, x, y, 1); });
      EXPECT_TRUE(placed) << "pixel " << x << "," << y << " changed outside the labels";
    }
  EXPECT_GT(changed, 100);
  // ... each letter is there, bright over the black background, at the middle of its edge ...
  for (const PixelBox& b : layout.edge_labels) {
    EXPECT_GT(differing_in(labelled, plain, b), 10) << b.x0 << "," << b.y0;
    EXPECT_TRUE(b.x0 >= 0 && b.y0 >= 0 && b.x1 <= kSize && b.y1 <= kSize);
  }
  EXPECT_NEAR((layout.edge_labels[0].y0 + layout.edge_labels[0].y1) / 2, kSize / 2, 1);  // right
  EXPECT_LT(layout.edge_labels[1].x0, 16);                                               // left
  EXPECT_NEAR((layout.edge_labels[2].x0 + layout.edge_labels[2].x1) / 2, kSize / 2, 1);  // top
  EXPECT_GT(layout.edge_labels[3].y1, kSize - 16);                                       // bottom
  // ... and the triad's x (red) and y (green) arms point right and up, as R and A do in this axial view.
  const PixelBox& t = layout.triad;
  ASSERT_TRUE(t.x0 >= 0 && t.y1 <= kSize);
  const int cx = int((t.x0 + t.x1) / 2), cy = int((t.y0 + t.y1) / 2);
  int red_right = 0, green_up = 0;
  for (int y = int(t.y0); y < int(t.y1); ++y)
    for (int x = int(t.x0); x < int(t.x1); ++x) {
      const std::uint8_t* p = labelled.pixel(x, y);
      red_right += p[0] > 200 && p[1] < 120 && x > cx + 4 && std::abs(y - cy) <= 3;
      green_up += p[1] > 200 && p[0] < 120 && y < cy - 4 && std::abs(x - cx) <= 3;
    }
  EXPECT_GT(red_right, 10);
  EXPECT_GT(green_up, 10);

  // On a white background the letters are dark.
  s.background_color = glm::vec3(1.0f);
  const Image on_white = annotated(r, annotations, s, camera);
  const PixelBox& letter = annotations.layout().edge_labels[2];
  int dark = 0;
  for (int y = int(letter.y0); y < int(letter.y1); ++y)
    for (int x = int(letter.x0); x < int(letter.x1); ++x) dark += on_white.pixel(x, y)[0] < 60;
  EXPECT_GT(dark, 5);
}

TEST_F(Annotations, TheColourBarFollowsTheColourMapFromMinimumToMaximum) {
  VxlFile f = make_scene(dir, small_ramp(), 5.0);
  Renderer r(f);
  PictureAnnotations annotations;
  const Camera camera = test::top_view(kSize);
  RenderSettings s = opaque(ColorMode::Scalar);
  s.colorbar = true;
  s.range = std::array<float, 2>{-1.0f, 3.0f};
  for (Colormap map : {Colormap::Grey, Colormap::Hot, Colormap::Viridis}) {
    s.colormap = map;
    const Image img = annotated(r, annotations, s, camera);
    const PixelBox bar = annotations.layout().colorbar;
    ASSERT_GT(bar.y1 - bar.y0, 100) << colormap_name(map);
    ASSERT_GE(bar.x1 - bar.x0, 8);
    EXPECT_LE(bar.x1, kSize);
    const int column = int((bar.x0 + bar.x1) / 2);
    // Every row but the outermost two: the colour of its centre's place between the bottom (t = 0) and the
    // top (t = 1), within the 8-bit colours the bar's corners carry.
    for (int y = int(bar.y0) + 2; y < int(bar.y1) - 2; ++y) {
      const float t = (bar.y1 - (y + 0.5f)) / (bar.y1 - bar.y0);
      const glm::vec3 want = colormap_rgb(map, t);
      for (int k = 0; k < 3; ++k)
        EXPECT_NEAR(img.pixel(column, y)[k], want[k] * 255.0f, 3.0f)
            << colormap_name(map) << " row " << y << " t " << t << " channel " << k;
    }
  }

  // The numbers and the name are drawn next to the bar: another range changes them, not the bar.
  const Image a = annotated(r, annotations, s, camera);
  const app::AnnotationLayout layout = annotations.layout();
  s.range = std::array<float, 2>{0.0f, 1.0f};
  const Image b = annotated(r, annotations, s, camera);
  EXPECT_EQ(differing_in(a, b, layout.colorbar), 0);
  EXPECT_GT(differing_in(a, b, layout.colorbar_texts), 20);
  // (The line in the middle changes colour too; the right quarter holds only the bar and its texts.)
  for (int y = 0; y < kSize; ++y)
    for (int x = kSize * 3 / 4; x < kSize; ++x)
      if (differs(a, b, x, y)) {
        EXPECT_TRUE(inside(layout.colorbar_texts, x, y, 1)) << x << "," << y;
      }
  EXPECT_GE(layout.colorbar_texts.x0, kSize * 3 / 4);
  // The name stands above the bar, in the text's colour (light over black).
  int ink_above = 0;
  for (int y = int(layout.colorbar_texts.y0); y < int(layout.colorbar.y0) - 2; ++y)
    for (int x = int(layout.colorbar_texts.x0); x < int(layout.colorbar_texts.x1); ++x)
      ink_above += a.pixel(x, y)[0] > 128;
  EXPECT_GT(ink_above, 20);
}

// The most common colour of a picture: its background.
std::array<std::uint8_t, 3> most_common(const Image& img) {
  std::map<std::array<std::uint8_t, 3>, int> counts;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) ++counts[{img.pixel(x, y)[0], img.pixel(x, y)[1], img.pixel(x, y)[2]}];
  return std::max_element(counts.begin(), counts.end(), [](auto& a, auto& b) { return a.second < b.second; })->first;
}

TEST(BackgroundColour, ParsesNamesHexAndFloatTriplesAndNamesThemBack) {
  EXPECT_EQ(parse_background_color("black"), glm::vec3(0.0f));
  EXPECT_EQ(parse_background_color("white"), glm::vec3(1.0f));
  EXPECT_EQ(parse_background_color("grey"), glm::vec3(0.5f));
  EXPECT_EQ(parse_background_color("#336699"), glm::vec3(0x33, 0x66, 0x99) / 255.0f);
  EXPECT_EQ(parse_background_color("0.1,0.2,1"), glm::vec3(0.1f, 0.2f, 1.0f));
  for (const char* bad : {"purple", "#12345", "#12345g", "1.5,0,0", "0.1,0.2", "0.1,0.2,0.3,0.4", "-0.1,0,0",
                          "0.1,0.2,0.3x", "", "nan,0,0"})
    EXPECT_FALSE(parse_background_color(bad)) << bad;
  for (const glm::vec3 c : {glm::vec3(0.0f), glm::vec3(1.0f), glm::vec3(0x33, 0x66, 0x99) / 255.0f,
                            glm::vec3(0.1f, 0.2f, 0.3f), glm::vec3(0.123456f, 1e-7f, 0.999f)})
    EXPECT_EQ(parse_background_color(background_color_text(c)), c) << background_color_text(c);
  EXPECT_EQ(background_color_text(glm::vec3(1.0f)), "white");
  EXPECT_EQ(background_color_text(glm::vec3(0x33, 0x66, 0x99) / 255.0f), "#336699");
}

class AnnotatedFigures : public ::testing::Test {
 protected:
  void SetUp() override {
    gl_context();
    ASSERT_TRUE(std::filesystem::exists(VOXVIEW_CLI)) << VOXVIEW_CLI;
    make_scene(dir, small_ramp(), 5.0, "ramp.vxl");
  }
  test::CommandResult voxview(const std::string& args) {
    return test::run_program(VOXVIEW_CLI, test::q(dir.file("ramp.vxl")) + " --size 160x120 " + args);
  }
  std::string at(const std::string& name) { return test::q(dir.file(name)); }
  Image image(const std::string& name) { return read_image(dir.file(name)); }
  ScratchDir dir;
};

TEST_F(AnnotatedFigures, TheBackgroundIsTheColourAskedFor) {
  struct Case {
    const char* option;
    std::array<std::uint8_t, 3> rgb;
  };
  for (const Case& c : {Case{"'#336699'", {0x33, 0x66, 0x99}}, Case{"0.2,0.4,1", {51, 102, 255}},
                        Case{"lightgrey", {191, 191, 191}}, Case{"white", {255, 255, 255}}}) {
    const auto r = voxview(std::string("--background ") + c.option + " --render " + at("bg.png"));
    ASSERT_EQ(r.exit_code, 0) << c.option << ": " << r.output;
    EXPECT_EQ(most_common(image("bg.png")), c.rgb) << c.option;
  }
  // The default stays black.
  ASSERT_EQ(voxview("--render " + at("default.png")).exit_code, 0);
  EXPECT_EQ(most_common(image("default.png")), (std::array<std::uint8_t, 3>{0, 0, 0}));
  // Anything else is a usage error listing the forms, and writes no picture.
  for (const char* bad : {"purple", "'#12345'", "1.5,0,0", "0.1,0.2"}) {
    const auto r = voxview(std::string("--background ") + bad + " --render " + at("bad.png"));
    EXPECT_EQ(r.exit_code, 2) << bad << ": " << r.output;
    EXPECT_NE(r.output.find("--background: expected a name (black, white"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("#RRGGBB"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("R,G,B"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir.file("bad.png"))) << bad;
  }
}

TEST_F(AnnotatedFigures, SavedViewsKeepTheLabelsTheColourBarAndTheBackground) {
  const std::string look = " --view axial --color scalar --orientation-labels --colorbar --background '#203040'";
  auto first = voxview(look + " --render " + at("a.png") + " --save-camera " + at("v.json"));
  ASSERT_EQ(first.exit_code, 0) << first.output;
  const std::string json = test::slurp<std::string>(dir.file("v.json"));
  EXPECT_NE(json.find("\"orientation_labels\": true"), std::string::npos) << json;
  EXPECT_NE(json.find("\"colorbar\": true"), std::string::npos) << json;
  EXPECT_NE(json.find("\"background\": \"#203040\""), std::string::npos) << json;

  auto replay = voxview("--render " + at("b.png") + " --camera " + at("v.json"));
  ASSERT_EQ(replay.exit_code, 0) << replay.output;
  EXPECT_EQ(compare_images(image("a.png"), image("b.png")).differing_pixels, 0u);
  // Without the labels and the bar, the same view differs: they were in the picture.
  auto bare = voxview("--view axial --color scalar --background '#203040' --render " + at("c.png"));
  ASSERT_EQ(bare.exit_code, 0) << bare.output;
  EXPECT_GT(compare_images(image("a.png"), image("c.png")).differing_pixels, 200u);

  // A colour bar needs values to show.
  auto no_values = voxview("--colorbar --render " + at("d.png"));
  EXPECT_EQ(no_values.exit_code, 2) << no_values.output;
  EXPECT_NE(no_values.output.find("--colorbar goes with --color scalar"), std::string::npos) << no_values.output;
  EXPECT_FALSE(std::filesystem::exists(dir.file("d.png")));
}

}  // namespace
}  // namespace vxl
