// The Voxlines renderer. Needs only a current OpenGL context (3.3 core for every mode but `exact`, which
// needs 4.3): it is driven the same way from a GLFW window and from a headless EGL context.
//
//   Renderer r(file);                       // uploads the scene (few large copies)
//   Renderer r({&a, &b});                   // several files, their voxels sorted together every frame
//   r.set_volume(volume);                   // optional: an anatomical image, shown as opaque slices
//   r.draw(camera, settings, w, h, fbo);    // one frame into the bound framebuffer `fbo`
#pragma once

#include <array>
#include <cstdint>
#include <initializer_list>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "viewer/render/camera.h"
#include "viewer/render/frame_plan.h"
#include "viewer/render/gl_util.h"
#include "viewer/render/gpu_scene.h"
#include "viewer/render/region_shapes.h"
#include "viewer/render/render_settings.h"
#include "viewer/render/scene_groups.h"
#include "viewer/render/view_queries.h"

namespace vxl {

class LinePass;
class ModePass;
class PassHost;
class RegionShells;
class SliceRenderer;
struct Volume;

struct FrameStats {
  double plan_ms = 0;  // CPU work of the frame: cull + sort + order pick + uploads + command building (segsort:
                       // + segment sort)
  std::uint64_t voxels_drawn = 0;
  std::uint64_t segments_drawn = 0;
  std::uint64_t voxels_waiting = 0;  // visible but not drawn: their span did not fit the GPU memory budget
};

class Renderer {
 public:
  static constexpr int kSamplersPerSpan = 4;        // words, orders, dataset order, attributes
  static constexpr std::size_t kMaxBoundSpans = 8;  // spans one draw binds (each a branch in the vertex shader)
  // The drawing rate a frame in pieces assumes before it has measured one: about Mesa llvmpipe's on two
  // cores at 1024x1024 (a GPU is faster, so its first piece is merely short).
  static constexpr double kAssumedSegmentsPerMs = 1000;
  explicit Renderer(const VxlFile& file, std::uint64_t max_texels = 0, std::uint32_t level = 0);
  // Several files drawn as one scene: one sort over all their voxels, one group per file. The files must
  // outlive the renderer. level: the level of detail drawn (.vxl spec §5.12; scene_layout.h), its opacity
  // compensated so that the picture keeps its brightness.
  // pool: the GPU memory budget shared with the context's other renderers (gpu_memory_pool.h; none: no
  // budget). A frame draws the visible voxels whose span the budget holds, the nearest first.
  // eager: upload the whole scene when made, if it fits the pool's free room; else spans come as frames (or
  // upload_spans) need them.
  // file_levels: when not empty, each file's own level instead of `level` (a selection's focus copy at full
  // detail beside the context at a coarser one: viewer_session.h); each group's opacity is then compensated
  // for the level of the files it is drawn from (LinePass::bind).
  explicit Renderer(std::vector<const VxlFile*> files, std::uint64_t max_texels = 0, std::uint32_t level = 0,
                    std::shared_ptr<GpuMemoryPool> pool = nullptr, bool eager = true,
                    const std::vector<std::uint32_t>& file_levels = {});
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // The files' per-voxel indexes (the vertices' streamlines for colour and opacity by group), shared with
  // other users of the same files (the window's selections) so that they are built once.
  void share_indexes(std::shared_ptr<VoxelVoxlinesCache> indexes) { indexes_ = std::move(indexes); }

  // Renders one frame into framebuffer `fbo` (0: the default one) of size width x height.
  // Throws std::runtime_error when the mode needs more than the context offers (exact on GL < 4.3).
  void draw(const Camera& camera, const RenderSettings& settings, int width, int height, GLuint fbo);

  // A frame drawn in pieces, so that a window takes input between them (voxview's refinement at rest):
  // begin_pieces() starts the picture of draw(camera, settings, ...) in `fbo` (the background or the slices)
  // and plans it; each draw_piece() adds the next voxels, back to front, for about `max_ms` (at least one
  // voxel) and returns true once the picture is complete. It is then the picture draw() makes: the same
  // draws in the same order for opaque, basic and axis; exact composites runs of voxels as its draw()
  // does, only shorter ones. Modes that blend in no order (unsorted, additive, wboit) are drawn whole by
  // the first piece. A draw() in between abandons the pieces.
  // stand_in: a renderer of the same files (and image, if any) at a coarser level, for a picture while this one's
  // spans are still coming (the web viewer fetching a level nearest the view first, the window's partial pictures):
  // the plan's voxels whose span is not resident are drawn from it, at its level, in their place back to front, and
  // no span is uploaded (the caller sees that the stand-in's spans for the view are resident). Only
  // for the modes drawn in pieces of voxels (draws_in_voxel_pieces); ignored for the others. It must outlive the
  // pieces (until draw(), the next begin_pieces() or the end of this renderer).
  void begin_pieces(const Camera& camera, const RenderSettings& settings, int width, int height, GLuint fbo,
                    Renderer* stand_in = nullptr);
  bool draw_piece(double max_ms);
  // Whether `mode` is drawn in pieces of voxels, back to front (opaque, basic, axis): then a stand-in can fill in.
  bool draws_in_voxel_pieces(RenderMode mode);
  // The share of the frame's segments drawn so far (1 when complete).
  double pieces_progress() const;

