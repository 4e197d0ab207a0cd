// Illuminated lines: with lighting on, a line along the light is darker than one across it, by the
// amounts line_lighting.h computes; with lighting off both show the plain colour.
#include <algorithm>

#include "tests/viewer/render_support.h"
#include "viewer/render/line_lighting.h"

namespace vxl {
namespace {

using test::gl_context;
using test::make_scene;
using test::render_image;
using test::ScratchDir;

// Seen from above (eye space = world space: x right, y up, z towards the viewer), two 30 mm lines through
// their centres: one along the light direction on the left, one across it (in the screen plane, at right
// angles to the light's screen direction) on the right.
Tractogram two_lines(const glm::vec3& along, const glm::vec3& across) {
  Tractogram t;
  auto add = [&](const glm::vec3& centre, const glm::vec3& dir) {
    const glm::vec3 a = centre - 15.0f * dir, b = centre + 15.0f * dir;
    const float p[6] = {a.x, a.y, a.z, b.x, b.y, b.z};
    t.add_streamline(p, 2);
  };
  add({-15.5f, 0.5f, 0.0f}, along);
  add({16.5f, 0.5f, 0.0f}, across);
  t.source.path = "two_lines";
  return t;
}

using test::top_view;

// The brightest red value in columns [x0, x1).
int brightest(const Image& img, int x0, int x1) {
  int best = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = x0; x < x1; ++x) best = std::max(best, int(img.pixel(x, y)[0]));
  return best;
}

class Lighting : public ::testing::Test {
 protected:
  void SetUp() override { gl_context(); }
  ScratchDir dir;
};

TEST_F(Lighting, ALineAlongTheLightIsDarkerThanOneAcrossIt) {
  const glm::vec3 light = lighting::light_direction_eye();
  // Across: in the screen plane, perpendicular to the light's projection on it (so L.T = 0).
  const glm::vec3 across = glm::normalize(glm::vec3(light.y, -light.x, 0.0f));
  VxlFile f = make_scene(dir, two_lines(light, across), 10.0);
  Renderer r(f);
  RenderSettings s;
  s.mode = RenderMode::Opaque;
  s.color = ColorMode::Fixed;
  s.fixed_color = {0.5f, 0.5f, 0.5f};

  Image off = render_image(r, top_view(96), s, 96, 96);
  const int off_along = brightest(off, 0, 48), off_across = brightest(off, 48, 96);
  EXPECT_NEAR(off_along, 128, 1);
  EXPECT_EQ(off_along, off_across);

  s.lighting = true;
  Image on = render_image(r, top_view(96), s, 96, 96);
  const int on_along = brightest(on, 0, 48), on_across = brightest(on, 48, 96);
  const glm::vec3 view(0, 0, 1);
  const float expect_along = lighting::lit_colour(s.fixed_color, light, view).r;
  const float expect_across = lighting::lit_colour(s.fixed_color, across, view).r;
  EXPECT_LT(expect_along, 0.2f);   // the model: ambient only
  EXPECT_GT(expect_across, 0.8f);  // full diffuse and the specular peak
  EXPECT_NEAR(on_along, expect_along * 255, 2);
  EXPECT_NEAR(on_across, expect_across * 255, 2);
  EXPECT_LT(on_along + 60, on_across);

  // Running the other way round lights the same.
  VxlFile g = make_scene(dir, two_lines(-light, -across), 10.0, "reversed.vxl");
  Renderer rg(g);
  Image reversed = render_image(rg, top_view(96), s, 96, 96);
  EXPECT_NEAR(brightest(reversed, 0, 48), on_along, 1);
  EXPECT_NEAR(brightest(reversed, 48, 96), on_across, 1);

  // Every transparency mode goes through the same vertex shader.
  for (RenderMode m : {RenderMode::Axis, RenderMode::Unsorted, RenderMode::Wboit}) {
    s.mode = m;
    s.opacity = 1.0f;
    Image img = render_image(r, top_view(96), s, 96, 96);
    EXPECT_LT(brightest(img, 0, 48) + 60, brightest(img, 48, 96)) << render_mode_name(m);
  }
}

}  // namespace
}  // namespace vxl
