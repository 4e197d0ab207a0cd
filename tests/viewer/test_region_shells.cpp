// The selection's regions drawn as translucent shells (region_shells.h): the half facing away under the
// lines, the half facing the viewer over them, both hidden behind the opaque slices. Pixels computed from
// the shell's colour rules (region_shapes.h), seen from above on a 64 x 64 image.
#include <cmath>
#include <cstring>
#include <filesystem>

#include "tests/nifti_test_files.h"
#include "tests/viewer/render_support.h"
#include "viewer/render/clip_planes.h"
#include "viewer/render/region_shapes.h"
#include "viewer/render/volume.h"

namespace vxl {
namespace {

using test::gl_context;
using test::make_scene;
using test::render_image;
using test::ScratchDir;
using test::top_view;

using test::column_of;
using test::row_of;

// One line along x at y = 0.5, 2 mm above z = 0 (towards the viewer), through the sphere.
Tractogram one_line() {
  Tractogram t;
  const float p[] = {-20.5f, 0.5f, 2.0f, 20.5f, 0.5f, 2.0f};
  t.add_streamline(p, 2);
  t.source.path = "line";
  return t;
}

// A 10 mm sphere around (0.5, 0.5, 0), the active include region.
RegionShape sphere() {
  RegionShape s;
  s.centre = {0.5, 0.5, 0};
  s.radius = 10;
  s.active = true;
  return s;
}

// The line opaque red.
RenderSettings red_line(RenderMode mode) {
  RenderSettings s;
  s.mode = mode;
  s.color = ColorMode::Fixed;
  s.fixed_color = {1, 0, 0};
  s.opacity = 1.0f;
  return s;
}

// colour over `under` at `alpha`, 0..255.
glm::dvec3 over(const glm::dvec3& under, const glm::vec3& colour, double alpha) {
  return under * (1 - alpha) + glm::dvec3(colour) * 255.0 * alpha;
}

void expect_pixel(const Image& img, int x, int y, const glm::dvec3& rgb, const char* what) {
  const std::uint8_t* p = img.pixel(x, y);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(p[c], rgb[c], 3.0) << what << ", channel " << c;
}

class RegionShells : public ::testing::Test {
 protected:
  void SetUp() override { gl_context(); }
  ScratchDir dir;
};

TEST_F(RegionShells, ALineInsideIsDrawnOverTheBackHalfAndUnderTheFrontHalf) {
  const VxlFile scene = make_scene(dir, one_line(), 10.0);
  Renderer r({&scene});
  const glm::vec3 green = region_shell_color(RegionShape::Role::Include);
  const double face_on = region_shell_alpha(1.0f, true);
  // 5 mm from the centre across the view, the surface normal makes cos = sqrt(1 - 0.5^2) with it.
  const double off_centre = region_shell_alpha(static_cast<float>(std::sqrt(0.75)), true);
  for (RenderMode mode :
       {RenderMode::Opaque, RenderMode::Basic, RenderMode::Axis, RenderMode::Segsort, RenderMode::Exact}) {
    SCOPED_TRACE(render_mode_name(mode));
    RenderSettings s = red_line(mode);
    s.regions = {sphere()};
    const Image img = render_image(r, top_view(), s, 64, 64);
    // The line at the sphere's centre: the back half under it is covered, the front half tints it.
    const glm::dvec3 expected = over({255, 0, 0}, green, face_on);
    expect_pixel(img, column_of(0.5), row_of(0.5), expected, "the line inside the sphere");
    // Not what the shell pasted over the picture would give (both halves over the line).
    EXPECT_GT(std::abs(img.pixel(column_of(0.5), row_of(0.5))[0] - 255 * (1 - face_on) * (1 - face_on)), 10);
    // Beside the line inside the sphere: both halves over the background.
    expect_pixel(img, column_of(0.5), row_of(5.5), over(over({0, 0, 0}, green, off_centre), green, off_centre),
                 "the two halves");
    // The line outside the sphere and the background outside it are untouched.
    expect_pixel(img, column_of(15.5), row_of(0.5), {255, 0, 0}, "the line outside");
    expect_pixel(img, column_of(0.5), row_of(15.5), {0, 0, 0}, "the background outside");
  }
}

TEST_F(RegionShells, WithoutRegionsThePictureIsTheSame) {
  const VxlFile scene = make_scene(dir, one_line(), 10.0);
  for (RenderMode mode : {RenderMode::Axis, RenderMode::Exact, RenderMode::Wboit}) {
    SCOPED_TRACE(render_mode_name(mode));
    RenderSettings plain = red_line(mode);
    plain.opacity = 0.5f;
    Renderer fresh({&scene});
    const Image before = render_image(fresh, top_view(), plain, 64, 64);
    // A renderer that drew shells, then none: nothing of them stays (state, the exact mode's base).
    Renderer used({&scene});
    RenderSettings shown = plain;
    shown.regions = {sphere()};
    const Image with = render_image(used, top_view(), shown, 64, 64);
    EXPECT_NE(with.rgba, before.rgba);
    const Image after = render_image(used, top_view(), plain, 64, 64);
    EXPECT_EQ(after.rgba, before.rgba);
  }
}

TEST_F(RegionShells, TheSlicesHideTheBackHalf) {
  const VxlFile scene = make_scene(dir, one_line(), 10.0);
  Renderer r({&scene});
  // A uniform mid-grey image over [-40, 40] mm; the axial slice through the focus (z = 0) hides what
  // lies below it, seen from above: the sphere's back half.
  Volume v;
  v.name = "grey";
  v.dims = {4, 4, 4};
  v.values.assign(64, 0.5f);
  v.voxel_to_ras = glm::dmat4(20.0);
  v.voxel_to_ras[3] = glm::dvec4(-30, -30, -30, 1);
  r.set_volume(v);
  const glm::vec3 green = region_shell_color(RegionShape::Role::Include);
  const double off_centre = region_shell_alpha(static_cast<float>(std::sqrt(0.75)), true);
  for (RenderMode mode : {RenderMode::Axis, RenderMode::Exact}) {
    SCOPED_TRACE(render_mode_name(mode));
    RenderSettings s = red_line(mode);
    s.slices.coronal = s.slices.sagittal = false;
    s.regions = {sphere()};
    const Image img = render_image(r, top_view(), s, 64, 64);
    const std::uint8_t grey = img.pixel(column_of(0.5), row_of(20.5))[0];  // the slice alone
    EXPECT_NEAR(grey, 127.5, 2);
    expect_pixel(img, column_of(0.5), row_of(5.5), over(glm::dvec3(grey), green, off_centre),
                 "the front half over the slice");
  }
}

// The slab and clip planes cut the shells where they cut the lines: a shell pixel on the cut-away side is
// the background, one on the kept side is still tinted.
TEST_F(RegionShells, TheClipPlanesAndTheSlabCutTheShells) {
  const VxlFile scene = make_scene(dir, one_line(), 10.0);
  Renderer r({&scene});
  const glm::vec3 green = region_shell_color(RegionShape::Role::Include);
  const double off_centre = region_shell_alpha(static_cast<float>(std::sqrt(0.75)), true);
  const glm::dvec3 both_halves = over(over({0, 0, 0}, green, off_centre), green, off_centre);
  for (RenderMode mode : {RenderMode::Opaque, RenderMode::Axis, RenderMode::Exact}) {
    SCOPED_TRACE(render_mode_name(mode));
    RenderSettings s = red_line(mode);
    s.regions = {sphere()};
    s.clipping.planes = {*parse_axis_clip("x,0")};  // keeps x >= 0
    const Image planed = render_image(r, top_view(), s, 64, 64);
    expect_pixel(planed, column_of(-1.5), row_of(5.5), {0, 0, 0}, "the shell beyond the plane");
    expect_pixel(planed, column_of(-1.5), row_of(0.5), {0, 0, 0}, "the line beyond the plane");
    expect_pixel(planed, column_of(0.5), row_of(5.5), both_halves, "the shell on the kept side");
    // A slab |z| <= 3 around the target keeps neither half near the sphere's centre (|z| > 8 there), and
    // both 9.8 mm from it (|z| < 2).
    s.clipping.planes.clear();
    s.clipping.slab_mm = 6;
    const Image slab = render_image(r, top_view(), s, 64, 64);
    expect_pixel(slab, column_of(0.5), row_of(5.5), {0, 0, 0}, "the shell outside the slab");
    int inner = 0, rim = 0;  // shell pixels whose centre lies within 8 mm of the sphere's axis, and beyond
    for (int y = 0; y < 64; ++y)
      for (int x = 0; x < 64; ++x) {
        if (slab.pixel(x, y)[1] == 0) continue;
        const double dx = x - 31.0 - 0.5, dy = 31.0 - y - 0.5;  // the pixel's centre from (0.5, 0.5)
        (dx * dx + dy * dy < 64 ? inner : rim) += 1;
      }
    EXPECT_EQ(inner, 0) << "the shell outside the slab";
    EXPECT_GT(rim, 0) << "the shell's rim inside the slab";
  }
}

// voxview --show-regions draws the selection's sphere; without it the picture has no shell; it needs a
// selection.
TEST_F(RegionShells, VoxviewShowRegions) {
  make_scene(dir, one_line(), 10.0, "line.vxl");
  auto render = [&](const std::string& name, const std::string& extra) {
    const test::CommandResult r = test::run_program(
        VOXVIEW_CLI, test::q(dir.file("line.vxl")) + " --render " + test::q(dir.file(name)) +
                         " --size 64x64 --ortho --view axial --include 0.5,0.5,0,10 --focus 0,0,0 " + extra);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return read_image(dir.file(name));
  };
  const Image plain = render("plain.png", "");
  const Image shown = render("shown.png", "--show-regions");
  int changed = 0, total = 0;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      const bool differs = std::memcmp(plain.pixel(x, y), shown.pixel(x, y), 3) != 0;
      changed += differs;
      ++total;
    }
  // About the sphere's disc (pi 10^2 of 64^2 mm^2 framed by the line's extent, so more pixels), no more
  // than half the picture.
  EXPECT_GT(changed, 100);
  EXPECT_LT(changed, total / 2);
  const test::CommandResult alone = test::run_program(
      VOXVIEW_CLI, test::q(dir.file("line.vxl")) + " --render " + test::q(dir.file("x.png")) + " --show-regions");
  EXPECT_EQ(alone.exit_code, 2) << alone.output;
  EXPECT_NE(alone.output.find("--show-regions"), std::string::npos) << alone.output;
  EXPECT_FALSE(std::filesystem::exists(dir.file("x.png")));
  // An image region has no shell: the picture says so rather than leaving it out unremarked.
  const std::vector<std::int16_t> all(4 * 4 * 4, 1);
  test::write_nifti_int16(dir.file("m.nii"), {4, 4, 4}, all, {10, 0, 0, -20, 0, 10, 0, -20, 0, 0, 10, -20});
  const test::CommandResult mask =
      test::run_program(VOXVIEW_CLI, test::q(dir.file("line.vxl")) + " --render " + test::q(dir.file("m.png")) +
                                         " --size 32x32 --include " + test::q(dir.file("m.nii")) +
                                         " --include 0.5,0.5,0,10 --show-regions");
  EXPECT_EQ(mask.exit_code, 0) << mask.output;
  EXPECT_NE(mask.output.find("--show-regions draws spheres and boxes: 1 image region(s) not drawn"), std::string::npos)
      << mask.output;
}

}  // namespace
}  // namespace vxl
