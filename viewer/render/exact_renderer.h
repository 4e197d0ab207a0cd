// The `exact` mode: per-fragment sorted transparency, the reference every other mode is scored against.
//
// A list pass stores line fragments (colour, depth) in per-pixel linked lists (a head image, a node
// buffer, an atomic counter); a resolve reads the lists back and composites each pixel's fragments back
// to front on the CPU, in (depth, node index) order, so lists of any length are resolved exactly, over
// the background or the anatomical slices (slice_renderer.h). Memory stays bounded by drawing the voxels
// in runs, back to front in a visibility order of the grid (frame_plan.h, PlanOrder::Visibility), each
// run's lists composited over the picture so far: every voxel is drawn once, however many fragments the
// scene has. A single voxel too large for the node buffer is drawn in bands of rows. Needs OpenGL 4.3.
//
// Why the CPU: the reference must not depend on a shader compiler. On llvmpipe 22.3 a fragment-shader
// resolve gave wrong pixels (docs/rendering.md, pitfall 2), and so did a compute-shader resolve once a pixel held
// more fragments than one batch of its bounded heap: on the 144k synthetic set its image changed with the
// batch size (RMSE 14 levels between 64 and 2048), although the algorithm is exact for any batch size.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "viewer/render/camera.h"
#include "viewer/render/frame_plan.h"
#include "viewer/render/gl_util.h"
#include "viewer/render/render_settings.h"

namespace vxl {

class PassHost;
class Renderer;

class ExactRenderer {
 public:
  // Draws with the host's line pass, plan and base (modes/pass_host.h). node_capacity 0: as many 16-byte
  // nodes as fit in min(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, 256 MiB).
  explicit ExactRenderer(PassHost& host, std::uint64_t node_capacity = 0);
  // The same over `lines`' passes (Renderer::pass_host).
  explicit ExactRenderer(Renderer& lines, std::uint64_t node_capacity = 0);
  ~ExactRenderer();
  void draw(const Camera& camera, const RenderSettings& settings, int width, int height, GLuint fbo);
  // draw() in pieces, so that a window takes input between them (Renderer::begin_pieces): begin() plans the
  // frame and starts the picture; each step() composites runs of voxels for about `max_ms` (at least one
  // run; a run is also kept short enough for that time, from the segments per millisecond measured so far)
  // and, after the last, writes the picture to `fbo` and returns true. draw() is begin() and one unbounded step.
  void begin(const Camera& camera, const RenderSettings& settings, int width, int height, GLuint fbo);
  bool step(double max_ms);
  // The share of the frame's segments composited so far (0 before the first step, 1 when done).
  double progress() const;
  int passes() const { return passes_; }  // list passes resolved in the last frame (depth runs and row bands)
  std::uint64_t fragments() const { return fragments_; }

 private:
  void start_image(const glm::vec3& background);
  // The end of the next run from plan voxel next_: as many voxels as fill about half the node buffer (once
  // the fragments per segment are known) and, with a time limit, as draw in `max_segments`.
  std::size_t run_end(double max_segments) const;
  // Writes image_ to `fbo_`.
  void show_image();
  // Stores the fragments of plan_ voxels [first_voxel, end_voxel) inside rows [y0, y1) in the lists;
  // returns how many there were (more than the capacity: the lists hold only the first ones).
  std::uint64_t list_pass(std::size_t first_voxel, std::size_t end_voxel, int y0, int y1);
  // The same voxels, in bands of rows small enough for the node buffer.
  void rows_in_bands(std::size_t first_voxel, std::size_t end_voxel, int height);
  // Composites the lists of rows [y0, y1) (holding `stored` nodes) over image_.
  void resolve_band(int y0, int y1, std::uint32_t stored);

  PassHost& host_;
  std::uint64_t capacity_ = 0;
  GLuint list_program_ = 0, clear_program_ = 0, blit_program_ = 0;
  GLuint nodes_ = 0, counter_ = 0, heads_ = 0, result_ = 0;
  int width_ = 0, height_ = 0;
  // The frame being drawn (begin() to the step() that completes it).
  Camera camera_;
  RenderSettings settings_;
  GLuint fbo_ = 0;
  FramePlan plan_;
  std::vector<std::uint64_t> segments_before_;  // segments of plan voxels [0, v)
  std::size_t next_ = 0;                        // the first plan voxel not composited yet
  double per_segment_ = 0;                      // fragments per segment, 0 until measured
  double composited_ms_ = 0;                    // the runs' time so far (list passes and resolves)
  int passes_ = 0;
  std::uint64_t fragments_ = 0;
  // Read-back scratch, kept between frames.
  std::vector<std::uint32_t> heads_copy_;
  std::vector<std::array<std::uint32_t, 4>> nodes_copy_;  // colour rg, colour ba (half floats), depth, next
  std::vector<float> image_;  // the picture so far (RGBA, bottom row first): slices or background, then runs
};

}  // namespace vxl
