#include "viewer/render/line_pass.h"

#include <algorithm>
#include <limits>
#include <utility>

#include <glm/gtc/type_ptr.hpp>

#include "format/base/error.h"
#include "format/voxel_voxlines.h"
#include "viewer/render/clip_planes.h"
#include "viewer/render/clip_uniforms.h"
#include "viewer/render/colormap.h"
#include "viewer/render/line_lighting.h"
#include "viewer/render/line_shaders.h"
#include "viewer/render/vertex_attributes.h"

namespace vxl {
namespace {

// The level each group is drawn at: the finest of the files it fills alone (a focus copy), else the scene's.
std::vector<std::uint32_t> group_levels(const SceneGroups& groups, const SceneLayout& layout) {
  std::vector<std::uint32_t> levels(groups.groups().size(), layout.level());
  for (std::size_t i = 0; i < layout.files().size(); ++i)
    if (groups.uniform(i)) {
      std::uint32_t& level = levels[groups.group_of(i, 0)];
      level = std::min(level, layout.files()[i].level);
    }
  return levels;
}

}  // namespace

LinePass::LinePass(GpuScene& scene, const std::vector<const VxlFile*>& files) : scene_(scene), files_(files) {
  // A draw binds up to kMaxBoundSpans spans, as many as the vertex shader's texture units allow beside the
  // streamline groups' table (GL 3.3 promises 16: three spans).
  GLint units = 0;
  glGetIntegerv(GL_MAX_VERTEX_TEXTURE_IMAGE_UNITS, &units);
  const std::size_t spans = std::max<std::size_t>(1, scene_.layout().texture_spans().size());
  bound_spans_ = static_cast<unsigned>(std::min<std::size_t>(
      {spans, kMaxBoundSpans, static_cast<std::size_t>(std::max(0, units - 1)) / kSamplersPerSpan}));
  if (bound_spans_ == 0)
    throw Error(ErrorKind::Unsupported, files_.front()->path(), std::nullopt,
                "this GPU offers " + std::to_string(units) + " vertex-shader textures; the lines need " +
                    std::to_string(kSamplersPerSpan + 1));
  draw_spans_ = bound_spans_;
  glGenVertexArrays(1, &vao_);
  make_programs(false);
}

LinePass::~LinePass() {
  make_programs(false);
  streamline_groups_.destroy();
  if (vao_) glDeleteVertexArrays(1, &vao_);
}

void LinePass::make_programs(bool slice_test) {
  for (auto* programs : {&programs_, &one_span_programs_})
    for (GLuint& p : *programs)
      if (p) glDeleteProgram(std::exchange(p, 0));
  slice_test_ = slice_test;
}

GLuint LinePass::program(Fragment fragment, unsigned spans) const {
  GLuint& slot = (spans == bound_spans_ ? programs_ : one_span_programs_)[static_cast<std::size_t>(fragment)];
  if (slot) return slot;
  const char* body = fragment == Fragment::Over          ? shaders::kLineOverFragment
                     : fragment == Fragment::WboitAccum  ? shaders::kLineWboitAccumFragment
                     : fragment == Fragment::WboitReveal ? shaders::kLineWboitRevealFragment
                                                         : shaders::kLineAdditiveFragment;
  slot = make_program(body, "#version 330 core", spans);
  return slot;
}

GLuint LinePass::make_program(const char* fragment_body, const char* version) const {
  return make_program(fragment_body, version, bound_spans_);
}

GLuint LinePass::make_program(const char* fragment_body, const char* version, unsigned spans) const {
  return gl::make_program(shaders::line_vertex(spans, version),
                          shaders::line_fragment(fragment_body, version, slice_test_));
}

void LinePass::plan_draws(std::span<const std::int64_t> first, std::span<const std::int32_t> count,
                          std::uint64_t segments_per_own_draw) {
  draw_spans_ = bound_spans_;
  if (bound_spans_ == 1 || first.empty()) return;
  const SceneLayout& layout = scene_.layout();
  std::uint64_t runs = 1, segments = 0;
  for (std::size_t i = 0; i < first.size(); ++i) {
    if (i > 0 && layout.span_of_id(first[i]) != layout.span_of_id(first[i - 1])) ++runs;
    segments += static_cast<std::uint64_t>(count[i] / 2);
  }
  if (segments / runs >= segments_per_own_draw) draw_spans_ = 1;
}

GLuint LinePass::drawn(GLuint program) const {
  if (draw_spans_ == bound_spans_) return program;
  for (std::size_t f = 0; f < kFragments; ++f)
    if (program == programs_[f]) return this->program(static_cast<Fragment>(f), draw_spans_);
  return program;
}

unsigned LinePass::span_slots(GLuint program) const {
  for (const GLuint p : one_span_programs_)
    if (p == program && p != 0) return 1;
  return bound_spans_;
}

void LinePass::prepare_attributes(const RenderSettings& s, const std::string& scalar, const SceneGroups& groups,
                                  VoxelVoxlinesCache& indexes) {
  const std::string name = s.color == ColorMode::Scalar ? scalar : std::string();
  bool want_groups = s.color == ColorMode::Group;
  const auto& all = groups.groups();
  for (std::size_t g = 0; g < all.size(); ++g) want_groups |= s.group_color(all[g].name, g).a != 1.0f || all[g].hidden;
  const std::string key = name.empty() && !want_groups ? "" : "value:" + name;
  if (key != attributes_key_) {
    std::vector<AttributeSource> per_file;
    std::uint64_t first_streamline = 0;
    if (!key.empty())
      for (std::size_t i = 0; i < files_.size(); ++i) {
        const VoxelVoxlines* index = indexes.of(i);
        if (index == nullptr)
          throw Error(ErrorKind::Unsupported, files_[i]->path(), std::nullopt,
                      "colour or opacity by value or group needs the voxel index of voxlines, which holds fewer than "
                      "2^32 streamlines and voxlines of fewer than 2^26 points");
        per_file.push_back({name.empty() ? ValueSource{} : find_value_set(*files_[i], name),
                            static_cast<std::uint32_t>(first_streamline), index, &indexes, i});
        first_streamline += files_[i]->meta().streamline_count;
      }
    scene_.upload_attributes(std::move(per_file));
    attributes_key_ = key;
  }
  if (!key.empty() && streamline_groups_stale_) upload_streamline_groups(groups);
}

void LinePass::upload_streamline_groups(const SceneGroups& groups) {
  std::uint64_t total = 0;
  for (const VxlFile* f : files_) total += f->meta().streamline_count;
  const std::uint64_t max_texels = gl::max_buffer_texels();
  if (total > max_texels || total > 0xFFFFFFFFu)
    throw Error(ErrorKind::Unsupported, files_.front()->path(), std::nullopt,
                "colour or opacity by group needs a table of " + std::to_string(total) +
                    " streamlines; this GPU's buffer textures hold " + std::to_string(max_texels));
  std::vector<std::uint8_t> table(std::max<std::uint64_t>(total, 1), 0);
  std::uint64_t at = 0;
  for (std::size_t i = 0; i < files_.size(); ++i) {
    const std::uint64_t n = files_[i]->meta().streamline_count;
    groups.write_table(i, {table.data() + at, static_cast<std::size_t>(n)}, shaders::kShaderGroups);
    at += n;
  }
  streamline_groups_.destroy();
  streamline_groups_.create(GL_R8UI, table.data(), table.size());
  streamline_groups_stale_ = false;
}

void LinePass::bind(GLuint mode_program, const LineUniforms& u) const {
  const GLuint program = drawn(mode_program);
  const Camera& camera = u.camera;
  const RenderSettings& s = u.settings;
  glUseProgram(program);
  const glm::dvec3 eye = camera.eye();
  const glm::vec3 hi(eye);
  const glm::vec3 lo(eye - glm::dvec3(hi));
  glUniform3fv(glGetUniformLocation(program, "u_eye_hi"), 1, glm::value_ptr(hi));
  glUniform3fv(glGetUniformLocation(program, "u_eye_lo"), 1, glm::value_ptr(lo));
  const glm::mat3 rotation = camera.view_rotation();
  glUniformMatrix3fv(glGetUniformLocation(program, "u_rotation"), 1, GL_FALSE, glm::value_ptr(rotation));
  const glm::mat4 proj(u.projection);
  glUniformMatrix4fv(glGetUniformLocation(program, "u_projection"), 1, GL_FALSE, glm::value_ptr(proj));
  glUniform1i(glGetUniformLocation(program, "u_color_mode"), static_cast<int>(s.color));
  glUniform3fv(glGetUniformLocation(program, "u_fixed_color"), 1, glm::value_ptr(s.fixed_color));
  glUniform1i(glGetUniformLocation(program, "u_attributes"), attributes_key_.empty() ? 0 : 1);
  glUniform3fv(glGetUniformLocation(program, "u_colormap"), kColormapSamples,
               glm::value_ptr(colormap_samples(s.colormap)[0]));
  glUniform2f(glGetUniformLocation(program, "u_range"), u.scalar_range[0], u.scalar_range[1]);
  std::vector<glm::vec4> group(shaders::kShaderGroups, glm::vec4(1.0f));
  const auto& groups = u.groups.groups();
  for (std::size_t g = 0; g < groups.size() && g < group.size(); ++g) group[g] = s.group_color(groups[g].name, g);
  for (std::size_t g = 0; g < groups.size() && g < group.size(); ++g)
    if (groups[g].hidden) group[g].a = 0.0f;
  // A coarse level's segment stands for the 8^level segments it samples (.vxl spec §6.5).
  const float opacity = SceneLayout::level_opacity(std::clamp(s.opacity, 0.001f, 1.0f), scene_.layout().level());
  if (!scene_.layout().one_level()) {
    // Files at several levels (a focus copy at full detail): a group drawn from finer files than the scene's
    // level gets its own compensation, as a factor on u_opacity.
    const std::vector<std::uint32_t> levels = group_levels(u.groups, scene_.layout());
    for (std::size_t g = 0; g < levels.size() && g < group.size(); ++g)
      if (levels[g] != scene_.layout().level())
        group[g].a *= SceneLayout::level_opacity(std::clamp(s.opacity, 0.001f, 1.0f), levels[g]) / opacity;
  }
  glUniform4fv(glGetUniformLocation(program, "u_group"), shaders::kShaderGroups, glm::value_ptr(group[0]));
  glUniform1f(glGetUniformLocation(program, "u_opacity"), opacity);
  glUniform1i(glGetUniformLocation(program, "u_lighting"), s.lighting ? 1 : 0);
  const glm::vec3 light = lighting::light_direction_eye();
  glUniform3fv(glGetUniformLocation(program, "u_light"), 1, glm::value_ptr(light));
  glUniform4f(glGetUniformLocation(program, "u_light_terms"), lighting::kAmbient, lighting::kDiffuse,
              lighting::kSpecular, lighting::kShininess);
  glUniform1i(glGetUniformLocation(program, "u_orthographic"), camera.orthographic ? 1 : 0);
  bind_clip_half_spaces(program, clip_half_spaces(s.clipping, camera), eye);
  // The streamline groups' table on the first unit after the spans', the slices' depth on the next (units
  // of their own: two sampler types must not share one), bound even when unused.
  const GLint groups_unit = static_cast<GLint>(kSamplersPerSpan * span_slots(program));
  glActiveTexture(GL_TEXTURE0 + groups_unit);
  glBindTexture(gl::kBufferTextureTarget, streamline_groups_.texture);
  glUniform1i(glGetUniformLocation(program, "u_streamline_group"), groups_unit);
  const GLint unit = groups_unit + 1;
  glActiveTexture(GL_TEXTURE0 + unit);
  glBindTexture(GL_TEXTURE_2D, u.slice_depth);
  glUniform1i(glGetUniformLocation(program, "u_slice_depth"), unit);
  glUniform1i(glGetUniformLocation(program, "u_slice_test"), u.slice_depth != 0 ? 1 : 0);
  glActiveTexture(GL_TEXTURE0);
}

void LinePass::bind_spans(GLuint program, unsigned slots, std::span<const std::uint32_t> bound,
                          std::span<const std::int64_t> base) const {
  const auto& spans = scene_.layout().texture_spans();
  // Per slot: where its ids start in this draw and how its buffers are laid out (scene_layout.h); a slot
  // left empty starts past every id.
  std::vector<std::pair<const char*, std::vector<GLint>>> fields = {
      {"u_span_base", {}},   {"u_span_segments", {}},      {"u_span_slots", {}},        {"u_span_vertices", {}},
      {"u_span_voxels", {}}, {"u_span_segment_table", {}}, {"u_span_vertex_table", {}}, {"u_span_order_words", {}},
  };
  for (std::size_t slot = 0; slot < slots; ++slot) {
    std::int64_t values[] = {std::numeric_limits<std::int32_t>::max(), 1, 1, 0, 1, 0, 0, 1};
    if (slot < bound.size()) {
      const TextureSpan& c = spans[bound[slot]];
      // The order buffer holds at least one word (gl::TextureBuffer keeps 16 bytes for an empty one).
      const std::int64_t used[] = {base[slot],
                                   static_cast<std::int64_t>(std::max<std::uint64_t>(1, c.segments)),
                                   c.slots,
                                   static_cast<std::int64_t>(c.vertices),
                                   std::max<std::int64_t>(1, c.voxel_count),
                                   static_cast<std::int64_t>(c.segment_table_first()),
                                   static_cast<std::int64_t>(c.vertex_table_first()),
                                   static_cast<std::int64_t>(std::max<std::uint64_t>(1, c.order_words))};
      std::copy(std::begin(used), std::end(used), values);
    }
    for (std::size_t f = 0; f < fields.size(); ++f) fields[f].second.push_back(static_cast<GLint>(values[f]));
  }
  for (const auto& [name, values] : fields)
    glUniform1iv(glGetUniformLocation(program, name), static_cast<GLsizei>(values.size()), values.data());
  const char* names[kSamplersPerSpan] = {"u_words", "u_ord", "u_dat", "u_att"};
  for (std::size_t slot = 0; slot < slots; ++slot) {
    const GpuTextureSpan* g = slot < bound.size() ? &scene_.texture_spans()[bound[slot]] : nullptr;
    const GLuint textures[kSamplersPerSpan] = {g ? g->words.texture : 0, g ? g->orders.texture : 0,
                                               g ? g->dataset.texture : 0, g ? g->attributes.texture : 0};
    for (int t = 0; t < kSamplersPerSpan; ++t) {
      const GLint unit = static_cast<GLint>(kSamplersPerSpan * slot + t);
      glActiveTexture(GL_TEXTURE0 + unit);
      glBindTexture(gl::kBufferTextureTarget, textures[t]);
      glUniform1i(glGetUniformLocation(program, (names[t] + std::to_string(slot)).c_str()), unit);
    }
  }
  glActiveTexture(GL_TEXTURE0);
}

void LinePass::draw_plan(GLuint mode_program, std::span<const std::int64_t> first,
                         std::span<const std::int32_t> count) const {
  if (first.empty()) return;
  const GLuint program = drawn(mode_program);
  const unsigned slots = span_slots(program);
  glBindVertexArray(vao_);
  const SceneLayout& layout = scene_.layout();
  const auto& spans = layout.texture_spans();
  // Consecutive runs of the sequence, each over at most bound_spans_ spans whose ids, rebased one after
  // another, stay below 2^31: one multi-draw each, in order, so blending sees the same sequence.
  std::vector<std::uint32_t> bound;
  std::vector<std::int64_t> base;
  std::vector<GLint> run_first;
  std::vector<GLsizei> run_count;
  std::int64_t next_base = 0;
  auto flush = [&] {
    if (run_first.empty()) return;
    bind_spans(program, slots, bound, base);
    gl::multi_draw(GL_LINES, run_first.data(), run_count.data(), static_cast<GLsizei>(run_first.size()));
    bound.clear();
    base.clear();
    run_first.clear();
    run_count.clear();
    next_base = 0;
  };
  for (std::size_t i = 0; i < first.size(); ++i) {
    const std::uint32_t span = layout.span_of_id(first[i]);
    std::size_t slot = std::find(bound.begin(), bound.end(), span) - bound.begin();
    if (slot == bound.size()) {
      const std::int64_t ids = static_cast<std::int64_t>(spans[span].virtual_ids());
      if (bound.size() == slots || next_base + ids > std::numeric_limits<std::int32_t>::max()) flush();
      slot = bound.size();
      bound.push_back(span);
      base.push_back(next_base);
      next_base += ids;
    }
    run_first.push_back(
        static_cast<GLint>(first[i] - static_cast<std::int64_t>(spans[span].virtual_base) + base[slot]));
    run_count.push_back(count[i]);
  }
  flush();
}

}  // namespace vxl
