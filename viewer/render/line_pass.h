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
  // good part of a second for one, and a picture needs one or two of the four.
  GLuint over() const { return program(over_program_, Fragment::Over); }
  GLuint wboit_accum() const { return program(accum_program_, Fragment::WboitAccum); }
  GLuint wboit_reveal() const { return program(reveal_program_, Fragment::WboitReveal); }
  GLuint additive() const { return program(additive_program_, Fragment::Additive); }
  unsigned bound_spans() const { return bound_spans_; }  // span slots of the line programs
  GLuint vao() const { return vao_; }                    // core profile draws need a bound VAO, even without attributes

  // Uploads the per-vertex (value, streamline) attributes that `settings` needs when they changed (colour by
  // the value set `scalar`, or by group or with a group's own opacity), and the streamline groups' table
  // when the groups changed since (groups_changed()).
  void prepare_attributes(const RenderSettings& settings, const std::string& scalar, const SceneGroups& groups,
                          VoxelVoxlinesCache& indexes);
  void groups_changed() { streamline_groups_stale_ = true; }

  // Binds `program`'s uniforms and textures (the streamline groups' table, the slices' depth) and enables
  // the clip distances the settings' slab and clip planes need.
  void bind(GLuint program, const LineUniforms& uniforms) const;
  // Draws the virtual-id ranges (first, count) in order with `program` (its other uniforms bound), binding
  // the spans they lie in a few at a time.
  void draw_plan(GLuint program, std::span<const std::int64_t> first, std::span<const std::int32_t> count) const;
  // Binds spans `bound` to the program's span slots, their ids starting at `base` in this draw.
  void bind_spans(GLuint program, std::span<const std::uint32_t> bound, std::span<const std::int64_t> base) const;
  // Enables the first n of the line shader's clip distances and disables the others (passes without
  // gl_ClipDistance must run with none enabled).

 private:
  void upload_streamline_groups(const SceneGroups& groups);
  enum class Fragment { Over, WboitAccum, WboitReveal, Additive };
  GLuint program(GLuint& slot, Fragment fragment) const;

  GpuScene& scene_;
  const std::vector<const VxlFile*>& files_;
  GLuint vao_ = 0;
  unsigned bound_spans_ = 1;
  bool slice_test_ = false;
  mutable GLuint over_program_ = 0, accum_program_ = 0, reveal_program_ = 0, additive_program_ = 0;
  std::string attributes_key_;  // what the attribute buffers hold ("" : nothing)
  // One byte per streamline of the scene (the files' streamlines one after another): its group mod the
  // shader's group table. A new selection or grouping uploads this alone, not the per-vertex attributes.
  gl::TextureBuffer streamline_groups_;
  bool streamline_groups_stale_ = true;
};

}  // namespace vxl
