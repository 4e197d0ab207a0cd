// A selection drawn as focus and context (voxview --include ...): the selected streamlines and the others
// are groups with their own opacity, drawn in the one back-to-front pass, so that a focus line behind a
// context line is seen through it and one in front covers it — computed pixels, in axis and exact.
#include <cmath>

#include "converter/selection/streamline_selection.h"
#include "tests/viewer/render_support.h"
#include "viewer/render/scene_groups.h"

namespace vxl {
namespace {

using test::gl_context;
using test::make_scene;
using test::render_image;
using test::ScratchDir;
using test::top_view;

using test::column_of;
using test::row_of;

// Line 0 along x at y = 0.5, 10 mm above (in front, seen from above); line 1 along y at x = 0.5, 10 mm
// below. They cross at pixel (32, 31).
Tractogram crossing_lines() {
  Tractogram t;
  const float front[] = {-20.5f, 0.5f, 10.0f, 20.5f, 0.5f, 10.0f};
  const float back[] = {0.5f, -20.5f, -10.0f, 0.5f, 20.5f, -10.0f};
  t.add_streamline(front, 2);
  t.add_streamline(back, 2);
  t.source.path = "crossing";
  return t;
}

RenderSettings focus_red_context_blue(float focus, float context) {
  RenderSettings s;
  s.color = ColorMode::Group;
  s.opacity = std::max(focus, context);
  GroupStyle& f = s.style_of(SceneGroups::kSelected);
  f.color = glm::vec3(1, 0, 0);
  f.opacity = focus / s.opacity;
  GroupStyle& c = s.style_of(SceneGroups::kContext);
  c.color = glm::vec3(0, 0, 1);
  c.opacity = context / s.opacity;
  return s;
}

class FocusContext : public ::testing::Test {
 protected:
  void SetUp() override { gl_context(); }
  ScratchDir dir;
};

TEST_F(FocusContext, FocusAndContextInterleaveInDepthInOnePass) {
  const VxlFile scene = make_scene(dir, crossing_lines(), 10.0);
  const std::vector<const VxlFile*> files = {&scene};
  const float af = 0.8f, ac = 0.4f;
  struct Case {
    const char* region;  // selects one of the two lines (a sphere around one of its end points)
    double red, blue;    // the crossing pixel, 0..1
  };
  const Case cases[] = {
      // The front line selected: drawn last, over the context line behind it.
      {"20.5,0.5,10,1", af, (1 - af) * ac},
      // The back line selected: seen through the context line in front of it.
      {"0.5,20.5,-10,1", (1 - ac) * af, ac},
  };
  for (const Case& c : cases) {
    SelectionCriteria criteria;
    criteria.include.push_back(parse_region(c.region));
    const std::vector<std::uint64_t> kept = select_streamlines(scene, criteria).streamlines;
    ASSERT_EQ(kept.size(), 1u) << c.region;
    Renderer r(files);
    r.set_groups(SceneGroups::selection(files, {kept}));
    for (RenderMode mode : {RenderMode::Axis, RenderMode::Exact}) {
      SCOPED_TRACE(std::string(render_mode_name(mode)) + " " + c.region);
      RenderSettings s = focus_red_context_blue(af, ac);
      s.mode = mode;
      const Image img = render_image(r, top_view(), s, 64, 64);
      const std::uint8_t* cross = img.pixel(column_of(0.5), row_of(0.5));
      EXPECT_NEAR(cross[0], 255 * c.red, 3);
      EXPECT_NEAR(cross[1], 0, 2);
      EXPECT_NEAR(cross[2], 255 * c.blue, 3);
      // Away from the crossing each line shows alone, at its own opacity and colour.
      const bool front_selected = kept[0] == 0;
      const std::uint8_t* front = img.pixel(column_of(10), row_of(0.5));
      const std::uint8_t* back = img.pixel(column_of(0.5), row_of(10));
      EXPECT_NEAR(front[front_selected ? 0 : 2], 255 * (front_selected ? af : ac), 3);
      EXPECT_NEAR(back[front_selected ? 2 : 0], 255 * (front_selected ? ac : af), 3);
    }
  }
}

TEST_F(FocusContext, ContextOpacityZeroHidesTheRest) {
  const VxlFile scene = make_scene(dir, crossing_lines(), 10.0);
  const std::vector<const VxlFile*> files = {&scene};
  Renderer r(files);
  r.set_groups(SceneGroups::selection(files, {{1}}));
  for (RenderMode mode : {RenderMode::Axis, RenderMode::Exact}) {
    RenderSettings s = focus_red_context_blue(0.8f, 0.0f);
    s.mode = mode;
    const Image img = render_image(r, top_view(), s, 64, 64);
    EXPECT_EQ(img.pixel(column_of(10), row_of(0.5))[2], 0) << render_mode_name(mode);  // the context line
    EXPECT_NEAR(img.pixel(column_of(0.5), row_of(0.5))[0], 255 * 0.8, 3) << render_mode_name(mode);
  }
}

// A region moved in the window: the renderer gets a new selection (set_groups) and uploads only the byte
// per streamline; its picture is that of a renderer made for the new selection, in every mode, for every
// file of the scene (the second file's streamlines come after the first's in that table).
TEST_F(FocusContext, ANewSelectionOnTheSameRendererDrawsAsAFreshRenderer) {
  const VxlFile a = make_scene(dir, crossing_lines(), 10.0, "a.vxl");
  Tractogram shifted = crossing_lines();
  for (std::size_t i = 0; i < shifted.positions.size(); i += 3) shifted.positions[i] += 5.0f;  // x + 5 mm
  const VxlFile b = make_scene(dir, std::move(shifted), 10.0, "b.vxl");
  const std::vector<const VxlFile*> files = {&a, &b};
  Renderer moving(files);
  const std::vector<std::vector<std::vector<std::uint64_t>>> selections = {{{0}, {1}}, {{1}, {}}, {{}, {0, 1}}};
  for (RenderMode mode : {RenderMode::Axis, RenderMode::Wboit, RenderMode::Exact}) {
    RenderSettings s = focus_red_context_blue(0.8f, 0.3f);
    s.mode = mode;
    for (const auto& kept : selections) {
      SCOPED_TRACE(std::string(render_mode_name(mode)) + " selection " + std::to_string(&kept - &selections[0]));
      moving.set_groups(SceneGroups::selection(files, kept));
      const Image updated = render_image(moving, top_view(), s, 64, 64);
      Renderer fresh(files);
      fresh.set_groups(SceneGroups::selection(files, kept));
      const Image expected = render_image(fresh, top_view(), s, 64, 64);
      EXPECT_EQ(updated.rgba, expected.rgba);
      // And the selection shows: some red (focus) pixel exactly when something is selected.
      bool red = false;
      for (std::size_t p = 0; p + 3 < updated.rgba.size(); p += 4) red |= updated.rgba[p] > 100;
      EXPECT_EQ(red, !kept[0].empty() || !kept[1].empty());
    }
  }
}

// voxview --include: the command line selects and draws (the picture's focus red, the context hidden), and
// the opacities need a selection.
TEST_F(FocusContext, VoxviewSelectsFromTheCommandLine) {
  make_scene(dir, crossing_lines(), 10.0, "lines.vxl");
  const std::string png = dir.file("sel.png");
  const test::CommandResult r = test::run_program(
      VOXVIEW_CLI, test::q(dir.file("lines.vxl")) + " --render " + test::q(png) +
                       " --size 64x64 --ortho --view axial --include 0.5,20.5,-10,1 --context-opacity 0 --color group "
                       "--group selected=#ff0000 --focus-opacity 1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("1 of 2 streamlines selected"), std::string::npos) << r.output;
  const Image img = read_image(png);
  int red = 0, other = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const std::uint8_t* p = img.pixel(x, y);
      if (p[0] > 200 && p[1] < 30 && p[2] < 30)
        ++red;
      else if (p[0] | p[1] | p[2])
        ++other;
    }
  EXPECT_GT(red, 20);   // the selected line, the whole framed height
  EXPECT_EQ(other, 0);  // nothing of the hidden context
  const test::CommandResult alone = test::run_program(
      VOXVIEW_CLI, test::q(dir.file("lines.vxl")) + " --render " + test::q(dir.file("x.png")) + " --context-opacity 0");
  EXPECT_EQ(alone.exit_code, 2) << alone.output;
  const test::CommandResult bad = test::run_program(
      VOXVIEW_CLI, test::q(dir.file("lines.vxl")) + " --render " + test::q(dir.file("y.png")) + " --include 0,0,0,-2");
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("0,0,0,-2"), std::string::npos) << bad.output;
  EXPECT_FALSE(std::filesystem::exists(dir.file("y.png")));
}

// A saved view keeps the selection: replayed without any region on the command line, the same picture.
TEST_F(FocusContext, ASavedViewKeepsTheSelectionAndItsShells) {
  make_scene(dir, crossing_lines(), 10.0, "lines.vxl");
  const std::string in = test::q(dir.file("lines.vxl"));
  const test::CommandResult save =
      test::run_program(VOXVIEW_CLI, in + " --render " + test::q(dir.file("a.png")) +
                                         " --size 64x64 --include 0.5,20.5,-10,1 --context-opacity 0.1 --save-camera " +
                                         test::q(dir.file("v.json")));
  ASSERT_EQ(save.exit_code, 0) << save.output;
  const test::CommandResult replay = test::run_program(
      VOXVIEW_CLI, in + " --render " + test::q(dir.file("b.png")) + " --camera " + test::q(dir.file("v.json")));
  ASSERT_EQ(replay.exit_code, 0) << replay.output;
  EXPECT_NE(replay.output.find("1 of 2 streamlines selected"), std::string::npos) << replay.output;
  EXPECT_EQ(test::slurp(dir.file("a.png")), test::slurp(dir.file("b.png")));

  // With the shells drawn, the view says so and its replay draws them too; without, it does not.
  const test::CommandResult shells =
      test::run_program(VOXVIEW_CLI, in + " --render " + test::q(dir.file("c.png")) +
                                         " --size 64x64 --include 0.5,20.5,-10,8 --show-regions --save-camera " +
                                         test::q(dir.file("w.json")));
  ASSERT_EQ(shells.exit_code, 0) << shells.output;
  auto text = [&](const char* name) {
    const std::vector<char> bytes = test::slurp(dir.file(name));
    return std::string(bytes.begin(), bytes.end());
  };
  EXPECT_NE(text("w.json").find("\"show_regions\": true"), std::string::npos);
  const test::CommandResult again = test::run_program(
      VOXVIEW_CLI, in + " --render " + test::q(dir.file("d.png")) + " --camera " + test::q(dir.file("w.json")));
  ASSERT_EQ(again.exit_code, 0) << again.output;
  EXPECT_EQ(test::slurp(dir.file("c.png")), test::slurp(dir.file("d.png")));
  EXPECT_NE(test::slurp(dir.file("c.png")), test::slurp(dir.file("a.png")));
  EXPECT_NE(text("v.json").find("\"show_regions\": false"), std::string::npos);
}

}  // namespace
}  // namespace vxl
