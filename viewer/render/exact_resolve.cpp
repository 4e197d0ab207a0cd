#include "viewer/render/exact_resolve.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>

#include <glm/glm.hpp>

#include "format/base/parallel.h"

namespace vxl {
namespace {

// One pixel a thread. A list of any length is composited in batches: each walk of the list keeps, by
// insertion, the kBatch fragments that come next after the last one composited, then composites them. The
// list is walked about length / kBatch times; no storage grows with it.
const char* const kResolveCompute = R"(#version 430 core
layout(local_size_x = 8, local_size_y = 8) in;
layout(binding = 0, r32ui) uniform readonly uimage2D u_heads;
layout(binding = 1, rgba32f) uniform image2D u_result;
layout(std430, binding = 1) readonly buffer Nodes { uvec4 nodes[]; };
uniform uint u_stored;
uniform ivec2 u_rows;  // y0, y1
const uint kEnd = 0xFFFFFFFFu;
const int kBatch = 16;
// Whether fragment a (depth, colour words, node) is composited before b: the farther first; at equal depths by
// their colours' words, then their nodes (fragments equal in both are the same fragment).
bool before(float da, uvec2 ca, uint ia, float db, uvec2 cb, uint ib) {
  if (da != db) return da > db;
  if (ca.x != cb.x) return ca.x < cb.x;
  if (ca.y != cb.y) return ca.y < cb.y;
  return ia < ib;
}
void main() {
  ivec2 p = ivec2(gl_GlobalInvocationID.x, int(gl_GlobalInvocationID.y) + u_rows.x);
  if (p.x >= imageSize(u_heads).x || p.y >= u_rows.y) return;
  uint head = imageLoad(u_heads, p).r;
  if (head == kEnd) return;
  // precise: every operation rounded on its own, as the CPU composites (no fused multiply-add).
  precise vec3 color = imageLoad(u_result, p).rgb;
  float depth[kBatch];
  uvec2 colour[kBatch];
  uint node[kBatch];
  bool started = false;
  float last_depth = 0.0;
  uvec2 last_colour = uvec2(0u);
  uint last_node = 0u;
  for (;;) {
    int n = 0;
    uint walked = 0u;  // a list cannot hold more than the nodes stored: a corrupt one ends there
    for (uint i = head; i != kEnd && i < u_stored && walked < u_stored; i = nodes[i].w, ++walked) {
      uvec4 f = nodes[i];
      float d = uintBitsToFloat(f.z);
      if (started && !before(last_depth, last_colour, last_node, d, f.xy, i)) continue;  // composited already
      if (n == kBatch && !before(d, f.xy, i, depth[kBatch - 1], colour[kBatch - 1], node[kBatch - 1])) continue;
      int j = n < kBatch ? n++ : kBatch - 1;
      for (; j > 0 && before(d, f.xy, i, depth[j - 1], colour[j - 1], node[j - 1]); --j) {
        depth[j] = depth[j - 1];
        colour[j] = colour[j - 1];
        node[j] = node[j - 1];
      }
      depth[j] = d;
      colour[j] = f.xy;
      node[j] = i;
    }
    for (int k = 0; k < n; ++k) {
      uvec4 f = nodes[node[k]];
      vec2 rg = unpackHalf2x16(f.x), ba = unpackHalf2x16(f.y);
      color = vec3(rg, ba.x) * ba.y + color * (1.0 - ba.y);
    }
    if (n < kBatch) break;
    started = true;
    last_depth = depth[kBatch - 1];
    last_colour = colour[kBatch - 1];
    last_node = node[kBatch - 1];
  }
  imageStore(u_result, p, vec4(color, 1.0));
}
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

// binary32 -> binary16, round to nearest (for the lists the self-test makes; values within half's range).
std::uint16_t float_to_half(float f) {
  std::uint32_t bits;
  std::memcpy(&bits, &f, 4);
  const std::uint32_t sign = (bits >> 16) & 0x8000u;
  const int exponent = int((bits >> 23) & 0xFFu) - 127 + 15;
  std::uint32_t mantissa = bits & 0x7FFFFFu;
  if (exponent <= 0) return static_cast<std::uint16_t>(sign);  // tiny: zero is enough here
  std::uint32_t h = sign | std::uint32_t(exponent) << 10 | mantissa >> 13;
  if ((mantissa & 0x1FFFu) > 0x1000u || ((mantissa & 0x1FFFu) == 0x1000u && (h & 1u))) ++h;
  return static_cast<std::uint16_t>(h);
}

}  // namespace

void composite_lists_on_cpu(std::span<const std::uint32_t> heads, std::span<const FragmentNode> nodes, int width,
                            int y0, int y1, std::span<float> image) {
  // Pixels are independent: bands of rows on every thread, each with its own scratch list.
  constexpr int kRows = 8;
  std::vector<std::vector<std::pair<float, std::uint32_t>>> lists(resolve_threads(0));  // (depth, node)
  parallel_for(std::uint64_t(std::max(0, y1 - y0) + kRows - 1) / kRows, 0, [&](std::uint64_t band, unsigned t) {
    std::vector<std::pair<float, std::uint32_t>>& list = lists[t];
    for (int y = y0 + int(band) * kRows; y < std::min(y1, y0 + int(band + 1) * kRows); ++y)
      for (int x = 0; x < width; ++x) {
        list.clear();
        for (std::uint32_t i = heads[std::size_t(y) * width + x]; i != kListEnd; i = nodes[i][3]) {
          if (i >= nodes.size() || list.size() >= nodes.size())
            throw std::runtime_error("exact mode: corrupt fragment list");
          float depth;
          std::memcpy(&depth, &nodes[i][2], 4);
          list.push_back({depth, i});
        }
        if (list.empty()) continue;
        // Farthest first; at equal depths by the colours' words: a GPU stores the fragments of one run in an
        // order of its own, and the picture must not depend on it. (Runs are composited one after another:
        // a fragment of an earlier run goes under.)
        std::sort(list.begin(), list.end(), [&](const auto& a, const auto& b) {
          if (a.first != b.first) return a.first > b.first;
          const FragmentNode &na = nodes[a.second], &nb = nodes[b.second];
          if (na[0] != nb[0]) return na[0] < nb[0];
          if (na[1] != nb[1]) return na[1] < nb[1];
          return a.second < b.second;
        });
        float* out = image.data() + (std::size_t(y) * width + x) * 4;
        glm::vec3 color(out[0], out[1], out[2]);
        for (const auto& [depth, i] : list) {
          const FragmentNode& n = nodes[i];
          const glm::vec3 c(half_to_float(n[0] & 0xFFFF), half_to_float(n[0] >> 16), half_to_float(n[1] & 0xFFFF));
          const float a = half_to_float(n[1] >> 16);
          color = c * a + color * (1.0f - a);
        }
        out[0] = color.r, out[1] = color.g, out[2] = color.b, out[3] = 1.0f;
      }
  });
}

bool software_rasterizer() {
  const char* name = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  const std::string renderer = name ? name : "";
  for (const char* software : {"llvmpipe", "softpipe", "SwiftShader"})
    if (renderer.find(software) != std::string::npos) return true;
  return false;
}

GpuListResolve::GpuListResolve() : program_(gl::make_compute_program(kResolveCompute)) {}

GpuListResolve::~GpuListResolve() {
  if (program_) glDeleteProgram(program_);
}

void GpuListResolve::resolve(GLuint heads, GLuint nodes, std::uint32_t stored, GLuint result, int width, int y0,
                             int y1) const {
  if (y1 <= y0 || width <= 0) return;
  glUseProgram(program_);
  glUniform1ui(glGetUniformLocation(program_, "u_stored"), stored);
  glUniform2i(glGetUniformLocation(program_, "u_rows"), y0, y1);
  glBindImageTexture(0, heads, 0, GL_FALSE, 0, GL_READ_ONLY, GL_R32UI);
  glBindImageTexture(1, result, 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, nodes);
  glDispatchCompute(static_cast<GLuint>((width + 7) / 8), static_cast<GLuint>((y1 - y0 + 7) / 8), 1);
  // The next list pass rewrites the heads, and the picture is read from `result`.
  glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT);
}

