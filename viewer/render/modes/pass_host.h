// What a transparency mode (mode_pass.h) draws with: the frame it draws, and the renderer's services it
// lends the modes (the line pass, the scene, planning within the GPU memory budget, the picture's base).
#pragma once

#include <algorithm>
#include <vector>

#include "format/vxl_file.h"
#include "viewer/render/camera.h"
#include "viewer/render/frame_plan.h"
#include "viewer/render/gl_util.h"
#include "viewer/render/gpu_scene.h"
#include "viewer/render/line_pass.h"
#include "viewer/render/render_settings.h"

namespace vxl {

struct FrameStats;

// One frame: drawn from `camera` with `settings` into framebuffer `fbo` of width x height.
struct FrameView {
  const Camera& camera;
  const RenderSettings& settings;
  int width = 0, height = 0;
  GLuint fbo = 0;
  double aspect() const { return double(width) / std::max(1, height); }
};

class PassHost {
 public:
  virtual ~PassHost() = default;
  virtual LinePass& lines() = 0;
  virtual GpuScene& scene() = 0;
  virtual const std::vector<const VxlFile*>& scene_files() const = 0;
  // The renderer's frame plan (what pieces and queries keep) and the last frame's statistics.
  virtual FramePlan& frame_plan() = 0;
  virtual FrameStats& frame_stats() = 0;
  // The plan of `frame` in `order` for drawing: culled by its clipping, the spans made resident (voxels whose
  // span the budget does not hold dropped), the CPU time and counts in frame_stats().
  virtual void plan_and_count(const FrameView& frame, PlanOrder order, FramePlan& out) = 0;
  // Makes the spans of the plan's voxels resident, the nearest first, and drops the voxels of those that
  // do not fit the budget.
  virtual void keep_resident(FramePlan& plan) = 0;
  // Binds the line program's uniforms and textures for the frame's camera, with `settings` (a mode may
  // draw with changed settings, e.g. opaque).
  virtual void bind_lines(GLuint program, const FrameView& frame, const RenderSettings& settings) = 0;
  // Clears frame.fbo to the picture's base under the lines: the background, or the slices over it, with the
  // back halves of the settings' region shells blended on.
  virtual void clear_to_base(const FrameView& frame) = 0;
  // exact with region shells: its base in frame.fbo with the back halves drawn on it (base_in_framebuffer()).
  virtual void base_for_exact(const FrameView& frame) = 0;
  virtual bool base_in_framebuffer() const = 0;
  // The slices' colour of this frame (RGBA32F), 0 when none were drawn.
  virtual GLuint slice_color_texture() const = 0;
};

}  // namespace vxl