  // Uploads an anatomical image; settings.slices then chooses which of its slices every frame shows under
  // the lines. The volume need not outlive the call.
  void set_volume(const Volume& volume);
  bool has_volume() const { return slices_ != nullptr; }
  // The grey range the slices use for `settings` (its range, else the image's window); {0, 1} without an image.
  std::array<float, 2> slice_range(const RenderSettings& settings) const;
  // The slices' colour of the last frame (RGBA32F, the background where none), 0 when none were drawn.
  GLuint slice_color_texture() const;
  // Whether this frame's base (background or slices, and the back halves of the region shells) is in the
  // framebuffer rather than only in slice_color_texture(): exact then reads it from there.
  bool base_in_framebuffer() const { return base_in_framebuffer_; }

  // The checks of what the renderer has uploaded, which run beside the drawing (GpuScene::check_uploaded):
  // rethrows their failure (vxl::Error, Input: the file is damaged); with `wait`, once all have run. draw()
  // and draw_piece() call it without waiting before they draw, so a damaged file stops being drawn at the
  // first frame after its checks fail; a program that writes a picture waits for them first.
  void check_uploaded(bool wait) { scene_.check_uploaded(wait); }
  // Without threads (the web viewer): runs those checks for about `max_ms` (GpuScene::check_some); true once done.
  bool check_some(double max_ms) { return scene_.check_some(max_ms); }

  const FrameStats& stats() const { return stats_; }
  // The scene's groups (scene_groups.h) and value sets (per-vertex sets first, then per-streamline ones).
  const SceneGroups& groups() const { return groups_; }
  // Replaces the groups (e.g. with a selection's focus and context); the next frame uploads them.
  void set_groups(SceneGroups groups);
  const std::vector<std::string>& value_set_names() const { return value_set_names_; }
  // The value set ColorMode::Scalar shows for `settings` (its `scalar`, else the first; empty when none),
  // and the range it maps (settings.range, else the set's stored min and max).
  std::string scalar_name(const RenderSettings& settings) const;
  std::array<float, 2> scalar_range(const RenderSettings& settings) const;
  // What the scene's voxels are and where they lie on the GPU (read-only: the grid overlay and the framing use
  // it), and the GPU memory the scene takes.
  const SceneLayout& layout() const { return scene_.layout(); }
  std::uint64_t gpu_bytes() const { return scene_.gpu_bytes(); }
  const GpuMemoryPool& gpu_memory() const { return scene_.pool(); }
  bool span_resident(std::uint32_t span) const { return scene_.resident(span); }
  // Uploads what `mode` builds on its first frame (the unsorted mode's dataset order, the segsort mode's
  // buffers), so that a timed frame does not include it.
  void prepare(RenderMode mode);
  const VxlFile& file() const { return *files_.front(); }  // the first
  const std::vector<const VxlFile*>& files() const { return files_; }
  glm::dvec3 bounds_min() const { return line_bounds_.min; }
  glm::dvec3 bounds_max() const { return line_bounds_.max; }
  // The lines' bounds joined with the image's box (when there is one): what the depth range covers (the
  // camera frames the lines).
  glm::dvec3 scene_min() const { return scene_bounds_.min; }
  glm::dvec3 scene_max() const { return scene_bounds_.max; }

  // The projection the renderer uses for `camera` (near/far planes fitted to the scene bounds).
  glm::dmat4 projection(const Camera& camera, double aspect) const;

