#include "viewer/render/renderer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include "format/base/error.h"
#include "viewer/render/clip_uniforms.h"
#include "viewer/render/line_pass.h"
#include "viewer/render/modes/mode_pass.h"
#include "viewer/render/region_shells.h"
#include "viewer/render/slice_renderer.h"
#include "viewer/render/view_queries.h"

namespace vxl {

static_assert(Renderer::kSamplersPerSpan == LinePass::kSamplersPerSpan);
static_assert(Renderer::kMaxBoundSpans == LinePass::kMaxBoundSpans);

// The renderer's services as its modes' passes use them (modes/pass_host.h).
class Renderer::Host final : public PassHost {
 public:
  explicit Host(Renderer& renderer) : r_(renderer) {}
  LinePass& lines() override { return *r_.lines_; }
  GpuScene& scene() override { return r_.scene_; }
  const std::vector<const VxlFile*>& scene_files() const override { return r_.files_; }
  FramePlan& frame_plan() override { return r_.plan_; }
  FrameStats& frame_stats() override { return r_.stats_; }
  void plan_and_count(const FrameView& f, PlanOrder order, FramePlan& out) override {
    r_.plan_and_count(f.camera, f.aspect(), order, out, f.settings.clipping);
  }
  void keep_resident(FramePlan& plan) override { r_.keep_resident(plan); }
  void bind_lines(GLuint program, const FrameView& f, const RenderSettings& settings) override {
    r_.bind_line_program(program, f.camera, settings, f.aspect());
  }
  void clear_to_base(const FrameView& f) override { r_.clear_to_base(f.fbo, f.camera, f.settings, f.width, f.height); }
  void base_for_exact(const FrameView& f) override {
    r_.shells_under_exact(f.camera, f.settings, f.width, f.height, f.fbo);
  }
  bool base_in_framebuffer() const override { return r_.base_in_framebuffer_; }
  GLuint slice_color_texture() const override { return r_.slice_color_texture(); }

