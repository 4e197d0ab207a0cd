#include "viewer/render/exact_renderer.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <span>
#include <stdexcept>
#include <vector>

#include <glm/gtc/type_ptr.hpp>

#include "viewer/render/clip_uniforms.h"
#include "viewer/render/line_shaders.h"
#include "viewer/render/modes/pass_host.h"
#include "viewer/render/renderer.h"

namespace vxl {
namespace {

const char* const kListFragment = R"(
layout(binding = 0, r32ui) uniform coherent uimage2D u_heads;
layout(binding = 0, offset = 0) uniform atomic_uint u_counter;
layout(std430, binding = 1) buffer Nodes { uvec4 nodes[]; };
uniform uint u_capacity;
uniform ivec4 u_band;  // x0, y0, x1, y1: only fragments inside are stored this pass
void main() {
  discard_behind_slices();
  ivec2 p = ivec2(gl_FragCoord.xy);
  if (p.x < u_band.x || p.y < u_band.y || p.x >= u_band.z || p.y >= u_band.w) discard;
  uint i = atomicCounterIncrement(u_counter);
  if (i < u_capacity) {
    uint previous = imageAtomicExchange(u_heads, p, i);
    vec4 c = line_color();
    nodes[i] = uvec4(packHalf2x16(c.rg), packHalf2x16(c.ba), floatBitsToUint(gl_FragCoord.z), previous);
  }
  discard;  // nothing is written to the colour buffer in this pass
}
)";

const char* const kClearCompute = R"(#version 430 core
layout(local_size_x = 8, local_size_y = 8) in;
layout(binding = 0, r32ui) uniform writeonly uimage2D u_heads;
void main() { imageStore(u_heads, ivec2(gl_GlobalInvocationID.xy), uvec4(0xFFFFFFFFu)); }
)";

const char* const kBlitFragment = R"(#version 330 core
in vec2 v_uv;
uniform sampler2D u_result;
out vec4 frag;
void main() { frag = vec4(texture(u_result, v_uv).rgb, 1.0); }
)";

}  // namespace

ExactRenderer::ExactRenderer(Renderer& lines, std::uint64_t node_capacity, ExactResolve resolve)
    : ExactRenderer(lines.pass_host(), node_capacity, resolve) {}

ExactRenderer::ExactRenderer(PassHost& host, std::uint64_t node_capacity, ExactResolve resolve) : host_(host) {
  GLint major = 0, minor = 0;
  glGetIntegerv(GL_MAJOR_VERSION, &major);
  glGetIntegerv(GL_MINOR_VERSION, &minor);
  if (major * 10 + minor < 43)
    throw std::runtime_error("the exact mode needs OpenGL 4.3 (compute shaders, storage buffers); this context is " +
                             std::to_string(major) + "." + std::to_string(minor));
  GLint max_block = 0;
  glGetIntegerv(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &max_block);
  std::uint64_t bytes = std::min<std::uint64_t>(static_cast<std::uint32_t>(max_block), 256ull << 20);
  capacity_ = node_capacity ? node_capacity : bytes / 16;
  list_program_ = host_.lines().make_program(kListFragment, "#version 430 core");
  clear_program_ = gl::make_compute_program(kClearCompute);
  blit_program_ = gl::make_program(shaders::kFullscreenVertex, kBlitFragment);
  if (resolve == ExactResolve::Gpu || (resolve == ExactResolve::Auto && !software_rasterizer())) {
    try {
      gpu_ = std::make_unique<GpuListResolve>();
      if (!gpu_->agrees_with_cpu()) gpu_.reset();  // this driver composites otherwise: the CPU does it
    } catch (const std::exception&) {
      gpu_.reset();  // a driver that cannot build the compute pass: the CPU composites
    }
  }
  glGenBuffers(1, &nodes_);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, nodes_);
  glBufferData(GL_SHADER_STORAGE_BUFFER, static_cast<GLsizeiptr>(capacity_ * 16), nullptr, GL_DYNAMIC_COPY);
  glGenBuffers(1, &counter_);
  glBindBuffer(GL_ATOMIC_COUNTER_BUFFER, counter_);
  glBufferData(GL_ATOMIC_COUNTER_BUFFER, 4, nullptr, GL_DYNAMIC_COPY);
}

ExactRenderer::~ExactRenderer() {
  for (GLuint p : {list_program_, clear_program_, blit_program_})
    if (p) glDeleteProgram(p);
  if (nodes_) glDeleteBuffers(1, &nodes_);
  if (counter_) glDeleteBuffers(1, &counter_);
  if (heads_) glDeleteTextures(1, &heads_);
  if (result_) glDeleteTextures(1, &result_);
}

void ExactRenderer::draw(const Camera& camera, const RenderSettings& s, int width, int height, GLuint fbo) {
  begin(camera, s, width, height, fbo);
  step(std::numeric_limits<double>::infinity());
}

