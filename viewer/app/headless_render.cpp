#include "viewer/app/headless_render.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "format/base/memory_size.h"
#include "viewer/app/camera_file.h"
#include "viewer/app/picture_annotations.h"
#include "viewer/app/process_clock.h"
#include "viewer/app/region_editor.h"
#include "viewer/app/render_stats.h"
#include "viewer/app/scene_selection.h"
#include "viewer/app/scene_source.h"
#include "viewer/app/turntable.h"
#include "viewer/app/viewer_session.h"
#include "viewer/platform/egl_context.h"
#include "viewer/platform/image_io.h"
#include "viewer/platform/offscreen_target.h"
#include "viewer/render/renderer.h"
#include "viewer/render/scene_framing.h"

namespace vxl::app {

Camera initial_camera(std::span<const glm::dvec3> points, const ViewerOptions& options, double aspect) {
  if (options.camera) {
    // A saved view is used as saved; --view and --ortho given as well still turn it.
    Camera c = *options.camera;
    if (options.orthographic) c.orthographic = true;
    if (options.view) {
      c.azimuth_deg = (*options.view)[0];
      c.elevation_deg = (*options.view)[1];
    }
    if (options.focus) c.target = *options.focus;
    return c;
  }
  Camera c;
  c.orthographic = options.orthographic;
  auto view = options.view.value_or(kDefaultView);
  c.azimuth_deg = view[0];
  c.elevation_deg = view[1];
  if (options.turntable > 1) {
    glm::dvec3 lo(0.0), hi(0.0);
    if (!points.empty()) lo = hi = points[0];
    for (const glm::dvec3& p : points) lo = glm::min(lo, p), hi = glm::max(hi, p);
    const glm::dvec3 pivot = (lo + hi) * 0.5;
    c.frame_points_about(turntable_points(points, pivot, options.turntable), pivot, aspect);
  } else {
    c.frame_points(points, aspect);
  }
  if (options.focus) c.target = *options.focus;
  return c;
}

int run_headless(const ViewerOptions& o) {
  auto t0 = std::chrono::steady_clock::now();
  RenderStats stats;  // for --stats
  stats.main_s = seconds_before_main();
  for (const std::string& note : o.notes) std::fprintf(stderr, "voxview: note: %s\n", note.c_str());
  // Made after the files are open, gone after the session's renderers: declared first, made later.
  std::optional<HeadlessGlContext> context;
  ViewerSession session(o);                 // before any GL work: a bad file or image fails fast
  std::optional<SceneSelection> selection;  // before any GL work too: a bad region fails fast
  std::vector<RegionShape> shells;          // drawn with --show-regions
  if (o.selecting()) {
    const RegionEditor regions(o);
    selection = select_in_scene(session.files(), regions.criteria());
    if (o.show_regions) {
      shells = regions.shapes();
      if (const std::size_t masks = regions.regions().size() - shells.size(); masks > 0)
        std::fprintf(stderr, "voxview: --show-regions draws spheres and boxes: %zu image region(s) not drawn\n", masks);
    }
    std::fprintf(stderr, "voxview: %llu of %llu streamlines selected (the focus; the others are context)\n",
                 (unsigned long long)selection->selected, (unsigned long long)selection->total);
  }
  stats.files_open_s = seconds_since_process_start();
  context.emplace();
  stats.context_s = seconds_since_process_start();
  session.choose_detail(o, /*one_renderer=*/true);
  const SceneDetail& detail = session.detail();
  const double aspect = double(o.width) / o.height;
  // One view (not a turntable) may be drawn finer than the whole scene: a slab or a close view of a large scene.
  const bool one_view = o.turntable <= 1;
  const Camera camera = initial_camera(framing_points(session.framing_layout(one_view)), o, aspect);
  const Camera* const view = one_view ? &camera : nullptr;
  PictureLevels levels = session.picture_levels(view, aspect, o.settings.clipping);
  // Focus first: the selection's full-detail copy is made only where the picture is drawn coarser.
  if (selection && session.focus_copy_needed(levels.level)) {
    try {
      session.set_focus(selection->kept);
      levels = session.picture_levels(view, aspect, o.settings.clipping);
    } catch (const std::exception& e) {  // the copy could not be written: drawn at one level
      std::fprintf(stderr, "voxview: the focus is drawn with the context: %s\n", e.what());
    }
  }
  const std::uint32_t level = levels.level;
  const std::optional<FocusFirstLevels>& focus_first = levels.focus_first;
  if (focus_first)
    std::fprintf(stderr,
                 "voxview: focus first: the %llu selected streamlines at full detail (level 0, %s of GPU memory), "
                 "the context at level %u in the rest of the GPU memory budget of %s (one level for both: %u)\n",
                 (unsigned long long)selection->selected, format_memory_size(focus_first->focus_bytes).c_str(),
                 focus_first->context, format_memory_size(detail.budget).c_str(), level);
  else if (level < detail.level)
    std::fprintf(stderr,
                 "voxview: drawing level %u: the visible part fits the GPU memory budget of %s (the whole scene "
                 "needs level %u)\n",
                 level, format_memory_size(detail.budget).c_str(), detail.level);
  else if (const std::string note = describe_scene_detail(detail, session.levels_in_files()); !note.empty())
    std::fprintf(stderr, "voxview: %s\n", note.c_str());
  if (selection) session.set_groups(selection->groups);
  Renderer* const renderer =
      focus_first ? &session.focus_first_renderer(focus_first->context, true) : &session.renderer_at(level, true);
  session.release_image();
  check_color_options(o.inputs_name(), *renderer, o.settings, o.from_view_file);
  RenderSettings settings = o.settings;
  settings.regions = shells;
  OffscreenTarget target(o.width, o.height);
  target.bind();
  if (o.save_camera)
    write_view(*o.save_camera, SavedView{camera, o.settings, std::array<int, 2>{o.width, o.height}, true, o.include,
                                         o.exclude, o.ends_in, o.show_regions});
  stats.scene_ready_s = seconds_since_process_start();
  stats.gl_renderer = context->renderer();
  stats.mode = render_mode_name(o.settings.mode);
  stats.width = o.width;
  stats.height = o.height;
  stats.level = focus_first ? focus_first->context : level;
  const int frames = std::max(1, o.turntable);
  std::optional<PictureAnnotations> annotations;
  if (PictureAnnotations::wanted(o.settings)) annotations.emplace();
  for (int i = 0; i < frames; ++i) {
    const Camera frame_camera = turntable_camera(camera, i, frames);
    RenderedPicture& picture = stats.pictures.emplace_back();
    auto step = std::chrono::steady_clock::now();
    const auto step_ms = [&step] {  // since the last step, which ends now
      const auto now = std::chrono::steady_clock::now();
      return std::chrono::duration<double, std::milli>(now - std::exchange(step, now)).count();
    };
    renderer->draw(frame_camera, settings, o.width, o.height, target.framebuffer());
    if (annotations) {
      target.bind();
      annotations->draw(frame_camera, o.settings, *renderer, o.width, o.height);
    }
    glFinish();  // the drawing's time includes the GPU's work
    picture.draw_ms = step_ms();
    std::vector<std::uint8_t> rgba = target.read_rgba();
    picture.read_back_ms = step_ms();
    renderer->check_uploaded(true);  // a damaged file's picture is not written
    picture.checks_wait_ms = step_ms();
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const std::string png = o.turntable ? turntable_frame_path(*o.render_png, i, frames) : *o.render_png;
    write_picture(png, o.width, o.height, rgba);
    picture.write_ms = step_ms();
    picture.written_s = seconds_since_process_start();
    const FrameStats& s = renderer->stats();
    picture.voxels = s.voxels_drawn;
    picture.segments = s.segments_drawn;
    const std::string levels =
        focus_first ? ", focus at level 0 and context at level " + std::to_string(focus_first->context) : "";
    std::printf("%s: %dx%d %s, %llu voxels and %llu segments drawn%s, %s after %.3f s (%s)\n", png.c_str(), o.width,
                o.height, render_mode_name(o.settings.mode), (unsigned long long)s.voxels_drawn,
                (unsigned long long)s.segments_drawn, levels.c_str(), i == 0 ? "first frame" : "frame", seconds,
                context->renderer().c_str());
  }
  if (o.save_camera) std::printf("view saved to %s\n", o.save_camera->c_str());
  if (o.stats_json) {
    stats.uploads = session.uploads();
    write_render_stats(*o.stats_json, stats);
  }
  return 0;
}

}  // namespace vxl::app
