// Colour maps for colouring by value (--color scalar): grey, hot and viridis, as tables of 33 samples at
// t = 0, 1/32, ..., 1 with linear interpolation between them. The table is the definition: the line shader
// interpolates the same samples (uploaded as uniforms), so colormap_rgb() predicts a pixel to the rounding.
//
//   grey     black to white.
//   hot      black - red - yellow - white, matplotlib's "hot" (red rises over [0, 0.365], green over
//            [0.365, 0.746], blue over [0.746, 1]; red starts at 0.0416).
//   viridis  matplotlib's perceptually uniform default (van der Walt & Smith; the CC0 table, every 8th of its
//            256 entries and the last).
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace vxl {

enum class Colormap { Grey, Hot, Viridis };

std::optional<Colormap> parse_colormap(const std::string& name);
const char* colormap_name(Colormap map);
// Every colour map's name ("grey", "hot", "viridis"), for help texts; parse_colormap also takes "gray".
std::vector<std::string> colormap_names();

inline constexpr int kColormapSamples = 33;
const std::array<glm::vec3, kColormapSamples>& colormap_samples(Colormap map);

// The colour of t in [0, 1] (clamped), interpolated like the shader does.
glm::vec3 colormap_rgb(Colormap map, float t);

}  // namespace vxl
