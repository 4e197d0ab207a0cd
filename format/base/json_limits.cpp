#include "format/base/json_limits.h"

#include "format/base/error.h"

namespace vxl {

std::optional<std::uint64_t> json_too_deep_at(std::string_view text, std::size_t max_depth) {
  std::size_t depth = 0;
  bool in_string = false, escaped = false;
  for (std::size_t k = 0; k < text.size(); ++k) {
    const char c = text[k];
    if (in_string) {
      if (escaped)
        escaped = false;
      else if (c == '\\')
        escaped = true;
      else if (c == '"')
        in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > max_depth) return k;
    } else if ((c == ']' || c == '}') && depth > 0) {
      --depth;
    }
  }
  return std::nullopt;
}

nlohmann::json parse_json(std::string_view text, const std::string& file, std::optional<std::uint64_t> base,
                          const std::string& what, std::size_t max_depth) {
  if (const auto at = json_too_deep_at(text, max_depth))
    fail_input(file, base ? std::optional<std::uint64_t>(*base + *at) : std::nullopt,
               what + ": JSON nested deeper than " + std::to_string(max_depth) + " arrays and objects");
  return nlohmann::json::parse(text, nullptr, false);
}

}  // namespace vxl
