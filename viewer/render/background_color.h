// The picture's background colour as the user writes it (--background, saved views): a name, "#RRGGBB", or
// "R,G,B" with each channel a number in [0, 1].
#pragma once

#include <optional>
#include <string>

#include <glm/glm.hpp>

namespace vxl {

// nullopt for anything else (a channel outside [0, 1], a malformed hex, an unknown name).
std::optional<glm::vec3> parse_background_color(const std::string& text);
// The forms parse_background_color() takes, for error messages and --help.
std::string background_color_forms();
// The shortest text that parses back to `color` exactly: its name, else #rrggbb, else R,G,B.
std::string background_color_text(const glm::vec3& color);
// Whether text drawn over `background` should be dark (a light background) rather than light.
bool background_is_light(const glm::vec3& background);

}  // namespace vxl
