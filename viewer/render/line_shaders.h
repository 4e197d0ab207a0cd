// GLSL sources of the line renderer. The vertex shader is generated for the scene's texture-span count (samplers
// cannot be indexed dynamically in GLSL 3.30, so each span gets its own samplers and an if-chain).
#pragma once

#include <string>

namespace vxl::shaders {

// Groups with their own colour and opacity in the shader's table; group g uses entry g mod kShaderGroups.
inline constexpr int kShaderGroups = 64;

// Vertex shader: virtual vertex id -> segment end (scene_layout.h), camera-relative position, colour.
std::string line_vertex(unsigned span_count, const char* version = "#version 330 core");

// A fragment shader for the line pass: `body` (with its main) after the line inputs and line_color(),
// which gives the fragment's colour and alpha (colour map per fragment, lighting), and
// discard_behind_slices(), which each body calls first (the opaque slices hide what is behind them).
// slice_test false compiles that test out: a scene without an image does not pay for it (measured on
// llvmpipe: about 6 % of an axis frame's CPU time, the shader's `discard` alone costing it).
std::string line_fragment(const char* body, const char* version = "#version 330 core", bool slice_test = true);

// Bodies for line_fragment.
extern const char* const kLineOverFragment;         // colour with alpha: blended "over", or opaque
extern const char* const kLineWboitAccumFragment;   // McGuire & Bavoil accumulation (premultiplied, weighted)
extern const char* const kLineWboitRevealFragment;  // revealage: product of (1 - alpha)
extern const char* const kLineAdditiveFragment;     // sum of alpha * colour

// Fullscreen composites (a triangle from gl_VertexID, no buffers).
extern const char* const kFullscreenVertex;
extern const char* const kWboitCompositeFragment;
extern const char* const kAdditiveCompositeFragment;

}  // namespace vxl::shaders