void ExactRenderer::begin(const Camera& camera, const RenderSettings& s, int width, int height, GLuint fbo) {
  if (width != width_ || height != height_) {
    if (heads_) glDeleteTextures(1, &heads_);
    if (result_) glDeleteTextures(1, &result_);
    glGenTextures(1, &heads_);
    glBindTexture(GL_TEXTURE_2D, heads_);
    glTexStorage2D(GL_TEXTURE_2D, 1, GL_R32UI, width, height);
    // An integer texture is complete only with NEAREST filters; some drivers check it for image units too.
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glGenTextures(1, &result_);
    glBindTexture(GL_TEXTURE_2D, result_);
    glTexStorage2D(GL_TEXTURE_2D, 1, GL_RGBA32F, width, height);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    width_ = width;
    height_ = height;
  }
  camera_ = camera;
  settings_ = s;
  fbo_ = fbo;
  host_.plan_and_count(FrameView{camera, s, width, height, fbo}, render_mode_info(RenderMode::Exact).plan_order, plan_);
  segments_before_.assign(plan_.count.size() + 1, 0);
  for (std::size_t v = 0; v < plan_.count.size(); ++v)
    segments_before_[v + 1] = segments_before_[v] + plan_.count[v] / 2;
  start_image(s.background());
  if (gpu_) {  // the picture so far lives on the GPU from here
    glBindTexture(GL_TEXTURE_2D, result_);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, width_, height_, GL_RGBA, GL_FLOAT, image_.data());
  }
  next_ = 0;
  per_segment_ = 0;
  composited_ms_ = 0;
  passes_ = 0;
  fragments_ = 0;
}

double ExactRenderer::progress() const {
  const std::uint64_t total = segments_before_.empty() ? 0 : segments_before_.back();
  return total == 0 ? (next_ >= plan_.count.size() ? 1.0 : 0.0) : double(segments_before_[next_]) / double(total);
}

std::size_t ExactRenderer::run_end(double max_segments) const {
  const std::size_t n = plan_.count.size();
  // Several grids: the voxels are not in a visibility order, so they are composited in one run.
  if (!host_.scene().layout().one_grid()) return n;
  double budget = max_segments;
  if (per_segment_ > 0) budget = std::min(budget, 0.5 * double(capacity_) / per_segment_);
  if (!std::isfinite(budget)) return n;  // the first run of an unbounded frame measures the fragments
  std::size_t j = next_ + 1;
  while (j < n && double(segments_before_[j + 1] - segments_before_[next_]) <= budget) ++j;
  return j;
}

bool ExactRenderer::step(double max_ms) {
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  auto elapsed_ms = [&] { return std::chrono::duration<double, std::milli>(Clock::now() - start).count(); };
  // A window draws other things between steps: the state this pass needs is set again each time.
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
  glViewport(0, 0, width_, height_);
  glDisable(GL_BLEND);
  glDisable(GL_DEPTH_TEST);
  host_.bind_lines(list_program_, FrameView{camera_, settings_, width_, height_, fbo_}, settings_);
  glUniform1ui(glGetUniformLocation(list_program_, "u_capacity"),
               static_cast<GLuint>(std::min<std::uint64_t>(capacity_, 0xFFFFFFFFu)));

  // Depth passes: runs of voxels in visibility order, back to front. A run's fragments all lie behind the
  // next run's along every ray, so compositing run after run is exact. A run that overflows is
  // shortened and redone; one that cannot be (a single voxel, or several grids whose voxels overlap)
  // is split into bands of rows instead.
  const bool depth_passes = host_.scene().layout().one_grid();
  const std::size_t n = plan_.count.size();
  while (next_ < n) {
    // Before anything is measured, a time-limited run assumes the line passes' rate (Renderer).
    // Fragments per millisecond over every run so far, and the most fragments per segment seen: nearer
    // voxels cover more pixels a segment, so a rate in segments alone let late runs overrun the time.
    const double rate = composited_ms_ > 0 && fragments_ > 0 && per_segment_ > 0
                            ? double(fragments_) / composited_ms_ / per_segment_
                            : Renderer::kAssumedSegmentsPerMs;
    const double max_segments =
        std::isfinite(max_ms) ? rate * std::max(max_ms - elapsed_ms(), 0.0) : std::numeric_limits<double>::infinity();
    const std::size_t j = run_end(max_segments);
    const auto run_start = Clock::now();
    auto run_ms = [&] { return std::chrono::duration<double, std::milli>(Clock::now() - run_start).count(); };
    const std::uint64_t stored = list_pass(next_, j, 0, height_);
    const std::uint64_t segments = segments_before_[j] - segments_before_[next_];
    if (segments > 0) per_segment_ = std::max(per_segment_, double(stored) / double(segments));
    if (stored <= capacity_) {
      resolve_band(0, height_, static_cast<std::uint32_t>(stored));
    } else if (depth_passes && j - next_ > 1) {
      composited_ms_ += run_ms();  // spent, though nothing was composited: the rate counts it
      continue;                    // retry a shorter run with the new estimate
    } else {
      rows_in_bands(next_, j, height_);
    }
    composited_ms_ += run_ms();
    next_ = j;
    if (std::isfinite(max_ms) && elapsed_ms() >= max_ms) break;
  }
  if (next_ < n) return false;
  show_image();
  return true;
}

