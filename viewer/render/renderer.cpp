#include "viewer/render/renderer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include <glm/gtc/type_ptr.hpp>

#include "format/base/error.h"
#include "viewer/render/exact_renderer.h"
#include "viewer/render/line_lighting.h"
#include "viewer/render/line_shaders.h"
#include "viewer/render/region_shells.h"
#include "viewer/render/segment_sort.h"
#include "viewer/render/slice_renderer.h"
#include "viewer/render/vertex_attributes.h"
#include "viewer/render/view_queries.h"

namespace vxl {

Renderer::Renderer(const VxlFile& file, std::uint64_t max_texels, std::uint32_t level)
    : Renderer(std::vector<const VxlFile*>{&file}, max_texels, level) {}

Renderer::Renderer(std::vector<const VxlFile*> files, std::uint64_t max_texels, std::uint32_t level,
                   std::shared_ptr<GpuMemoryPool> pool, bool eager)
    : files_(files.empty() ? throw Error(ErrorKind::Usage, "", std::nullopt, "Renderer: no files") : files),
      scene_(files_, max_texels, level, std::move(pool), eager),
      groups_(files_),
      indexes_(std::make_shared<VoxelVoxlinesCache>(files_)) {
  const VxlFile& file = *files_.front();
  for (const VxlFile* f : files_)
    for (const ValueSets* sets : {&f->vertex_values(), &f->streamline_values()})
      for (std::uint32_t k = 0; k < sets->size(); ++k)
        if (std::find(value_set_names_.begin(), value_set_names_.end(), sets->name(k)) == value_set_names_.end())
          value_set_names_.push_back(sets->name(k));
  // A draw binds up to kMaxBoundSpans spans, as many as the vertex shader's texture units allow beside the
  // streamline groups' table (GL 3.3 promises 16: three spans).
  GLint units = 0;
  glGetIntegerv(GL_MAX_VERTEX_TEXTURE_IMAGE_UNITS, &units);
  const std::size_t spans = std::max<std::size_t>(1, scene_.layout().texture_spans().size());
  bound_spans_ = static_cast<unsigned>(std::min<std::size_t>(
      {spans, kMaxBoundSpans, static_cast<std::size_t>(std::max(0, units - 1)) / kSamplersPerSpan}));
  if (bound_spans_ == 0)
    throw Error(ErrorKind::Unsupported, file.path(), std::nullopt,
                "this GPU offers " + std::to_string(units) + " vertex-shader textures; the lines need " +
                    std::to_string(kSamplersPerSpan + 1));
  glGenVertexArrays(1, &vao_);  // core profile draws need a bound VAO, even without attributes
  make_line_programs();
  wboit_composite_ = gl::make_program(shaders::kFullscreenVertex, shaders::kWboitCompositeFragment);
  additive_composite_ = gl::make_program(shaders::kFullscreenVertex, shaders::kAdditiveCompositeFragment);
}

Renderer::~Renderer() {
  exact_.reset();
  segment_sorter_.reset();
  slices_.reset();
  for (GLuint p :
       {over_program_, accum_program_, reveal_program_, additive_program_, wboit_composite_, additive_composite_})
    if (p) glDeleteProgram(p);
  streamline_groups_.destroy();
  wboit_target_.destroy();
  opaque_target_.destroy();
  additive_target_.destroy();
  if (vao_) glDeleteVertexArrays(1, &vao_);
}

std::pair<glm::dvec3, glm::dvec3> Renderer::bounds() const {
  const SceneBounds b = line_bounds(files_);
  return {b.min, b.max};
}

glm::dvec3 Renderer::scene_min() const { return slices_ ? glm::min(bounds_min(), slices_->ras_min()) : bounds_min(); }
glm::dvec3 Renderer::scene_max() const { return slices_ ? glm::max(bounds_max(), slices_->ras_max()) : bounds_max(); }

void Renderer::make_line_programs() {
  for (GLuint* p : {&over_program_, &accum_program_, &reveal_program_, &additive_program_})
    if (*p) glDeleteProgram(std::exchange(*p, 0));
  const std::string vs = shaders::line_vertex(bound_spans_);
  const char* const version = "#version 330 core";
  const bool slice_test = slices_ != nullptr;
  over_program_ = gl::make_program(vs, shaders::line_fragment(shaders::kLineOverFragment, version, slice_test));
  accum_program_ = gl::make_program(vs, shaders::line_fragment(shaders::kLineWboitAccumFragment, version, slice_test));
  reveal_program_ =
      gl::make_program(vs, shaders::line_fragment(shaders::kLineWboitRevealFragment, version, slice_test));
  additive_program_ = gl::make_program(vs, shaders::line_fragment(shaders::kLineAdditiveFragment, version, slice_test));
}

void Renderer::set_volume(const Volume& volume) {
  slices_ = std::make_unique<SliceRenderer>(volume);
  // The line programs now test against the slices' depth; exact's list program is made again on first use.
  make_line_programs();
  exact_.reset();
  pieces_.reset();
}

std::array<float, 2> Renderer::slice_range(const RenderSettings& s) const {
  return slices_ ? slices_->range(s.slices) : std::array<float, 2>{0, 1};
}

GLuint Renderer::slice_color_texture() const { return slices_drawn_ ? slices_->color_texture() : 0; }

glm::dmat4 Renderer::projection(const Camera& camera, double aspect) const {
  // Near and far planes hug the lines and the image.
  return fitted_projection(camera, aspect, {scene_min(), scene_max()}, scene_.layout().voxel_size());
}

void Renderer::plan(const Camera& camera, double aspect, PlanOrder order, FramePlan& out,
                    const Clipping& clipping) const {
  plan_view(scene_.layout(), camera, projection(camera, aspect), order, out, clipping);
}

std::uint64_t Renderer::view_bytes(const Camera& camera, double aspect, const Clipping& clipping) const {
  return vxl::view_bytes(scene_.layout(), camera, aspect, {scene_min(), scene_max()}, clipping);
}

void Renderer::plan_and_count(const Camera& camera, double aspect, PlanOrder order, FramePlan& out,
                              const Clipping& clipping) {
  auto t0 = std::chrono::steady_clock::now();
  plan(camera, aspect, order, out, clipping);
  keep_resident(out);
  stats_.plan_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  stats_.voxels_drawn = out.voxels_drawn;
  stats_.segments_drawn = out.segments_drawn;
}

bool Renderer::upload_for(const Camera& camera, double aspect, const Clipping& clipping, double max_ms) {
  FramePlan nearest;
  plan(camera, aspect, PlanOrder::Nearest, nearest, clipping);
  return !scene_.make_resident(spans_nearest_first(scene_.layout(), nearest), max_ms).out_of_time;
}

void Renderer::keep_resident(FramePlan& plan) {
  const SceneLayout& layout = scene_.layout();
  const std::vector<std::uint32_t> needed = spans_nearest_first(layout, plan);
  stats_.voxels_waiting = 0;
  if (scene_.make_resident(needed).complete) return;
  // The budget holds only some: draw the voxels whose span is resident, in the plan's order.
  std::size_t kept = 0;
  plan.segments_drawn = 0;
  for (std::size_t i = 0; i < plan.first.size(); ++i) {
    if (!scene_.resident(layout.span_of_id(plan.first[i]))) continue;
    plan.first[kept] = plan.first[i];
    plan.count[kept] = plan.count[i];
    if (!plan.voxels.empty()) plan.voxels[kept] = plan.voxels[i];
    plan.segments_drawn += static_cast<std::uint64_t>(plan.count[i] / 2);
    ++kept;
  }
  stats_.voxels_waiting = plan.first.size() - kept;
  plan.first.resize(kept);
  plan.count.resize(kept);
  if (!plan.voxels.empty()) plan.voxels.resize(kept);
  plan.voxels_drawn = kept;
}

void Renderer::prepare(RenderMode mode) {
  if (mode == RenderMode::Unsorted) scene_.dataset_first();
  if (mode == RenderMode::Segsort) scene_.prepare_view_order();
}

void Renderer::bind_line_program(GLuint program, const Camera& camera, const RenderSettings& s, double aspect) const {
  glUseProgram(program);
  const glm::dvec3 eye = camera.eye();
  const glm::vec3 hi(eye);
  const glm::vec3 lo(eye - glm::dvec3(hi));
  glUniform3fv(glGetUniformLocation(program, "u_eye_hi"), 1, glm::value_ptr(hi));
  glUniform3fv(glGetUniformLocation(program, "u_eye_lo"), 1, glm::value_ptr(lo));
  const glm::mat3 rotation = camera.view_rotation();
  glUniformMatrix3fv(glGetUniformLocation(program, "u_rotation"), 1, GL_FALSE, glm::value_ptr(rotation));
  const glm::mat4 proj(projection(camera, aspect));
  glUniformMatrix4fv(glGetUniformLocation(program, "u_projection"), 1, GL_FALSE, glm::value_ptr(proj));
  glUniform1i(glGetUniformLocation(program, "u_color_mode"), static_cast<int>(s.color));
  glUniform3fv(glGetUniformLocation(program, "u_fixed_color"), 1, glm::value_ptr(s.fixed_color));
  glUniform1i(glGetUniformLocation(program, "u_attributes"), attributes_key_.empty() ? 0 : 1);
  glUniform3fv(glGetUniformLocation(program, "u_colormap"), kColormapSamples,
               glm::value_ptr(colormap_samples(s.colormap)[0]));
  const std::array<float, 2> range = scalar_range(s);
  glUniform2f(glGetUniformLocation(program, "u_range"), range[0], range[1]);
  std::vector<glm::vec4> group(shaders::kShaderGroups, glm::vec4(1.0f));
  const auto& groups = groups_.groups();
  for (std::size_t g = 0; g < groups.size() && g < group.size(); ++g) group[g] = s.group_color(groups[g].name, g);
  glUniform4fv(glGetUniformLocation(program, "u_group"), shaders::kShaderGroups, glm::value_ptr(group[0]));
  // A coarse level's segment stands for the 8^level segments it samples (.vxl spec §6.5).
  const float opacity = SceneLayout::level_opacity(std::clamp(s.opacity, 0.001f, 1.0f), scene_.layout().level());
  glUniform1f(glGetUniformLocation(program, "u_opacity"), opacity);
  glUniform1i(glGetUniformLocation(program, "u_lighting"), s.lighting ? 1 : 0);
  const glm::vec3 light = lighting::light_direction_eye();
  glUniform3fv(glGetUniformLocation(program, "u_light"), 1, glm::value_ptr(light));
  glUniform4f(glGetUniformLocation(program, "u_light_terms"), lighting::kAmbient, lighting::kDiffuse,
              lighting::kSpecular, lighting::kShininess);
  glUniform1i(glGetUniformLocation(program, "u_orthographic"), camera.orthographic ? 1 : 0);
  std::vector<glm::vec4> clip;
  for (const glm::dvec4& h : clip_half_spaces(s.clipping, camera)) clip.push_back(glm::vec4(relative_to(h, eye)));
  const int clips = static_cast<int>(std::min<std::size_t>(clip.size(), kMaxClipDistances));
  if (clips > 0) glUniform4fv(glGetUniformLocation(program, "u_clip"), clips, glm::value_ptr(clip[0]));
  glUniform1i(glGetUniformLocation(program, "u_clip_count"), clips);
  enable_clip_distances(clips);
  // The streamline groups' table on the first unit after the spans', the slices' depth on the next (units
  // of their own: two sampler types must not share one), bound even when unused.
  const GLint groups_unit = static_cast<GLint>(kSamplersPerSpan * bound_spans_);
  glActiveTexture(GL_TEXTURE0 + groups_unit);
  glBindTexture(GL_TEXTURE_BUFFER, streamline_groups_.texture);
  glUniform1i(glGetUniformLocation(program, "u_streamline_group"), groups_unit);
  const GLint unit = groups_unit + 1;
  glActiveTexture(GL_TEXTURE0 + unit);
  glBindTexture(GL_TEXTURE_2D, slices_drawn_ ? slices_->depth_texture() : 0);
  glUniform1i(glGetUniformLocation(program, "u_slice_depth"), unit);
  glUniform1i(glGetUniformLocation(program, "u_slice_test"), slices_drawn_ ? 1 : 0);
  glActiveTexture(GL_TEXTURE0);
}

void Renderer::enable_clip_distances(int n) {
  for (int i = 0; i < kMaxClipDistances; ++i) {
    if (i < n)
      glEnable(GL_CLIP_DISTANCE0 + i);
    else
      glDisable(GL_CLIP_DISTANCE0 + i);
  }
}

std::string Renderer::scalar_name(const RenderSettings& s) const {
  if (!s.scalar.empty()) return s.scalar;
  return value_set_names_.empty() ? std::string() : value_set_names_.front();
}

std::array<float, 2> Renderer::scalar_range(const RenderSettings& s) const {
  float lo = 0, hi = 1;
  if (s.range) {
    lo = (*s.range)[0];
    hi = (*s.range)[1];
  } else if (const std::string name = scalar_name(s); !name.empty()) {
    // The stored extremes of the set over the files that have it (NaN when one has no finite value).
    bool any = false;
    for (const VxlFile* f : files_) {
      const ValueSource v = find_value_set(*f, name);
      const ValueSets* sets = v.kind == ValueSource::Kind::Vertex       ? &f->vertex_values()
                              : v.kind == ValueSource::Kind::Streamline ? &f->streamline_values()
                                                                        : nullptr;
      if (!sets || !std::isfinite(sets->min(v.set)) || !std::isfinite(sets->max(v.set))) continue;
      lo = any ? std::min(lo, sets->min(v.set)) : sets->min(v.set);
      hi = any ? std::max(hi, sets->max(v.set)) : sets->max(v.set);
      any = true;
    }
  }
  if (!(hi > lo)) {  // one value only: show it mid-map
    const float mid = std::isfinite(lo) ? lo : 0.0f;
    lo = mid - 0.5f;
    hi = mid + 0.5f;
  }
  return {lo, hi};
}

void Renderer::set_groups(SceneGroups groups) {
  groups_ = std::move(groups);
  streamline_groups_stale_ = true;  // the next frame uploads the table; the per-vertex words stay
}

void Renderer::prepare_attributes(const RenderSettings& s) {
  const std::string name = s.color == ColorMode::Scalar ? scalar_name(s) : std::string();
  bool want_groups = s.color == ColorMode::Group;
  const auto& groups = groups_.groups();
  for (std::size_t g = 0; g < groups.size(); ++g) want_groups |= s.group_color(groups[g].name, g).a != 1.0f;
  const std::string key = name.empty() && !want_groups ? "" : "value:" + name;
  if (key != attributes_key_) {
    std::vector<AttributeSource> per_file;
    std::uint64_t first_streamline = 0;
    if (!key.empty())
      for (std::size_t i = 0; i < files_.size(); ++i) {
        const VoxelVoxlines* index = indexes_->of(i);
        if (index == nullptr)
          throw Error(ErrorKind::Unsupported, files_[i]->path(), std::nullopt,
                      "colour or opacity by value or group needs the voxel index of voxlines, which holds fewer than "
                      "2^32 streamlines and voxlines of fewer than 2^26 points");
        per_file.push_back({name.empty() ? ValueSource{} : find_value_set(*files_[i], name),
                            static_cast<std::uint32_t>(first_streamline), index});
        first_streamline += files_[i]->meta().streamline_count;
      }
    scene_.upload_attributes(std::move(per_file));
    attributes_key_ = key;
  }
  if (!key.empty() && streamline_groups_stale_) upload_streamline_groups();
}

void Renderer::upload_streamline_groups() {
  std::uint64_t total = 0;
  for (const VxlFile* f : files_) total += f->meta().streamline_count;
  GLint max_texels = 0;
  glGetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, &max_texels);
  if (total > static_cast<std::uint64_t>(std::max(0, max_texels)) || total > 0xFFFFFFFFu)
    throw Error(ErrorKind::Unsupported, files_.front()->path(), std::nullopt,
                "colour or opacity by group needs a table of " + std::to_string(total) +
                    " streamlines; this GPU's buffer textures hold " + std::to_string(max_texels));
  std::vector<std::uint8_t> table(std::max<std::uint64_t>(total, 1), 0);
  std::uint64_t at = 0;
  for (std::size_t i = 0; i < files_.size(); ++i) {
    const std::uint64_t n = files_[i]->meta().streamline_count;
    if (groups_.uniform(i))
      std::fill_n(table.begin() + at, n, std::uint8_t(groups_.group_of(i, 0) % shaders::kShaderGroups));
    else
      for (std::uint64_t s = 0; s < n; ++s)
        table[at + s] = std::uint8_t(groups_.group_of(i, s) % shaders::kShaderGroups);
    at += n;
  }
  streamline_groups_.destroy();
  streamline_groups_.create(GL_R8UI, table.data(), table.size());
  streamline_groups_stale_ = false;
}

