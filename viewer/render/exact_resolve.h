// Compositing the exact mode's per-pixel fragment lists (exact_renderer.h) back to front, two ways that give
// the same floats: on the GPU (a compute pass, the default) and on the CPU (the reference, and the fallback
// for a driver whose compute pass disagrees with it).
//
// A fragment node is four words: its colour's red and green, blue and alpha (GLSL packHalf2x16), its window
// depth (float bits) and the next node of its pixel's list (0xFFFFFFFF ends a list). A pixel's fragments are
// composited farthest first and, at equal depths, in the order of their colour words as unsigned integers
// (the red-green word, then the blue-alpha one, each the smaller first), each as colour * alpha + below * (1 - alpha),
// every operation rounded on its own. The picture depends on the fragments alone, not on the order a GPU stored them in
// (which its fragment shaders' scheduling decides).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "viewer/render/gl_util.h"

namespace vxl {

using FragmentNode = std::array<std::uint32_t, 4>;
inline constexpr std::uint32_t kListEnd = 0xFFFFFFFFu;

// Composites rows [y0, y1) of the lists (heads: one node index per pixel, width a row, bottom row first) over
// `image` (RGBA floats, the same rows). Throws std::runtime_error on a list that leaves the nodes or loops.
void composite_lists_on_cpu(std::span<const std::uint32_t> heads, std::span<const FragmentNode> nodes, int width,
                            int y0, int y1, std::span<float> image);

// Whether the current context's driver rasterises on the CPU (Mesa's llvmpipe or softpipe, SwiftShader).
bool software_rasterizer();

// The compute pass (OpenGL 4.3). Needs a current context; made once per ExactRenderer.
class GpuListResolve {
 public:
  GpuListResolve();
  ~GpuListResolve();
  GpuListResolve(const GpuListResolve&) = delete;
  GpuListResolve& operator=(const GpuListResolve&) = delete;

  // Composites rows [y0, y1) of the lists in `heads` (an R32UI texture) whose nodes are the first `stored` of
  // the storage buffer `nodes`, over `result` (an RGBA32F texture of the same size), in place.
  void resolve(GLuint heads, GLuint nodes, std::uint32_t stored, GLuint result, int width, int y0, int y1) const;

  // Whether this driver composites lists made to try it (empty pixels, lists longer than a batch, equal
  // depths, colours and alphas of every range) to the same floats as composite_lists_on_cpu.
  bool agrees_with_cpu() const;

 private:
  GLuint program_ = 0;
};

}  // namespace vxl
