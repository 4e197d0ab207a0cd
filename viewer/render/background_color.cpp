#include "viewer/render/background_color.h"

#include <charconv>
#include <cmath>
#include <cstdlib>

#include "viewer/render/render_settings.h"

namespace vxl {

namespace {

struct NamedColor {
  const char* name;
  glm::vec3 rgb;
};
// A few greys cover what figures use; anything else is one #RRGGBB away.
const NamedColor kNames[] = {{"black", glm::vec3(0.0f)},     {"white", glm::vec3(1.0f)},
                             {"grey", glm::vec3(0.5f)},      {"gray", glm::vec3(0.5f)},
                             {"darkgrey", glm::vec3(0.25f)}, {"lightgrey", glm::vec3(0.75f)}};

// "R,G,B": three numbers in [0, 1], nothing else.
std::optional<glm::vec3> parse_rgb_triple(const std::string& text) {
  glm::vec3 c;
  const char* p = text.c_str();
  for (int i = 0; i < 3; ++i) {
    if (i > 0 && *p++ != ',') return std::nullopt;
    char* end = nullptr;
    c[i] = std::strtof(p, &end);
    if (end == p || !(c[i] >= 0.0f && c[i] <= 1.0f)) return std::nullopt;
    p = end;
  }
  if (*p != '\0') return std::nullopt;
  return c;
}

std::string float_text(float v) {
  char buf[32];
  const auto result = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, result.ptr);
}

}  // namespace

std::optional<glm::vec3> parse_background_color(const std::string& text) {
  for (const NamedColor& n : kNames)
    if (text == n.name) return n.rgb;
  if (!text.empty() && text[0] == '#') return parse_hex_color(text);
  return parse_rgb_triple(text);
}

std::string background_color_forms() {
  return "a name (black, white, grey, darkgrey, lightgrey), #RRGGBB (e.g. #1a2b3c) or R,G,B with each channel in "
         "[0, 1] (e.g. 0.1,0.1,0.2)";
}

std::string background_color_text(const glm::vec3& color) {
  for (const NamedColor& n : kNames)
    if (color == n.rgb) return n.name;
  const std::string hex = hex_color(color);
  if (parse_hex_color(hex) == color) return hex;
  return float_text(color.r) + "," + float_text(color.g) + "," + float_text(color.b);
}

bool background_is_light(const glm::vec3& background) {
  return glm::dot(background, glm::vec3(0.2126f, 0.7152f, 0.0722f)) > 0.5f;  // Rec. 709 luminance
}

}  // namespace vxl