void Renderer::bind_spans(GLuint program, std::span<const std::uint32_t> bound,
                          std::span<const std::int64_t> base) const {
  const auto& spans = scene_.layout().texture_spans();
  // Per slot: where its ids start in this draw and how its buffers are laid out (scene_layout.h); a slot
  // left empty starts past every id.
  std::vector<std::pair<const char*, std::vector<GLint>>> fields = {
      {"u_span_base", {}},     {"u_span_segments", {}},      {"u_span_slots", {}},        {"u_span_wide", {}},
      {"u_span_vertices", {}}, {"u_span_segment_table", {}}, {"u_span_vertex_table", {}},
  };
  for (std::size_t slot = 0; slot < bound_spans_; ++slot) {
    std::int64_t values[] = {std::numeric_limits<std::int32_t>::max(), 1, 1, 0, 0, 0, 0};
    if (slot < bound.size()) {
      const TextureSpan& c = spans[bound[slot]];
      const std::int64_t used[] = {base[slot],
                                   static_cast<std::int64_t>(std::max<std::uint64_t>(1, c.segments)),
                                   c.slots,
                                   static_cast<std::int64_t>(c.wide_segments),
                                   static_cast<std::int64_t>(c.vertices),
                                   static_cast<std::int64_t>(c.segment_table_first()),
                                   static_cast<std::int64_t>(c.vertex_table_first())};
      std::copy(std::begin(used), std::end(used), values);
    }
    for (std::size_t f = 0; f < fields.size(); ++f) fields[f].second.push_back(static_cast<GLint>(values[f]));
  }
  for (const auto& [name, values] : fields)
    glUniform1iv(glGetUniformLocation(program, name), static_cast<GLsizei>(values.size()), values.data());
  const char* names[kSamplersPerSpan] = {"u_words", "u_ord", "u_dat", "u_att"};
  for (std::size_t slot = 0; slot < bound_spans_; ++slot) {
    const GpuTextureSpan* g = slot < bound.size() ? &scene_.texture_spans()[bound[slot]] : nullptr;
    const GLuint textures[kSamplersPerSpan] = {g ? g->words.texture : 0, g ? g->orders.texture : 0,
                                               g ? g->dataset.texture : 0, g ? g->attributes.texture : 0};
    for (int t = 0; t < kSamplersPerSpan; ++t) {
      const GLint unit = static_cast<GLint>(kSamplersPerSpan * slot + t);
      glActiveTexture(GL_TEXTURE0 + unit);
      glBindTexture(GL_TEXTURE_BUFFER, textures[t]);
      glUniform1i(glGetUniformLocation(program, (names[t] + std::to_string(slot)).c_str()), unit);
    }
  }
  glActiveTexture(GL_TEXTURE0);
}

