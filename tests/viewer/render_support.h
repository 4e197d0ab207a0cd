// Shared by the render tests: one headless GL context per process, hand-made scenes converted to .vxl,
// and rendering a frame to an image.
#pragma once

#include <cstdlib>
#include <memory>
#include <string>

#include "converter/convert/convert.h"
#include "format/vxl_file.h"
#include "tests/test_support.h"
#include "viewer/platform/egl_context.h"
#include "viewer/platform/image_io.h"
#include "viewer/platform/offscreen_target.h"
#include "viewer/render/camera.h"
#include "viewer/render/exact_renderer.h"
#include "viewer/render/render_settings.h"
#include "viewer/render/renderer.h"

namespace vxl::test {

inline HeadlessGlContext& gl_context() {
  static HeadlessGlContext context;
  context.make_current();
  return context;
}

// Converts `t` to a .vxl in `dir` and opens it.
inline VxlFile make_scene(const ScratchDir& dir, Tractogram t, double voxel_size,
                          const std::string& name = "scene.vxl") {
  ConvertSettings s;
  s.voxel_size = voxel_size;
  std::string path = dir.file(name);
  convert_tractogram(std::move(t), path, s);
  return VxlFile::open(path);
}

// Pixels whose colour is not black.
inline int lit_pixels(const Image& img) {
  int n = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) n += (img.pixel(x, y)[0] | img.pixel(x, y)[1] | img.pixel(x, y)[2]) != 0;
  return n;
}

// An orthographic view from above (+z), `height_mm` of the scene over the image height: on a
// 64-pixel image at the default, world (x, y) is the centre of pixel (x + 31.5, 31.5 - y).
inline Camera top_view(double height_mm = 64) {
  Camera c;
  c.orthographic = true;
  c.ortho_height = height_mm;
  c.distance = 100;
  c.azimuth_deg = 180;
  c.elevation_deg = 90;
  return c;
}

// The synthetic brain (`voxlines synth`, centred near (0, -15, 10)) seen whole from the front left and above.
inline Camera synth_brain_view(double distance = 320) {
  Camera c;
  c.target = glm::dvec3(0, -15, 10);
  c.distance = distance;
  c.azimuth_deg = 30;
  c.elevation_deg = 20;
  return c;
}

// The pixel column and row whose centre world x and y fall in, under top_view() on a 64 x 64 image.
inline int column_of(double x) { return static_cast<int>(x + 31.5); }
inline int row_of(double y) { return static_cast<int>(31.5 - y); }

inline Image render_image(Renderer& r, const Camera& camera, const RenderSettings& settings, int w, int h) {
  OffscreenTarget target(w, h);
  target.bind();
  r.draw(camera, settings, w, h, target.framebuffer());
  glFinish();
  EXPECT_EQ(glGetError(), static_cast<GLenum>(GL_NO_ERROR)) << render_mode_name(settings.mode);
  Image img;
  img.width = w;
  img.height = h;
  img.rgba = target.read_rgba();
  // VOXLINES_TEST_IMAGES=DIR keeps every rendered image, for looking at a failure.
  if (const char* keep = std::getenv("VOXLINES_TEST_IMAGES")) {
    static int n = 0;
    write_png(std::string(keep) + "/" + std::to_string(n++) + "_" + render_mode_name(settings.mode) + ".png", img);
  }
  return img;
}

}  // namespace vxl::test
