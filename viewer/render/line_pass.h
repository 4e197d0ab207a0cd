// The line pass every transparency mode draws with: the line programs (line_shaders.h), the per-vertex
// attributes and streamline groups they read, their uniforms, and the draws of a frame plan's virtual-id
// ranges with the texture spans they lie in bound a few at a time.
//
//   LinePass lines(scene, files);
//   lines.prepare_attributes(settings, scalar, groups, indexes);  // once a frame
//   lines.bind(lines.over(), uniforms);                           // uniforms and textures for a camera
//   lines.draw_plan(lines.over(), plan.first, plan.count);        // the ranges, in order
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "viewer/render/camera.h"
#include "viewer/render/gl_util.h"
#include "viewer/render/gpu_scene.h"
#include "viewer/render/render_settings.h"
#include "viewer/render/scene_groups.h"

namespace vxl {

// What bind() sets besides the scene's own state: the camera and what the renderer derives for it.
struct LineUniforms {
  const Camera& camera;
  const glm::dmat4& projection;
  const RenderSettings& settings;
  std::array<float, 2> scalar_range;  // the values at the colour map's ends
  const SceneGroups& groups;
  GLuint slice_depth = 0;  // the opaque slices' depth texture; 0: no slices this frame (no depth test)
};

class LinePass {
 public:
  static constexpr int kSamplersPerSpan = 4;        // words, orders, dataset order, attributes
  static constexpr std::size_t kMaxBoundSpans = 8;  // spans one draw binds (each a branch in the vertex shader)
  // The average segments per run of voxels in one span from which a draw binds one span (plan_draws): about ten
  // times what an extra draw costs llvmpipe in the per-vertex branches it saves (0.1 ms a draw, 0.3 us a segment).
  static constexpr std::uint64_t kSegmentsPerOwnDraw = 4096;

  // Needs a current GL context; the scene and files must outlive the pass. Throws Error (Unsupported,
  // naming the first file) when the vertex shader has too few texture units for one span.
  LinePass(GpuScene& scene, const std::vector<const VxlFile*>& files);
  ~LinePass();
  LinePass(const LinePass&) = delete;
  LinePass& operator=(const LinePass&) = delete;

  // Forgets the line programs, to be made again on first use testing fragments against the slices' depth or not
  // (a scene without an image does not pay for the test).
  void make_programs(bool slice_test);
  // A program of the line vertex shader and line_fragment(body, version) for this scene's span slots and
  // slice test (the exact mode's list pass). The caller deletes it.
  GLuint make_program(const char* fragment_body, const char* version) const;
  // The modes' line programs, each made on first use: a software rasteriser (SwiftShader in a browser) takes a
  // good part of a second for one, and a picture needs one or two of the four. bind() and draw_plan() draw with
  // the one of the current plan's draws (plan_draws).
  GLuint over() const { return program(Fragment::Over, bound_spans_); }
  GLuint wboit_accum() const { return program(Fragment::WboitAccum, bound_spans_); }
  GLuint wboit_reveal() const { return program(Fragment::WboitReveal, bound_spans_); }
  GLuint additive() const { return program(Fragment::Additive, bound_spans_); }
  unsigned bound_spans() const { return bound_spans_; }  // span slots of the line programs
  GLuint vao() const { return vao_; }                    // core profile draws need a bound VAO, even without attributes

  // Uploads the per-vertex (value, streamline) attributes that `settings` needs when they changed (colour by
  // the value set `scalar`, or by group or with a group's own opacity), and the streamline groups' table
  // when the groups changed since (groups_changed()).
  void prepare_attributes(const RenderSettings& settings, const std::string& scalar, const SceneGroups& groups,
                          VoxelVoxlinesCache& indexes);
  void groups_changed() { streamline_groups_stale_ = true; }

  // How the next frame plan's virtual-id ranges (first, count) are drawn: where its runs of voxels in one span are
  // long (kSegmentsPerOwnDraw segments on average), a draw binds one span, with the modes' programs made for one
  // span slot, whose vertex shader has no span to look up; else a draw binds up to bound_spans() spans. Every
  // fetch of the shader branches over its span slots and a software rasteriser runs each branch: on llvmpipe the
  // 10M set's level 1 in spans of 4M texels drew in 17.7 s one span a draw against 32.7 s eight, the same picture.
  void plan_draws(std::span<const std::int64_t> first, std::span<const std::int32_t> count,
                  std::uint64_t segments_per_own_draw = kSegmentsPerOwnDraw);
  unsigned draw_spans() const { return draw_spans_; }  // the current plan's: bound_spans() or 1
  // Binds the uniforms and textures (the streamline groups' table, the slices' depth) of `program` (a mode's,
  // or its one-slot form for the current plan) and enables the clip distances the settings' slab and clip
  // planes need.
  void bind(GLuint program, const LineUniforms& uniforms) const;
  // Draws the virtual-id ranges (first, count) in order with `program` (bound), binding the spans they lie in one
  // or a few at a time (plan_draws).
  void draw_plan(GLuint program, std::span<const std::int64_t> first, std::span<const std::int32_t> count) const;

 private:
  void upload_streamline_groups(const SceneGroups& groups);
  enum class Fragment { Over, WboitAccum, WboitReveal, Additive };
  static constexpr std::size_t kFragments = 4;
  // A mode's program for `spans` span slots (bound_spans_ or 1), made on first use.
  GLuint program(Fragment fragment, unsigned spans) const;
  GLuint make_program(const char* fragment_body, const char* version, unsigned spans) const;
  // The program the current plan's draws use for `program`, and its span slots: a mode's program's one-slot form
  // where the plan draws one span at a time; any other program (the exact mode's) as it is, with bound_spans_.
  GLuint drawn(GLuint program) const;
  unsigned span_slots(GLuint program) const;
  // Binds spans `bound` to the program's `slots` span slots, their ids starting at `base` in this draw.
  void bind_spans(GLuint program, unsigned slots, std::span<const std::uint32_t> bound,
                  std::span<const std::int64_t> base) const;

  GpuScene& scene_;
  const std::vector<const VxlFile*>& files_;
  GLuint vao_ = 0;
  unsigned bound_spans_ = 1;
  unsigned draw_spans_ = 1;  // spans one draw of the current plan binds: bound_spans_ or 1
  bool slice_test_ = false;
  // Per fragment: the program with bound_spans_ span slots, and the one with one slot.
  mutable std::array<GLuint, kFragments> programs_{}, one_span_programs_{};
  std::string attributes_key_;  // what the attribute buffers hold ("" : nothing)
  // One byte per streamline of the scene (the files' streamlines one after another): its group mod the
  // shader's group table. A new selection or grouping uploads this alone, not the per-vertex attributes.
  gl::TextureBuffer streamline_groups_;
  bool streamline_groups_stale_ = true;
};

}  // namespace vxl
