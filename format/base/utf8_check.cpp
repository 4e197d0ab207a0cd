#include "format/base/utf8_check.h"

#include <iterator>

#include <utf8cpp/utf8.h>  // utfcpp (libutfcpp-dev): strict RFC 3629 decoding

namespace vxl {

bool is_valid_utf8(std::string_view s) { return utf8::is_valid(s.begin(), s.end()); }

std::string to_valid_utf8(std::string_view s) {
  if (is_valid_utf8(s)) return std::string(s);
  std::string out;
  out.reserve(2 * s.size());
  for (unsigned char c : s) utf8::append(static_cast<char32_t>(c), std::back_inserter(out));
  return out;
}

}  // namespace vxl
