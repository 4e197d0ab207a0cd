#include "viewer/render/exact_renderer.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <vector>

#include <glm/gtc/type_ptr.hpp>

#include "viewer/render/line_shaders.h"
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

// IEEE binary16 -> binary32 (the colours are stored with GLSL's packHalf2x16).
float half_to_float(std::uint16_t h) {
  const std::uint32_t sign = std::uint32_t(h & 0x8000u) << 16, exponent = (h >> 10) & 0x1Fu, mantissa = h & 0x3FFu;
  if (exponent == 0) {  // zero or subnormal: mantissa * 2^-24
    const float f = std::ldexp(static_cast<float>(mantissa), -24);
    return sign ? -f : f;
  }
  const std::uint32_t bits = sign | (exponent == 0x1F ? 0x7F800000u : (exponent + 112) << 23) | mantissa << 13;
  float f;
  std::memcpy(&f, &bits, 4);
  return f;
}

}  // namespace

ExactRenderer::ExactRenderer(Renderer& lines, std::uint64_t node_capacity) : lines_(lines) {
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
  const unsigned chunks = std::max<unsigned>(1, static_cast<unsigned>(lines.scene().layout().chunks().size()));
  list_program_ = gl::make_program(shaders::line_vertex(chunks, "#version 430 core"),
                                   shaders::line_fragment(kListFragment, "#version 430 core"));
  clear_program_ = gl::make_compute_program(kClearCompute);
  blit_program_ = gl::make_program(shaders::kFullscreenVertex, kBlitFragment);
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
  if (width != width_ || height != height_) {
    if (heads_) glDeleteTextures(1, &heads_);
    if (result_) glDeleteTextures(1, &result_);
    glGenTextures(1, &heads_);
    glBindTexture(GL_TEXTURE_2D, heads_);
    glTexStorage2D(GL_TEXTURE_2D, 1, GL_R32UI, width, height);
    glGenTextures(1, &result_);
    glBindTexture(GL_TEXTURE_2D, result_);
    glTexStorage2D(GL_TEXTURE_2D, 1, GL_RGBA32F, width, height);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    width_ = width;
    height_ = height;
  }
  const double aspect = double(width) / std::max(1, height);
  FramePlan plan;
  lines_.plan(camera, aspect, PlanOrder::Any, plan, s.clipping);
  const glm::vec3 bg = s.background();
  // The lines are composited over the opaque slices where there are some (their colour is the
  // background there); the list pass has already dropped the fragments behind them.
  base_.clear();
  if (const GLuint slices = lines_.slice_color_texture()) {
    base_.resize(std::size_t(width) * height * 4);
    glBindTexture(GL_TEXTURE_2D, slices);
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glGetTexImage(GL_TEXTURE_2D, 0, GL_RGBA, GL_FLOAT, base_.data());
  }

  // Bands of rows; a band whose fragments overflow the node buffer is split in two and redone.
  std::vector<std::array<int, 2>> bands = {{0, height}};
  bands_used_ = 0;
  fragments_ = 0;
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  glViewport(0, 0, width, height);
  glDisable(GL_BLEND);
  glDisable(GL_DEPTH_TEST);
  while (!bands.empty()) {
    auto [y0, y1] = bands.back();
    bands.pop_back();
    glUseProgram(clear_program_);
    glBindImageTexture(0, heads_, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32UI);
    glDispatchCompute((width + 7) / 8, (height + 7) / 8, 1);
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
    const GLuint zero = 0;
    glBindBuffer(GL_ATOMIC_COUNTER_BUFFER, counter_);
    glBufferSubData(GL_ATOMIC_COUNTER_BUFFER, 0, 4, &zero);

    lines_.bind_line_program(list_program_, camera, s, aspect);
    glUniform1ui(glGetUniformLocation(list_program_, "u_capacity"),
                 static_cast<GLuint>(std::min<std::uint64_t>(capacity_, 0xFFFFFFFFu)));
    glUniform4i(glGetUniformLocation(list_program_, "u_band"), 0, y0, width, y1);
    glBindImageTexture(0, heads_, 0, GL_FALSE, 0, GL_READ_WRITE, GL_R32UI);
    glBindBufferBase(GL_ATOMIC_COUNTER_BUFFER, 0, counter_);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, nodes_);
    lines_.draw_plan(plan.first, plan.count);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_ATOMIC_COUNTER_BARRIER_BIT);

    GLuint stored = 0;
    glBindBuffer(GL_ATOMIC_COUNTER_BUFFER, counter_);
    glGetBufferSubData(GL_ATOMIC_COUNTER_BUFFER, 0, 4, &stored);
    if (stored > capacity_) {
      if (y1 - y0 <= 1)
        throw std::runtime_error("exact mode: one pixel row has more fragments than the node buffer holds");
      int mid = (y0 + y1) / 2;
      bands.push_back({mid, y1});
      bands.push_back({y0, mid});
      continue;
    }
    ++bands_used_;
    fragments_ += stored;
    resolve_band(y0, y1, stored, bg);
  }
  Renderer::enable_clip_distances(0);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  glViewport(0, 0, width, height);
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

void ExactRenderer::resolve_band(int y0, int y1, std::uint32_t stored, const glm::vec3& background) {
  // The shaders' writes must be visible to the read-backs.
  glMemoryBarrier(GL_TEXTURE_UPDATE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
  heads_copy_.resize(std::size_t(width_) * height_);
  glBindTexture(GL_TEXTURE_2D, heads_);
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  glGetTexImage(GL_TEXTURE_2D, 0, GL_RED_INTEGER, GL_UNSIGNED_INT, heads_copy_.data());
  nodes_copy_.resize(stored);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, nodes_);
  glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(stored) * 16, nodes_copy_.data());

  rows_.resize(std::size_t(width_) * (y1 - y0) * 4);
  std::vector<std::pair<float, std::uint32_t>> list;  // (depth, node)
  for (int y = y0; y < y1; ++y)
    for (int x = 0; x < width_; ++x) {
      list.clear();
      for (std::uint32_t i = heads_copy_[std::size_t(y) * width_ + x]; i != 0xFFFFFFFFu; i = nodes_copy_[i][3]) {
        if (i >= stored || list.size() >= stored) throw std::runtime_error("exact mode: corrupt fragment list");
        float depth;
        std::memcpy(&depth, &nodes_copy_[i][2], 4);
        list.push_back({depth, i});
      }
      // Farthest first; equal depths in a fixed (node) order, so no fragment is lost or doubled.
      std::sort(list.begin(), list.end(), [](const auto& a, const auto& b) { return a > b; });
      glm::vec3 color = background;
      if (!base_.empty()) color = glm::make_vec3(base_.data() + (std::size_t(y) * width_ + x) * 4);
      for (const auto& [depth, i] : list) {
        const std::array<std::uint32_t, 4>& n = nodes_copy_[i];
        const glm::vec3 c(half_to_float(n[0] & 0xFFFF), half_to_float(n[0] >> 16), half_to_float(n[1] & 0xFFFF));
        const float a = half_to_float(n[1] >> 16);
        color = c * a + color * (1.0f - a);
      }
      float* out = rows_.data() + (std::size_t(y - y0) * width_ + x) * 4;
      out[0] = color.r, out[1] = color.g, out[2] = color.b, out[3] = 1.0f;
    }
  glBindTexture(GL_TEXTURE_2D, result_);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  glTexSubImage2D(GL_TEXTURE_2D, 0, 0, y0, width_, y1 - y0, GL_RGBA, GL_FLOAT, rows_.data());
}

}  // namespace vxl