void Renderer::draw_plan(GLuint program, std::span<const std::int64_t> first,
                         std::span<const std::int32_t> count) const {
  if (first.empty()) return;
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
    bind_spans(program, bound, base);
    glMultiDrawArrays(GL_LINES, run_first.data(), run_count.data(), static_cast<GLsizei>(run_first.size()));
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
      if (bound.size() == bound_spans_ || next_base + ids > std::numeric_limits<std::int32_t>::max()) flush();
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

void Renderer::draw_lines(GLuint program, const Camera& camera, const RenderSettings& s, double aspect,
                          PlanOrder order) {
  plan_and_count(camera, aspect, order, plan_, s.clipping);
  bind_line_program(program, camera, s, aspect);
  draw_plan(program, plan_.first, plan_.count);
}

void Renderer::draw_dataset_order(GLuint program, const Camera& camera, const RenderSettings& s, double aspect) {
  FramePlan dataset;  // runs of the streamline order, one span each
  dataset.first = scene_.dataset_first();
  dataset.count = scene_.dataset_count();
  keep_resident(dataset);
  stats_.plan_ms = 0;
  stats_.voxels_drawn = stats_.segments_drawn = 0;
  for (const VxlFile* f : files_) stats_.voxels_drawn += f->meta().voxel_count;
  for (std::int32_t ids : dataset.count) stats_.segments_drawn += static_cast<std::uint64_t>(ids / 2);  // the level's
  bind_line_program(program, camera, s, aspect);
  draw_plan(program, dataset.first, dataset.count);
}

void Renderer::draw_segment_sorted(GLuint program, const Camera& camera, const RenderSettings& s, double aspect) {
  // The dataset buffers take the view order first, so that the budget counts them when the spans are made
  // resident. Then the voxels back to front as axis sorts them (Block and Nearest share the sort), then each
  // one's segments for this view; the plan's ranges then point into the dataset buffers.
  scene_.prepare_view_order();
  plan_and_count(camera, aspect, PlanOrder::Block, plan_, s.clipping);
  auto t0 = std::chrono::steady_clock::now();
  if (!segment_sorter_) segment_sorter_ = std::make_unique<SegmentSorter>(scene_.layout(), files_);
  segment_sorter_->sort(SegmentSortView{camera.eye(), camera.forward(), camera.orthographic}, plan_);
  stats_.plan_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  std::vector<const std::vector<std::uint32_t>*> arrays;
  std::vector<std::pair<std::uint64_t, std::uint64_t>> ranges;
  for (std::uint32_t c = 0; c < scene_.layout().texture_spans().size(); ++c) {
    arrays.push_back(&segment_sorter_->span_order(c));
    ranges.push_back(segment_sorter_->written(c));
  }
  scene_.upload_view_order(arrays, ranges);
  bind_line_program(program, camera, s, aspect);
  draw_plan(program, plan_.first, plan_.count);
}

void Renderer::composite(GLuint program, std::initializer_list<std::pair<const char*, GLuint>> textures) const {
  enable_clip_distances(0);
  glUseProgram(program);
  GLint unit = 0;
  for (const auto& [name, texture] : textures) {
    glActiveTexture(GL_TEXTURE0 + unit);
    glBindTexture(GL_TEXTURE_2D, texture);
    glUniform1i(glGetUniformLocation(program, name), unit++);
  }
  glBindVertexArray(vao_);
  glDrawArrays(GL_TRIANGLES, 0, 3);  // a fullscreen triangle
  glActiveTexture(GL_TEXTURE0);
}

void Renderer::over_blending() {
  glEnable(GL_BLEND);
  // Premultiply colour, accumulate coverage: destination alpha reaches 1 (docs/rendering.md, pitfall 1).
  glBlendFuncSeparate(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
}

void Renderer::opaque_blending() {
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  // The colour replaces, the alpha stays the clear's 1: an opaque picture (a PNG would otherwise keep the
  // lines' opacity as their alpha).
  glEnable(GL_BLEND);
  glBlendFuncSeparate(GL_ONE, GL_ZERO, GL_ZERO, GL_ONE);
}

void Renderer::clear_to_base(GLuint fbo, const Camera& camera, const RenderSettings& s, int width, int height) {
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  glViewport(0, 0, width, height);
  const glm::vec3 background = s.background();
  glClearColor(background.r, background.g, background.b, 1.0f);
  glClearDepth(1.0);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  if (slices_drawn_) slices_->copy_color();
  draw_shells(ShellHalf::Back, camera, s, width, height);
}

void Renderer::start_frame(const Camera& camera, const RenderSettings& s, int width, int height) {
  const double aspect = double(width) / std::max(1, height);
  prepare_attributes(s);
  // The opaque slices first: their colour is the base of the picture, their depth hides lines behind them.
  slices_drawn_ = slices_ && s.slices.any();
  if (slices_drawn_)
    slices_->draw(camera, projection(camera, aspect), s.slices, clip_half_spaces(s.clipping, camera), s.background(),
                  width, height);
  glLineWidth(std::max(1.0f, s.line_width));
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_BLEND);
  glDepthMask(GL_TRUE);
}

void Renderer::draw(const Camera& camera, const RenderSettings& s, int width, int height, GLuint fbo) {
  pieces_.reset();
  const double aspect = double(width) / std::max(1, height);
  auto clear_target = [&](GLuint target, glm::vec4 colour) {
    glBindFramebuffer(GL_FRAMEBUFFER, target);
    glViewport(0, 0, width, height);
    glClearColor(colour.r, colour.g, colour.b, colour.a);
    glClearDepth(1.0);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  };
  start_frame(camera, s, width, height);

  switch (s.mode) {
    case RenderMode::Opaque:
      clear_to_base(fbo, camera, s, width, height);
      opaque_blending();
      draw_lines(over_program_, camera, s, aspect, PlanOrder::Any);
      glDisable(GL_DEPTH_TEST);
      break;
    case RenderMode::Unsorted:
      clear_to_base(fbo, camera, s, width, height);
      over_blending();
      draw_dataset_order(over_program_, camera, s, aspect);
      break;
    case RenderMode::Basic:
      clear_to_base(fbo, camera, s, width, height);
      over_blending();
      draw_lines(over_program_, camera, s, aspect, PlanOrder::Block);
      break;
    case RenderMode::Axis:
      clear_to_base(fbo, camera, s, width, height);
      over_blending();
      plan_.order_hysteresis = s.order_hysteresis;
      draw_lines(over_program_, camera, s, aspect, PlanOrder::Nearest);
      break;
    case RenderMode::Segsort:  // as axis, but each voxel's segments sorted for this view
      clear_to_base(fbo, camera, s, width, height);
      over_blending();
      draw_segment_sorted(over_program_, camera, s, aspect);
      break;
    case RenderMode::Wboit: {
      wboit_target_.ensure(width, height, GL_RGBA16F, GL_RGBA16F, false);
      glBindFramebuffer(GL_FRAMEBUFFER, wboit_target_.fbo);
      glViewport(0, 0, width, height);
      const GLenum accum = GL_COLOR_ATTACHMENT0, reveal = GL_COLOR_ATTACHMENT1;
      glDrawBuffers(1, &accum);
      glClearColor(0, 0, 0, 0);
      glClear(GL_COLOR_BUFFER_BIT);
      glEnable(GL_BLEND);
      glBlendFunc(GL_ONE, GL_ONE);
      draw_lines(accum_program_, camera, s, aspect, PlanOrder::Any);
      glDrawBuffers(1, &reveal);
      glClearColor(1, 1, 1, 1);
      glClear(GL_COLOR_BUFFER_BIT);
      glBlendFunc(GL_ZERO, GL_ONE_MINUS_SRC_COLOR);
      bind_line_program(reveal_program_, camera, s, aspect);
      draw_plan(reveal_program_, plan_.first, plan_.count);
      const GLenum both[2] = {accum, reveal};
      glDrawBuffers(2, both);
      clear_to_base(fbo, camera, s, width, height);
      over_blending();
      composite(wboit_composite_, {{"u_accum", wboit_target_.color[0]}, {"u_reveal", wboit_target_.color[1]}});
      break;
    }
    case RenderMode::Additive: {
      opaque_target_.ensure(width, height, GL_RGBA8, 0, true);
      additive_target_.ensure(width, height, GL_RGBA16F, 0, false);
      clear_target(opaque_target_.fbo, glm::vec4(0));
      glEnable(GL_DEPTH_TEST);
      glDepthFunc(GL_LESS);
      RenderSettings solid = s;
      solid.opacity = 1.0f;
      draw_lines(over_program_, camera, solid, aspect, PlanOrder::Any);
      glDisable(GL_DEPTH_TEST);
      glBindFramebuffer(GL_FRAMEBUFFER, additive_target_.fbo);
      glClearColor(0, 0, 0, 0);
      glClear(GL_COLOR_BUFFER_BIT);
      glEnable(GL_BLEND);
      glBlendFunc(GL_ONE, GL_ONE);
      bind_line_program(additive_program_, camera, s, aspect);
      draw_plan(additive_program_, plan_.first, plan_.count);
      clear_to_base(fbo, camera, s, width, height);
      over_blending();
      glUseProgram(additive_composite_);
      glUniform1f(glGetUniformLocation(additive_composite_, "u_opacity"), std::clamp(s.opacity, 0.001f, 1.0f));
      composite(additive_composite_,
                {{"u_opaque", opaque_target_.color[0]}, {"u_additive", additive_target_.color[0]}});
      break;
    }
    case RenderMode::Exact:
      if (!exact_) exact_ = std::make_unique<ExactRenderer>(*this);
      shells_under_exact(camera, s, width, height, fbo);
      exact_->draw(camera, s, width, height, fbo);
      break;
  }
  draw_shells(ShellHalf::Front, camera, s, width, height);
  glDisable(GL_BLEND);
  enable_clip_distances(0);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
}

struct Renderer::Pieces {
  enum class Kind { Whole, Voxels, Exact };
  Kind kind = Kind::Whole;
  Camera camera;
  RenderSettings settings;
  int width = 0, height = 0;
  GLuint fbo = 0;
  std::vector<std::int64_t> first;  // Kind::Voxels: the frame plan
  std::vector<std::int32_t> count;
  std::size_t next = 0;                   // the first plan voxel not drawn yet
  std::uint64_t segments = 0, drawn = 0;  // the plan's, and those drawn so far
  double drawn_ms = 0;                    // the pieces' time so far: drawn / drawn_ms is the measured rate
  bool done = false;
};

void Renderer::begin_pieces(const Camera& camera, const RenderSettings& s, int width, int height, GLuint fbo) {
  pieces_ = std::make_unique<Pieces>();
  Pieces& p = *pieces_;
  p.camera = camera;
  p.settings = s;
  p.width = width;
  p.height = height;
  p.fbo = fbo;
  switch (s.mode) {
    case RenderMode::Opaque:
    case RenderMode::Basic:
    case RenderMode::Axis: {
      start_frame(camera, s, width, height);
      clear_to_base(fbo, camera, s, width, height);
      if (s.mode == RenderMode::Axis) plan_.order_hysteresis = s.order_hysteresis;
      const PlanOrder order = s.mode == RenderMode::Opaque  ? PlanOrder::Any
                              : s.mode == RenderMode::Basic ? PlanOrder::Block
                                                            : PlanOrder::Nearest;
      plan_and_count(camera, double(width) / std::max(1, height), order, plan_, s.clipping);
      p.kind = Pieces::Kind::Voxels;
      p.first = plan_.first;
      p.count = plan_.count;
      for (std::int32_t ids : p.count) p.segments += static_cast<std::uint64_t>(ids / 2);
      p.done = p.first.empty();
      if (p.done) draw_front_shells(p);
      break;
    }
    case RenderMode::Exact:
      if (!exact_) exact_ = std::make_unique<ExactRenderer>(*this);
      start_frame(camera, s, width, height);
      shells_under_exact(camera, s, width, height, fbo);
      exact_->begin(camera, s, width, height, fbo);
      p.kind = Pieces::Kind::Exact;
      break;
    case RenderMode::Unsorted:
    case RenderMode::Additive:
    case RenderMode::Wboit:
    case RenderMode::Segsort:  // its CPU sort is the frame's cost: drawn whole
      p.kind = Pieces::Kind::Whole;
      break;
  }
}

bool Renderer::draw_piece(double max_ms) {
  if (!pieces_) throw std::logic_error("Renderer::draw_piece without begin_pieces");
  if (pieces_->done) return true;
  switch (pieces_->kind) {
    case Pieces::Kind::Whole: {
      std::unique_ptr<Pieces> p = std::move(pieces_);  // draw() abandons pieces: these are complete after it
      draw(p->camera, p->settings, p->width, p->height, p->fbo);
      pieces_ = std::move(p);
      pieces_->done = true;
      break;
    }
    case Pieces::Kind::Exact:
      pieces_->done = exact_->step(max_ms);
      if (pieces_->done) draw_front_shells(*pieces_);
      glDisable(GL_BLEND);
      enable_clip_distances(0);
      return pieces_->done;
    case Pieces::Kind::Voxels: {
      Pieces& p = *pieces_;
      const auto t0 = std::chrono::steady_clock::now();
      // A window draws other things between pieces: this piece's state is set again.
      glBindFramebuffer(GL_FRAMEBUFFER, p.fbo);
      glViewport(0, 0, p.width, p.height);
      glLineWidth(std::max(1.0f, p.settings.line_width));
      glDepthMask(GL_TRUE);
      if (p.settings.mode == RenderMode::Opaque) {  // as draw()
        opaque_blending();
      } else {
        glDisable(GL_DEPTH_TEST);
        over_blending();
      }
      bind_line_program(over_program_, p.camera, p.settings, double(p.width) / std::max(1, p.height));
      // Voxels up to what the measured rate draws in max_ms (before a measurement, llvmpipe's rate).
      // The rate over all pieces so far, not the last one's: a piece's time varies with its voxels' fragments
      // and a software renderer's flushes, and the last rate alone made sizes swing from 5 to 400 ms.
      const double rate = p.drawn > 0 && p.drawn_ms > 0 ? double(p.drawn) / p.drawn_ms : kAssumedSegmentsPerMs;
      const double max_segments = std::isfinite(max_ms) ? rate * max_ms : std::numeric_limits<double>::infinity();
      std::size_t end = p.next;
      std::uint64_t segments = 0;
      do segments += static_cast<std::uint64_t>(p.count[end++] / 2);
      while (end < p.count.size() && double(segments + p.count[end] / 2) <= max_segments);
      const std::span<const std::int64_t> first(p.first);
      const std::span<const std::int32_t> count(p.count);
      draw_plan(over_program_, first.subspan(p.next, end - p.next), count.subspan(p.next, end - p.next));
      glFinish();  // the piece's time includes the GPU's work, for the next piece's size
      const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      p.drawn_ms += ms;
      p.drawn += segments;
      p.next = end;
      p.done = end == p.count.size();
      if (p.done) draw_front_shells(p);
      glDisable(GL_BLEND);
      glDisable(GL_DEPTH_TEST);
      enable_clip_distances(0);
      break;
    }
  }
  return pieces_->done;
}

void Renderer::draw_front_shells(const Pieces& p) {
  glBindFramebuffer(GL_FRAMEBUFFER, p.fbo);
  glViewport(0, 0, p.width, p.height);
  draw_shells(ShellHalf::Front, p.camera, p.settings, p.width, p.height);
}

void Renderer::draw_shells(ShellHalf half, const Camera& camera, const RenderSettings& s, int width, int height) {
  if (s.regions.empty()) return;
  if (!shells_) shells_ = std::make_unique<RegionShells>();
  enable_clip_distances(0);
  shells_->draw(camera, projection(camera, double(width) / std::max(1, height)), s.regions, half,
                slices_drawn_ ? slices_->depth_texture() : 0);
}

void Renderer::shells_under_exact(const Camera& camera, const RenderSettings& s, int width, int height, GLuint fbo) {
  // exact composites its lists over a picture on the CPU: with shells, that picture is the framebuffer's
  // base with the back halves on it, read back by ExactRenderer::start_image.
  base_in_framebuffer_ = !s.regions.empty();
  if (!base_in_framebuffer_) return;
  clear_to_base(fbo, camera, s, width, height);
}

double Renderer::pieces_progress() const {
  if (!pieces_) return 0;
  if (pieces_->kind == Pieces::Kind::Exact) return exact_->progress();
  if (pieces_->done) return 1;
  return pieces_->segments == 0 ? 0 : double(pieces_->drawn) / double(pieces_->segments);
}

}  // namespace vxl
