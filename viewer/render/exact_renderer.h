// The `exact` mode: per-fragment sorted transparency, the reference every other mode is scored against.
//
// A list pass stores line fragments (colour, depth) in per-pixel linked lists (a head image, a node
// buffer, an atomic counter); a resolve composites each pixel's fragments back to front, in (depth, node
// index) order, so lists of any length are resolved exactly, over the background or the anatomical slices
// (slice_renderer.h). Memory stays bounded by drawing the voxels in runs, back to front in a visibility order
// of the grid (frame_plan.h, PlanOrder::Visibility), each run's lists composited over the picture so far:
// every voxel is drawn once, however many fragments the scene has. A single voxel too large for the node
// buffer is drawn in bands of rows. Needs OpenGL 4.3.
//
// The resolve (exact_resolve.h) runs on the GPU, a compute pass that leaves the lists where they are, unless
// the driver's result differs from the CPU's on lists made to try it, or the driver rasterises in software:
// then, and when asked, the lists are read back and composited on the CPU, the reference the GPU's is checked
// against, to the same floats.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include <memory>

#include "viewer/render/camera.h"
#include "viewer/render/exact_resolve.h"
#include "viewer/render/frame_plan.h"
#include "viewer/render/gl_util.h"
#include "viewer/render/render_settings.h"

namespace vxl {

class PassHost;
class Renderer;

// Where the lists are composited. Gpu: on the GPU when the driver agrees with the CPU (else on the CPU). Auto:
// the same, but on the CPU where the GPU is the CPU (a software rasteriser such as Mesa's llvmpipe, where the
// CPU's resolve on every thread is faster than the compute pass: docs/performance.md).
enum class ExactResolve { Auto, Gpu, Cpu };

class ExactRenderer {
 public:
  // Draws with the host's line pass, plan and base (modes/pass_host.h). node_capacity 0: as many 16-byte
  // nodes as fit in min(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, 256 MiB).
  explicit ExactRenderer(PassHost& host, std::uint64_t node_capacity = 0, ExactResolve resolve = ExactResolve::Auto);
  // The same over `lines`' passes (Renderer::pass_host).
  explicit ExactRenderer(Renderer& lines, std::uint64_t node_capacity = 0, ExactResolve resolve = ExactResolve::Auto);
  // Where this renderer composites: Gpu or Cpu (Gpu only where the driver passed GpuListResolve::agrees_with_cpu).
  ExactResolve resolve() const { return gpu_ ? ExactResolve::Gpu : ExactResolve::Cpu; }
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
  // Composites the lists of rows [y0, y1) (holding `stored` nodes) over the picture so far (result_ on the
  // GPU, image_ on the CPU).
  void resolve_band(int y0, int y1, std::uint32_t stored);

  PassHost& host_;
  std::unique_ptr<GpuListResolve> gpu_;  // null: the CPU composites
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
  // Read-back scratch for the CPU's resolve, kept between frames.
  std::vector<std::uint32_t> heads_copy_;
  std::vector<FragmentNode> nodes_copy_;
  // The picture so far (RGBA, bottom row first): slices or background, then runs; on the GPU, in result_.
  std::vector<float> image_;
};

}  // namespace vxl