 private:
  Renderer& r_;
};

Renderer::Renderer(const VxlFile& file, std::uint64_t max_texels, std::uint32_t level)
    : Renderer(std::vector<const VxlFile*>{&file}, max_texels, level) {}

Renderer::Renderer(std::vector<const VxlFile*> files, std::uint64_t max_texels, std::uint32_t level,
                   std::shared_ptr<GpuMemoryPool> pool, bool eager, const std::vector<std::uint32_t>& file_levels)
    : files_(files.empty() ? throw Error(ErrorKind::Usage, "", std::nullopt, "Renderer: no files") : files),
      line_bounds_(line_bounds(files_)),
      scene_bounds_(line_bounds_),
      scene_(files_, max_texels, level, std::move(pool), eager, file_levels),
      groups_(files_),
      indexes_(std::make_shared<VoxelVoxlinesCache>(files_)) {
  for (const VxlFile* f : files_)
    for (const ValueSets* sets : {&f->vertex_values(), &f->streamline_values()})
      for (std::uint32_t k = 0; k < sets->size(); ++k)
        if (std::find(value_set_names_.begin(), value_set_names_.end(), sets->name(k)) == value_set_names_.end())
          value_set_names_.push_back(sets->name(k));
  lines_ = std::make_unique<LinePass>(scene_, files_);
  host_ = std::make_unique<Host>(*this);
  passes_.resize(render_modes().size());
}

Renderer::~Renderer() {
  pieces_.reset();
  passes_.clear();  // they draw with the line pass and the slices
  slices_.reset();
}

PassHost& Renderer::pass_host() { return *host_; }

ModePass& Renderer::pass(RenderMode mode) {
  std::unique_ptr<ModePass>& p = passes_.at(static_cast<std::size_t>(mode));
  if (!p) p = make_mode_pass(mode);
  return *p;
}

void Renderer::set_volume(const Volume& volume) {
  slices_ = std::make_unique<SliceRenderer>(volume);
  scene_bounds_ = scene_bounds(files_, &volume);
  // The line programs now test against the slices' depth; the modes' own programs (exact's list program)
  // are made again on first use.
  lines_->make_programs(true);
  for (std::unique_ptr<ModePass>& p : passes_) p.reset();
  pieces_.reset();
}

std::array<float, 2> Renderer::slice_range(const RenderSettings& s) const {
  return slices_ ? slices_->range(s.slices) : std::array<float, 2>{0, 1};
}

GLuint Renderer::slice_color_texture() const { return slices_drawn_ ? slices_->color_texture() : 0; }

glm::dmat4 Renderer::projection(const Camera& camera, double aspect) const {
  // Near and far planes hug the lines and the image.
  return fitted_projection(camera, aspect, scene_bounds_, scene_.layout().voxel_size());
}

void Renderer::plan(const Camera& camera, double aspect, PlanOrder order, FramePlan& out,
                    const Clipping& clipping) const {
  plan_view(scene_.layout(), camera, projection(camera, aspect), order, out, clipping);
}

std::uint64_t Renderer::view_bytes(const Camera& camera, double aspect, const Clipping& clipping) const {
  return vxl::view_bytes(scene_.layout(), camera, aspect, scene_bounds_, clipping);
}

void Renderer::plan_and_count(const Camera& camera, double aspect, PlanOrder order, FramePlan& out,
                              const Clipping& clipping) {
  auto t0 = std::chrono::steady_clock::now();
  plan(camera, aspect, order, out, clipping);
  keep_resident(out);
  lines_->plan_draws(out.first, out.count);
  stats_.plan_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  stats_.voxels_drawn = out.voxels_drawn;
  stats_.segments_drawn = out.segments_drawn;
}

std::vector<std::uint32_t> Renderer::spans_for(const Camera& camera, double aspect, const Clipping& clipping) const {
  FramePlan nearest;
  plan(camera, aspect, PlanOrder::Nearest, nearest, clipping);
  return spans_nearest_first(scene_.layout(), nearest);
}

bool Renderer::upload_spans(std::span<const std::uint32_t> spans, double max_ms) {
  return !scene_.make_resident(spans, max_ms, false).out_of_time;
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
  const glm::dmat4 proj = projection(camera, aspect);
  lines_->bind(program,
               LineUniforms{camera, proj, s, scalar_range(s), groups_, slices_drawn_ ? slices_->depth_texture() : 0});
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
  lines_->groups_changed();  // the next frame uploads the table; the per-vertex words stay
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

void Renderer::prepare_attributes(const RenderSettings& s) {
  lines_->prepare_attributes(s, scalar_name(s), groups_, *indexes_);
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
  scene_.check_uploaded(false);
  pieces_.reset();
  ModePass& mode = pass(s.mode);
  start_frame(camera, s, width, height);
  mode.draw(*host_, FrameView{camera, s, width, height, fbo});
  draw_shells(ShellHalf::Front, camera, s, width, height);
  glDisable(GL_BLEND);
  enable_clip_distances(0);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  scene_.start_checks();  // of what this frame uploaded; their failure stops the next frame
}

struct Renderer::Pieces {
  PieceKind kind = PieceKind::Whole;
  ModePass* pass = nullptr;  // the mode's, which draws PieceKind::Own pieces and sets a voxel piece's state
  Camera camera;
  RenderSettings settings;
  int width = 0, height = 0;
  GLuint fbo = 0;
  std::vector<std::int64_t> first;  // PieceKind::Voxels: the frame plan
  std::vector<std::int32_t> count;
  std::size_t next = 0;                   // the first plan voxel not drawn yet
  std::int32_t next_drawn = 0;            // of its ids, those drawn already (a voxel larger than a piece)
  std::uint64_t segments = 0, drawn = 0;  // the plan's, and those drawn so far
  double drawn_ms = 0;                    // the pieces' time so far: drawn / drawn_ms is the measured rate
  bool done = false;
  Renderer* stand_in = nullptr;             // begin_pieces' stand-in, for the voxels not resident here
  std::vector<std::uint8_t> from_stand_in;  // with one: per plan entry, whether it is the stand-in's
};

bool Renderer::draws_in_voxel_pieces(RenderMode mode) { return pass(mode).piece_kind() == PieceKind::Voxels; }

void Renderer::plan_with_stand_in(const Camera& camera, double aspect, PlanOrder order, const Clipping& clipping,
                                  Renderer& stand_in, Pieces& p) {
  const auto t0 = std::chrono::steady_clock::now();
  const SceneLayout& layout = scene_.layout();
  if (stand_in.layout().voxels().size() != layout.voxels().size())
    throw std::logic_error("Renderer: a stand-in of other voxels");
  plan(camera, aspect, order, plan_, clipping);
  FramePlan theirs;
  stand_in.plan(camera, aspect, order, theirs, clipping);
  std::vector<std::int32_t> entry_of(layout.voxels().size(), -1);  // a voxel's entry in the stand-in's plan
  for (std::size_t i = 0; i < theirs.voxels.size(); ++i) entry_of[theirs.voxels[i]] = static_cast<std::int32_t>(i);
  std::vector<std::int64_t> own_first, their_first;
  std::vector<std::int32_t> own_count, their_count;
  for (std::size_t i = 0; i < plan_.first.size(); ++i) {
    const std::uint32_t voxel = plan_.voxels[i];
    const bool own = scene_.resident(layout.voxels()[voxel].span);
    if (!own && entry_of[voxel] < 0) continue;  // nothing of it at the stand-in's level
    const std::int64_t first = own ? plan_.first[i] : theirs.first[entry_of[voxel]];
    const std::int32_t count = own ? plan_.count[i] : theirs.count[entry_of[voxel]];
    (own ? own_first : their_first).push_back(first);
    (own ? own_count : their_count).push_back(count);
    p.first.push_back(first);
    p.count.push_back(count);
    p.from_stand_in.push_back(own ? 0 : 1);
    p.segments += static_cast<std::uint64_t>(count / 2);
  }
  lines_->plan_draws(own_first, own_count);
  stand_in.lines_->plan_draws(their_first, their_count);
  stats_.plan_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  stats_.voxels_drawn = own_first.size();
  stats_.voxels_waiting = plan_.first.size() - own_first.size();
  stats_.segments_drawn = 0;
  for (const std::int32_t c : own_count) stats_.segments_drawn += static_cast<std::uint64_t>(c / 2);
}

void Renderer::begin_pieces(const Camera& camera, const RenderSettings& s, int width, int height, GLuint fbo,
                            Renderer* stand_in) {
  pieces_ = std::make_unique<Pieces>();
  Pieces& p = *pieces_;
  p.camera = camera;
  p.settings = s;
  p.width = width;
  p.height = height;
  p.fbo = fbo;
  p.pass = &pass(s.mode);
  p.kind = p.pass->piece_kind();
  if (p.kind == PieceKind::Voxels) {
    if (stand_in) stand_in->start_frame(camera, s, width, height);  // its attributes for these settings
    start_frame(camera, s, width, height);
    clear_to_base(fbo, camera, s, width, height);
    const PlanOrder order = p.pass->plan_order(s, plan_);
    const double aspect = double(width) / std::max(1, height);
    if (stand_in) {
      p.stand_in = stand_in;
      plan_with_stand_in(camera, aspect, order, s.clipping, *stand_in, p);
    } else {
      plan_and_count(camera, aspect, order, plan_, s.clipping);
      p.first = plan_.first;
      p.count = plan_.count;
      for (std::int32_t ids : p.count) p.segments += static_cast<std::uint64_t>(ids / 2);
    }
    p.done = p.first.empty();
    if (p.done) draw_front_shells(p);
  } else if (p.kind == PieceKind::Own) {
    start_frame(camera, s, width, height);
    p.pass->begin(*host_, FrameView{camera, s, width, height, fbo});
  }
}

bool Renderer::draw_piece(double max_ms) {
  if (!pieces_) throw std::logic_error("Renderer::draw_piece without begin_pieces");
  scene_.check_uploaded(false);
  if (pieces_->done) return true;
  switch (pieces_->kind) {
    case PieceKind::Whole: {
      std::unique_ptr<Pieces> p = std::move(pieces_);  // draw() abandons pieces: these are complete after it
      draw(p->camera, p->settings, p->width, p->height, p->fbo);
      pieces_ = std::move(p);
      pieces_->done = true;
      break;
    }
    case PieceKind::Own:
      pieces_->done = pieces_->pass->step(max_ms);
      if (pieces_->done) draw_front_shells(*pieces_);
      glDisable(GL_BLEND);
      enable_clip_distances(0);
      break;
    case PieceKind::Voxels: draw_voxel_piece(max_ms); break;
  }
  return pieces_->done;
}

void Renderer::draw_voxel_piece(double max_ms) {
  Pieces& p = *pieces_;
  const auto t0 = std::chrono::steady_clock::now();
  // A window draws other things between pieces: this piece's state is set again.
  glBindFramebuffer(GL_FRAMEBUFFER, p.fbo);
  glViewport(0, 0, p.width, p.height);
  glLineWidth(std::max(1.0f, p.settings.line_width));
  glDepthMask(GL_TRUE);
  p.pass->piece_state();  // as the mode's draw()
  // Segments up to what the measured rate draws in max_ms (before a measurement, llvmpipe's rate), at least one.
  // The rate over all pieces so far, not the last one's: a piece's time varies with its voxels' fragments
  // and a software renderer's flushes, and the last rate alone made sizes swing from 5 to 400 ms.
  const double rate = p.drawn > 0 && p.drawn_ms > 0 ? double(p.drawn) / p.drawn_ms : kAssumedSegmentsPerMs;
  const double max_segments = std::isfinite(max_ms) ? rate * max_ms : std::numeric_limits<double>::infinity();
  // Whole voxels while they fit, then a part of the next: a voxel's segments are consecutive ids drawn in order,
  // so its parts in order blend as it does whole, and no piece outgrows max_ms however many segments a voxel
  // holds (one of the 1M set took a software WebGL 1.3 s).
  std::vector<std::int64_t> first;
  std::vector<std::int32_t> count;
  std::vector<std::uint8_t> from_stand_in;
  std::uint64_t segments = 0;
  while (p.next < p.count.size()) {
    const std::int32_t left = p.count[p.next] - p.next_drawn;
    if (left <= 0) {  // an empty run
      ++p.next;
      p.next_drawn = 0;
      continue;
    }
    const double room = std::max(segments == 0 ? 1.0 : 0.0, std::floor(max_segments - double(segments)));
    const std::int32_t ids = double(left / 2) <= room ? left : 2 * static_cast<std::int32_t>(room);
    if (ids == 0) break;
    first.push_back(p.first[p.next] + p.next_drawn);
    count.push_back(ids);
    if (p.stand_in) from_stand_in.push_back(p.from_stand_in[p.next]);
    segments += static_cast<std::uint64_t>(ids / 2);
    p.next_drawn += ids;
    if (p.next_drawn < p.count[p.next]) break;
    ++p.next;
    p.next_drawn = 0;
  }
  if (!p.stand_in) {
    draw_over_ranges(*this, p, first, count);
  } else {  // runs of one renderer's entries, each with its own program, uniforms and spans
    for (std::size_t run = 0, end = 0; run < first.size(); run = end) {
      for (end = run + 1; end < first.size() && from_stand_in[end] == from_stand_in[run];) ++end;
      draw_over_ranges(from_stand_in[run] ? *p.stand_in : *this, p, std::span(first).subspan(run, end - run),
                       std::span(count).subspan(run, end - run));
    }
  }
  gl::finish_gpu_work();  // the piece's time includes the GPU's work, for the next piece's size
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  p.drawn_ms += ms;
  p.drawn += segments;
  p.done = p.next == p.count.size();
  if (p.done) draw_front_shells(p);
  glDisable(GL_BLEND);
  glDisable(GL_DEPTH_TEST);
  enable_clip_distances(0);
}

void Renderer::draw_over_ranges(Renderer& renderer, const Pieces& p, std::span<const std::int64_t> first,
                                std::span<const std::int32_t> count) {
  const GLuint program = renderer.lines_->over();
  renderer.bind_line_program(program, p.camera, p.settings, double(p.width) / std::max(1, p.height));
  renderer.lines_->draw_plan(program, first, count);
}

void Renderer::draw_front_shells(const Pieces& p) {
  glBindFramebuffer(GL_FRAMEBUFFER, p.fbo);
  glViewport(0, 0, p.width, p.height);
  draw_shells(ShellHalf::Front, p.camera, p.settings, p.width, p.height);
}

void Renderer::draw_shells(ShellHalf half, const Camera& camera, const RenderSettings& s, int width, int height) {
  if (s.regions.empty()) return;
  if (!shells_) shells_ = std::make_unique<RegionShells>();
  shells_->draw(camera, projection(camera, double(width) / std::max(1, height)), s.regions, half,
                slices_drawn_ ? slices_->depth_texture() : 0, clip_half_spaces(s.clipping, camera));
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
  if (pieces_->kind == PieceKind::Own) return pieces_->pass->progress();
  if (pieces_->done) return 1;
  return pieces_->segments == 0 ? 0 : double(pieces_->drawn) / double(pieces_->segments);
}

}  // namespace vxl
