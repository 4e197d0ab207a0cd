// Whether a file name ends with a suffix, ignoring ASCII case (".TCK" is a TCK): what chooses a file's format by its
// name, without a copy of the name.
#pragma once

#include <cctype>
#include <string_view>

namespace vxl {

inline bool has_suffix_ignoring_case(std::string_view name, std::string_view suffix) {
  if (name.size() < suffix.size()) return false;
  const std::string_view end = name.substr(name.size() - suffix.size());
  for (std::size_t i = 0; i < end.size(); ++i)
    if (std::tolower(static_cast<unsigned char>(end[i])) != std::tolower(static_cast<unsigned char>(suffix[i])))
      return false;
  return true;
}

}  // namespace vxl
