#include "viewer/render/colormap.h"

#include <algorithm>
#include <cmath>

namespace vxl {

namespace {

std::array<glm::vec3, kColormapSamples> grey_table() {
  std::array<glm::vec3, kColormapSamples> t;
  for (int k = 0; k < kColormapSamples; ++k) t[k] = glm::vec3(k / 32.0f);
  return t;
}

// matplotlib's "hot" segment data, evaluated at the sample points.
std::array<glm::vec3, kColormapSamples> hot_table() {
  auto ramp = [](double x, double x0, double y0, double x1) {
    return x <= x0 ? y0 : x >= x1 ? 1.0 : y0 + (1 - y0) * (x - x0) / (x1 - x0);
  };
  std::array<glm::vec3, kColormapSamples> t;
  for (int k = 0; k < kColormapSamples; ++k) {
    const double x = k / 32.0;
    t[k] = glm::vec3(static_cast<float>(ramp(x, 0.0, 0.0416, 0.365079)),
                     static_cast<float>(ramp(x, 0.365079, 0.0, 0.746032)),
                     static_cast<float>(ramp(x, 0.746032, 0.0, 1.0)));
  }
  return t;
}

// Entries 0, 8, 16, ..., 248 and 255 of matplotlib's 256-entry viridis table (CC0).
const std::array<glm::vec3, kColormapSamples> kViridis = {{
    {0.267004f, 0.004874f, 0.329415f}, {0.277018f, 0.050344f, 0.375715f}, {0.282327f, 0.094955f, 0.417331f},
    {0.282884f, 0.135920f, 0.453427f}, {0.278826f, 0.175490f, 0.483397f}, {0.270595f, 0.214069f, 0.507052f},
    {0.258965f, 0.251537f, 0.524736f}, {0.244972f, 0.287675f, 0.537260f}, {0.229739f, 0.322361f, 0.545706f},
    {0.214298f, 0.355619f, 0.551184f}, {0.199430f, 0.387607f, 0.554642f}, {0.185556f, 0.418570f, 0.556753f},
    {0.172719f, 0.448791f, 0.557885f}, {0.160665f, 0.478540f, 0.558115f}, {0.149039f, 0.508051f, 0.557250f},
    {0.137770f, 0.537492f, 0.554906f}, {0.127568f, 0.566949f, 0.550556f}, {0.120565f, 0.596422f, 0.543611f},
    {0.120638f, 0.625828f, 0.533488f}, {0.132268f, 0.655014f, 0.519661f}, {0.157851f, 0.683765f, 0.501686f},
    {0.196571f, 0.711827f, 0.479221f}, {0.246070f, 0.738910f, 0.452024f}, {0.304148f, 0.764704f, 0.419943f},
    {0.369214f, 0.788888f, 0.382914f}, {0.440137f, 0.811138f, 0.340967f}, {0.515992f, 0.831158f, 0.294279f},
    {0.595839f, 0.848717f, 0.243329f}, {0.678489f, 0.863742f, 0.189503f}, {0.762373f, 0.876424f, 0.137064f},
    {0.845561f, 0.887322f, 0.099702f}, {0.926106f, 0.897330f, 0.104071f}, {0.993248f, 0.906157f, 0.143936f},
}};

struct NamedColormap {
  Colormap map;
  const char* name;
};
constexpr NamedColormap kColormapNames[] = {
    {Colormap::Grey, "grey"}, {Colormap::Hot, "hot"}, {Colormap::Viridis, "viridis"}};

}  // namespace

std::optional<Colormap> parse_colormap(const std::string& name) {
  for (const NamedColormap& n : kColormapNames)
    if (name == n.name) return n.map;
  if (name == "gray") return Colormap::Grey;
  return std::nullopt;
}

const char* colormap_name(Colormap map) {
  for (const NamedColormap& n : kColormapNames)
    if (n.map == map) return n.name;
  return "?";
}

std::vector<std::string> colormap_names() {
  std::vector<std::string> names;
  for (const NamedColormap& n : kColormapNames) names.emplace_back(n.name);
  return names;
}

const std::array<glm::vec3, kColormapSamples>& colormap_samples(Colormap map) {
  static const auto grey = grey_table(), hot = hot_table();
  switch (map) {
    case Colormap::Grey: return grey;
    case Colormap::Hot: return hot;
    case Colormap::Viridis: break;
  }
  return kViridis;
}

glm::vec3 colormap_rgb(Colormap map, float t) {
  const auto& s = colormap_samples(map);
  const float x = std::clamp(std::isnan(t) ? 0.0f : t, 0.0f, 1.0f) * (kColormapSamples - 1);
  const int i = std::min(static_cast<int>(x), kColormapSamples - 2);
  return glm::mix(s[i], s[i + 1], x - static_cast<float>(i));
}

}  // namespace vxl