void ExactRenderer::show_image() {
  if (!gpu_) {
    glBindTexture(GL_TEXTURE_2D, result_);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, width_, height_, GL_RGBA, GL_FLOAT, image_.data());
  }
  enable_clip_distances(0);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
  glViewport(0, 0, width_, height_);
  glUseProgram(blit_program_);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, result_);
  glUniform1i(glGetUniformLocation(blit_program_, "u_result"), 0);
  GLuint vao = 0;
  glGenVertexArrays(1, &vao);
  glBindVertexArray(vao);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glDeleteVertexArrays(1, &vao);
}

void ExactRenderer::start_image(const glm::vec3& background) {
  // The lines are composited over the opaque slices where there are some (their colour is the background
  // there); the list pass drops the fragments behind them.
  image_.resize(std::size_t(width_) * height_ * 4);
  if (host_.base_in_framebuffer()) {  // the region shells' back halves are drawn on it (renderer.h)
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glReadPixels(0, 0, width_, height_, GL_RGBA, GL_FLOAT, image_.data());
  } else if (const GLuint slices = host_.slice_color_texture()) {
    glBindTexture(GL_TEXTURE_2D, slices);
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glGetTexImage(GL_TEXTURE_2D, 0, GL_RGBA, GL_FLOAT, image_.data());
  } else {
    for (std::size_t p = 0; p < image_.size(); p += 4) {
      image_[p] = background.r, image_[p + 1] = background.g, image_[p + 2] = background.b, image_[p + 3] = 1.0f;
    }
  }
}

std::uint64_t ExactRenderer::list_pass(std::size_t first_voxel, std::size_t end_voxel, int y0, int y1) {
  glUseProgram(clear_program_);
  glBindImageTexture(0, heads_, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32UI);
  glDispatchCompute((width_ + 7) / 8, (height_ + 7) / 8, 1);
  glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
  const GLuint zero = 0;
  glBindBuffer(GL_ATOMIC_COUNTER_BUFFER, counter_);
  glBufferSubData(GL_ATOMIC_COUNTER_BUFFER, 0, 4, &zero);

  glUseProgram(list_program_);
  glUniform4i(glGetUniformLocation(list_program_, "u_band"), 0, y0, width_, y1);
  glBindImageTexture(0, heads_, 0, GL_FALSE, 0, GL_READ_WRITE, GL_R32UI);
  glBindBufferBase(GL_ATOMIC_COUNTER_BUFFER, 0, counter_);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, nodes_);
  const std::span<const std::int64_t> first(plan_.first);
  const std::span<const std::int32_t> count(plan_.count);
  host_.lines().draw_plan(list_program_, first.subspan(first_voxel, end_voxel - first_voxel),
                          count.subspan(first_voxel, end_voxel - first_voxel));
  // The counter is read back below (a buffer update), the lists by the resolve's shader or read-backs.
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_ATOMIC_COUNTER_BARRIER_BIT |
                  GL_BUFFER_UPDATE_BARRIER_BIT);

  // The counter counts every fragment, also those past the capacity that were not stored.
  GLuint stored = 0;
  glBindBuffer(GL_ATOMIC_COUNTER_BUFFER, counter_);
  glGetBufferSubData(GL_ATOMIC_COUNTER_BUFFER, 0, 4, &stored);
  return stored;
}

void ExactRenderer::rows_in_bands(std::size_t first_voxel, std::size_t end_voxel, int height) {
  // Bands of rows; a band whose fragments overflow the node buffer is split in two and redone.
  std::vector<std::array<int, 2>> bands = {{height / 2, height}, {0, height / 2}};
  while (!bands.empty()) {
    auto [y0, y1] = bands.back();
    bands.pop_back();
    if (y1 <= y0) continue;
    const std::uint64_t stored = list_pass(first_voxel, end_voxel, y0, y1);
    if (stored > capacity_) {
      if (y1 - y0 <= 1)
        throw std::runtime_error("exact mode: one pixel row has more fragments than the node buffer holds");
      int mid = (y0 + y1) / 2;
      bands.push_back({mid, y1});
      bands.push_back({y0, mid});
      continue;
    }
    resolve_band(y0, y1, static_cast<std::uint32_t>(stored));
  }
}

void ExactRenderer::resolve_band(int y0, int y1, std::uint32_t stored) {
  ++passes_;
  fragments_ += stored;
  if (stored == 0) return;
  if (gpu_) {
    gpu_->resolve(heads_, nodes_, stored, result_, width_, y0, y1);
    return;
  }
  // The shaders' writes must be visible to the read-backs.
  glMemoryBarrier(GL_TEXTURE_UPDATE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
  heads_copy_.resize(std::size_t(width_) * height_);
  glBindTexture(GL_TEXTURE_2D, heads_);
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  glGetTexImage(GL_TEXTURE_2D, 0, GL_RED_INTEGER, GL_UNSIGNED_INT, heads_copy_.data());
  nodes_copy_.resize(stored);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, nodes_);
  glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(stored) * 16, nodes_copy_.data());
  composite_lists_on_cpu(heads_copy_, nodes_copy_, width_, y0, y1, image_);
}

}  // namespace vxl
