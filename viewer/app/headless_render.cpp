#include "headless_render.h"

#include <chrono>
#include <cstdio>

#include "egl_context.h"
#include "image_io.h"
#include "offscreen_target.h"
#include "renderer.h"
#include "scene_source.h"

namespace vxl::app {

Camera initial_camera(const glm::dvec3& lo, const glm::dvec3& hi, const ViewerOptions& options, double aspect) {
  Camera c;
  c.orthographic = options.orthographic;
  auto view = options.view.value_or(std::array<double, 2>{-35.0, 25.0});
  c.azimuth_deg = view[0];
  c.elevation_deg = view[1];
  c.frame(lo, hi, aspect);
  return c;
}

int run_headless(const ViewerOptions& o) {
  auto t0 = std::chrono::steady_clock::now();
  VxlFile file = open_scene(o.input, o.voxel_size);
  HeadlessGlContext context;
  Renderer renderer(file);
  OffscreenTarget target(o.width, o.height);
  target.bind();
  const double aspect = double(o.width) / o.height;
  Camera camera = initial_camera(renderer.bounds_min(), renderer.bounds_max(), o, aspect);
  renderer.draw(camera, o.settings, o.width, o.height, target.framebuffer());
  std::vector<std::uint8_t> rgba = target.read_rgba();
  double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  write_png(*o.render_png, o.width, o.height, rgba);
  const FrameStats& s = renderer.stats();
  std::printf("%s: %dx%d %s, %llu voxels and %llu segments drawn, first frame after %.3f s (%s)\n",
              o.render_png->c_str(), o.width, o.height, render_mode_name(o.settings.mode),
              (unsigned long long)s.voxels_drawn, (unsigned long long)s.segments_drawn, seconds,
              context.renderer().c_str());
  return 0;
}

}  // namespace vxl::app
