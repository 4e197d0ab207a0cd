#include "viewer/render/clip_planes.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "viewer/render/camera.h"

namespace vxl {

bool Clipping::active() const {
  if (slab_mm > 0) return true;
  for (const AxisClip& p : planes)
    if (p.enabled) return true;
  return false;
}

std::optional<AxisClip> parse_axis_clip(const std::string& text) {
  AxisClip c;
  std::size_t at = 0;
  if (at < text.size() && (text[at] == '-' || text[at] == '+')) c.keep_above = text[at++] == '+';
  if (at >= text.size()) return std::nullopt;
  const char a = static_cast<char>(std::tolower(static_cast<unsigned char>(text[at++])));
  if (a < 'x' || a > 'z') return std::nullopt;
  c.axis = a - 'x';
  if (at >= text.size() || text[at++] != ',') return std::nullopt;
  const char* begin = text.c_str() + at;
  char* end = nullptr;
  c.position = std::strtod(begin, &end);
  if (end == begin || *end != '\0' || !std::isfinite(c.position)) return std::nullopt;
  return c;
}

std::string axis_clip_text(const AxisClip& c) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%s%c,%.17g", c.keep_above ? "" : "-", "xyz"[c.axis], c.position);
  return buf;
}

std::vector<glm::dvec4> clip_half_spaces(const Clipping& clipping, const Camera& camera) {
  std::vector<glm::dvec4> out;
  if (clipping.slab_mm > 0) {
    // Faces at target +- thickness / 2 along the view direction, normals pointing into the slab.
    const glm::dvec3 f = camera.forward();
    const double centre = glm::dot(f, camera.target), half = clipping.slab_mm / 2;
    out.push_back(glm::dvec4(f, -(centre - half)));
    out.push_back(glm::dvec4(-f, centre + half));
  }
  for (const AxisClip& p : clipping.planes) {
    if (!p.enabled) continue;
    glm::dvec3 n(0.0);
    n[p.axis] = p.keep_above ? 1.0 : -1.0;
    out.push_back(glm::dvec4(n, p.keep_above ? -p.position : p.position));
  }
  return out;
}

glm::dvec4 relative_to(const glm::dvec4& h, const glm::dvec3& origin) {
  const glm::dvec3 n(h);
  return glm::dvec4(n, h.w + glm::dot(n, origin));
}

}  // namespace vxl