  // The frame plan for `camera`: voxels outside the frustum or the slab / clip planes of `clipping` culled.
  // A query: stats() keeps describing the last frame drawn.
  void plan(const Camera& camera, double aspect, PlanOrder order, FramePlan& out, const Clipping& clipping = {}) const;
  // The most GPU memory a frame of `camera` with `clipping` can need: the spans its visible voxels lie in,
  // with everything a mode may upload for them (SceneLayout::span_upload_bytes).
  std::uint64_t view_bytes(const Camera& camera, double aspect, const Clipping& clipping = {}) const;
  // Makes what `settings` read per vertex (values, groups: LinePass::prepare_attributes) part of every span's upload
  // from now on; draw() and begin_pieces() do it themselves. A caller that uploads spans ahead of a frame
  // (upload_spans) calls it first: else the frame re-uploads every resident span with those words, all at once.
  void prepare_attributes(const RenderSettings& settings);
  // The spans a frame of `camera` needs, those of the nearest voxels first.
  std::vector<std::uint32_t> spans_for(const Camera& camera, double aspect, const Clipping& clipping = {}) const;
  // Uploads those of `spans` that are not resident, in that order, filled on other threads a few at a time
  // (GpuScene::make_resident without waiting), so that a window can spread a large upload over frames and its event
  // loop never waits for one: returns after about `max_ms`, with the spans whose fill ended by then resident. True
  // once nothing more of them can be uploaded (all resident, or the budget holds no more).
  bool upload_spans(std::span<const std::uint32_t> spans, double max_ms);

  // The renderer as its transparency modes see it (modes/pass_host.h): its line pass, scene, plan and base.
  // For drawing a mode's pass over this renderer's scene (e.g. an ExactRenderer with a small node buffer).
  PassHost& pass_host();

 private:
  class Host;  // the renderer as its modes' PassHost
  struct Pieces;
  // The pass that draws `mode` (modes/mode_pass.h), made on first use.
  ModePass& pass(RenderMode mode);
  // What every mode does first: the per-vertex attributes, the slices (their depth hides lines behind them),
  // line width and a neutral blend and depth state.
  void start_frame(const Camera& camera, const RenderSettings& settings, int width, int height);
  // Clears `fbo` to the picture's base under the lines: the background, or the slices over it, with the back
  // halves of settings.regions' shells blended on.
  void clear_to_base(GLuint fbo, const Camera& camera, const RenderSettings& settings, int width, int height);
  // Blends one half of settings.regions' shells (region_shells.h) over the bound framebuffer: the back half
  // over the base before the lines, the front half after them.
  void draw_shells(ShellHalf half, const Camera& camera, const RenderSettings& settings, int width, int height);
  void draw_front_shells(const Pieces& pieces);
  // exact with shells: its base in `fbo` with the back halves drawn on it (base_in_framebuffer()).
  void shells_under_exact(const Camera& camera, const RenderSettings& settings, int width, int height, GLuint fbo);
  // Makes the spans of the plan's voxels resident, the nearest first, and drops the voxels of those that
  // do not fit the budget.
  void keep_resident(FramePlan& plan);
  // plan() for drawing: the spans made resident (keep_resident), the frame's CPU time and counts in stats().
  void plan_and_count(const Camera& camera, double aspect, PlanOrder order, FramePlan& out, const Clipping& clipping);
  // Binds the line program's uniforms and textures for `camera`.
  void bind_line_program(GLuint program, const Camera& camera, const RenderSettings& settings, double aspect) const;
  // draw_piece() of a frame drawn in runs of the plan's voxels (PieceKind::Voxels).
  void draw_voxel_piece(double max_ms);
  // begin_pieces' plan with a stand-in: this renderer's resident voxels and the stand-in's entries for the others,
  // in one back-to-front order (pieces.first/count/from_stand_in).
  void plan_with_stand_in(const Camera& camera, double aspect, PlanOrder order, const Clipping& clipping,
                          Renderer& stand_in, Pieces& pieces);
  // Draws the ranges (first, count) with the over program of `renderer` (this one or a stand-in).
  void draw_over_ranges(Renderer& renderer, const Pieces& pieces, std::span<const std::int64_t> first,
                        std::span<const std::int32_t> count);

  std::vector<const VxlFile*> files_;
  SceneBounds line_bounds_;   // the files' (view_queries.h)
  SceneBounds scene_bounds_;  // the same joined with the image's box: what the projection covers
  GpuScene scene_;
  std::unique_ptr<LinePass> lines_;  // the line programs, attributes and draws every mode uses
  std::unique_ptr<Host> host_;
  std::vector<std::unique_ptr<ModePass>> passes_;  // by RenderMode, each made on first use
  FramePlan plan_;
  FrameStats stats_;
  std::unique_ptr<Pieces> pieces_;  // the frame begin_pieces() started, until draw() or the next begin
  std::unique_ptr<SliceRenderer> slices_;
  std::unique_ptr<RegionShells> shells_;  // made when regions are first shown
  bool base_in_framebuffer_ = false;
  bool slices_drawn_ = false;  // this frame: the line shaders test against the slices' depth
  SceneGroups groups_;
  std::vector<std::string> value_set_names_;
  std::shared_ptr<VoxelVoxlinesCache> indexes_;
};

}  // namespace vxl
