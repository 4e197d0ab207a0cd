#include "exact_renderer.h"

#include <algorithm>
#include <array>
#include <stdexcept>
#include <vector>

#include "line_shaders.h"
#include "renderer.h"

namespace vxl {
namespace {

const char* const kListFragment = R"(#version 430 core
layout(binding = 0, r32ui) uniform coherent uimage2D u_heads;
layout(binding = 0, offset = 0) uniform atomic_uint u_counter;
layout(std430, binding = 1) buffer Nodes { uvec4 nodes[]; };
uniform uint u_capacity;
uniform ivec4 u_band;  // x0, y0, x1, y1: only fragments inside are stored this pass
in vec4 v_color;
in float v_depth;
void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  if (p.x < u_band.x || p.y < u_band.y || p.x >= u_band.z || p.y >= u_band.w) discard;
  uint i = atomicCounterIncrement(u_counter);
  if (i < u_capacity) {
    uint previous = imageAtomicExchange(u_heads, p, i);
    nodes[i] = uvec4(packHalf2x16(v_color.rg), packHalf2x16(v_color.ba), floatBitsToUint(gl_FragCoord.z), previous);
  }
  discard;  // nothing is written to the colour buffer in this pass
}
)";

const char* const kClearCompute = R"(#version 430 core
layout(local_size_x = 8, local_size_y = 8) in;
layout(binding = 0, r32ui) uniform writeonly uimage2D u_heads;
void main() { imageStore(u_heads, ivec2(gl_GlobalInvocationID.xy), uvec4(0xFFFFFFFFu)); }
)";

const char* const kResolveCompute = R"(#version 430 core
layout(local_size_x = 8, local_size_y = 8) in;
layout(binding = 0, r32ui) uniform readonly uimage2D u_heads;
layout(binding = 1, rgba32f) uniform image2D u_result;
layout(std430, binding = 1) readonly buffer Nodes { uvec4 nodes[]; };
uniform ivec4 u_band;
uniform vec3 u_background;
const int B = 64;
float key_depth[B];
uint key_node[B];
// Fragments are ordered by (depth, node index): a strict order, so equal depths are never lost.
bool less_key(float da, uint ia, float db, uint ib) { return da < db || (da == db && ia < ib); }
void sift_down(int root, int n) {
  while (true) {
    int child = 2 * root + 1;
    if (child >= n) return;
    if (child + 1 < n && less_key(key_depth[child + 1], key_node[child + 1], key_depth[child], key_node[child])) child++;
    if (!less_key(key_depth[child], key_node[child], key_depth[root], key_node[root])) return;
    float d = key_depth[root]; key_depth[root] = key_depth[child]; key_depth[child] = d;
    uint k = key_node[root]; key_node[root] = key_node[child]; key_node[child] = k;
    root = child;
  }
}
void main() {
  ivec2 p = ivec2(gl_GlobalInvocationID.xy) + u_band.xy;
  if (p.x >= u_band.z || p.y >= u_band.w) return;
  vec3 color = u_background;
  float limit_depth = 3.0e38;   // only fragments nearer than the last batch's nearest remain
  uint limit_node = 0xFFFFFFFFu;
  uint head = imageLoad(u_heads, p).r;
  while (true) {
    // Batch: the B farthest fragments below the limit, kept in a min-heap (root = nearest kept).
    int n = 0;
    for (uint i = head; i != 0xFFFFFFFFu; i = nodes[i].w) {
      float d = uintBitsToFloat(nodes[i].z);
      if (!less_key(d, i, limit_depth, limit_node)) continue;
      if (n < B) {
        int c = n++;
        key_depth[c] = d; key_node[c] = i;
        while (c > 0) {  // sift up
          int parent = (c - 1) / 2;
          if (!less_key(key_depth[c], key_node[c], key_depth[parent], key_node[parent])) break;
          float t = key_depth[c]; key_depth[c] = key_depth[parent]; key_depth[parent] = t;
          uint u = key_node[c]; key_node[c] = key_node[parent]; key_node[parent] = u;
          c = parent;
        }
      } else if (less_key(key_depth[0], key_node[0], d, i)) {
        key_depth[0] = d; key_node[0] = i;
        sift_down(0, n);
      }
    }
    if (n == 0) break;
    // Heap sort with a min-heap leaves the batch in descending order: farthest first.
    for (int end = n - 1; end > 0; --end) {
      float t = key_depth[0]; key_depth[0] = key_depth[end]; key_depth[end] = t;
      uint u = key_node[0]; key_node[0] = key_node[end]; key_node[end] = u;
      sift_down(0, end);
    }
    for (int k = 0; k < n; ++k) {
      uvec4 node = nodes[key_node[k]];
      vec4 c = vec4(unpackHalf2x16(node.x), unpackHalf2x16(node.y));
      color = c.rgb * c.a + color * (1.0 - c.a);
    }
    limit_depth = key_depth[n - 1];
    limit_node = key_node[n - 1];
    if (n < B) break;
  }
  imageStore(u_result, p, vec4(color, 1.0));
}
)";

const char* const kBlitFragment = R"(#version 330 core
in vec2 v_uv;
uniform sampler2D u_result;
out vec4 frag;
void main() { frag = vec4(texture(u_result, v_uv).rgb, 1.0); }
)";

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
  list_program_ = gl::make_program(shaders::line_vertex(chunks, "#version 430 core"), kListFragment);
  clear_program_ = gl::make_compute_program(kClearCompute);
  resolve_program_ = gl::make_compute_program(kResolveCompute);
  blit_program_ = gl::make_program(shaders::kFullscreenVertex, kBlitFragment);
  glGenBuffers(1, &nodes_);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, nodes_);
  glBufferData(GL_SHADER_STORAGE_BUFFER, static_cast<GLsizeiptr>(capacity_ * 16), nullptr, GL_DYNAMIC_COPY);
  glGenBuffers(1, &counter_);
  glBindBuffer(GL_ATOMIC_COUNTER_BUFFER, counter_);
  glBufferData(GL_ATOMIC_COUNTER_BUFFER, 4, nullptr, GL_DYNAMIC_COPY);
}

ExactRenderer::~ExactRenderer() {
  for (GLuint p : {list_program_, clear_program_, resolve_program_, blit_program_})
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
  lines_.plan(camera, aspect, PlanOrder::Any, plan);
  const glm::vec3 bg = s.background();

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
    glUniform1ui(glGetUniformLocation(list_program_, "u_capacity"), static_cast<GLuint>(std::min<std::uint64_t>(capacity_, 0xFFFFFFFFu)));
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
      if (y1 - y0 <= 1) throw std::runtime_error("exact mode: one pixel row has more fragments than the node buffer holds");
      int mid = (y0 + y1) / 2;
      bands.push_back({mid, y1});
      bands.push_back({y0, mid});
      continue;
    }
    ++bands_used_;
    fragments_ += stored;
    glUseProgram(resolve_program_);
    glBindImageTexture(0, heads_, 0, GL_FALSE, 0, GL_READ_ONLY, GL_R32UI);
    glBindImageTexture(1, result_, 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, nodes_);
    glUniform4i(glGetUniformLocation(resolve_program_, "u_band"), 0, y0, width, y1);
    glUniform3f(glGetUniformLocation(resolve_program_, "u_background"), bg.r, bg.g, bg.b);
    glDispatchCompute((width + 7) / 8, (y1 - y0 + 7) / 8, 1);
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
  }
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

}  // namespace vxl