bool GpuListResolve::agrees_with_cpu() const {
  // 64 x 4 pixels: lists of 0 to 80 fragments (several batches), depths from a few values (ties), linked in a
  // shuffled order, over a background of varied colours.
  constexpr int kWidth = 64, kHeight = 4;
  std::mt19937 random(7);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::vector<std::uint32_t> heads(kWidth * kHeight, kListEnd);
  std::vector<FragmentNode> nodes;
  for (int p = 0; p < kWidth * kHeight; ++p) {
    const int length = (p * 37) % 81;
    for (int k = 0; k < length; ++k) {
      const float depth = 0.25f * float(random() % 5);
      std::uint32_t depth_bits;
      std::memcpy(&depth_bits, &depth, 4);
      const std::uint32_t rg = float_to_half(unit(random)) | std::uint32_t(float_to_half(unit(random))) << 16;
      const std::uint32_t ba = float_to_half(unit(random)) | std::uint32_t(float_to_half(unit(random))) << 16;
      nodes.push_back({rg, ba, depth_bits, 0});
    }
  }
  // Each pixel's nodes linked in a shuffled order: the walk order is not the node order.
  std::vector<std::uint32_t> order(nodes.size());
  for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  std::shuffle(order.begin(), order.end(), random);
  std::uint32_t next = 0;
  for (int p = 0; p < kWidth * kHeight; ++p)
    for (int k = 0, length = (p * 37) % 81; k < length; ++k) {
      const std::uint32_t i = order[next++];
      nodes[i][3] = heads[p];
      heads[p] = i;
    }
  std::vector<float> background(kWidth * kHeight * 4);
  for (std::size_t i = 0; i < background.size(); ++i) background[i] = i % 4 == 3 ? 1.0f : unit(random);
  std::vector<float> expected = background;
  composite_lists_on_cpu(heads, nodes, kWidth, 0, kHeight, expected);

  GLuint textures[2] = {0, 0}, buffer = 0;
  glGenTextures(2, textures);
  glBindTexture(GL_TEXTURE_2D, textures[0]);
  glTexStorage2D(GL_TEXTURE_2D, 1, GL_R32UI, kWidth, kHeight);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);  // an integer texture: complete with NEAREST
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, kWidth, kHeight, GL_RED_INTEGER, GL_UNSIGNED_INT, heads.data());
  glBindTexture(GL_TEXTURE_2D, textures[1]);
  glTexStorage2D(GL_TEXTURE_2D, 1, GL_RGBA32F, kWidth, kHeight);
  glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, kWidth, kHeight, GL_RGBA, GL_FLOAT, background.data());
  glGenBuffers(1, &buffer);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, buffer);
  glBufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(nodes.size() * sizeof(FragmentNode)), nodes.data(), GL_STATIC_DRAW);
  resolve(textures[0], buffer, static_cast<std::uint32_t>(nodes.size()), textures[1], kWidth, 0, kHeight);
  std::vector<float> result(background.size());
  glBindTexture(GL_TEXTURE_2D, textures[1]);
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  glGetTexImage(GL_TEXTURE_2D, 0, GL_RGBA, GL_FLOAT, result.data());
  glBindTexture(GL_TEXTURE_2D, 0);
  glDeleteTextures(2, textures);
  glDeleteBuffers(1, &buffer);
  return std::memcmp(result.data(), expected.data(), result.size() * sizeof(float)) == 0;
}

}  // namespace vxl
