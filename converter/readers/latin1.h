// Source headers carry 8-bit text of unknown encoding (TrackVis fields, zip member names); provenance is
// JSON, which must be UTF-8. Bytes are read as Latin-1, which maps every byte to one code point.
#pragma once

#include <string>
#include <string_view>

namespace vxl {

inline std::string latin1_to_utf8(std::string_view bytes) {
  std::string out;
  out.reserve(bytes.size());
  for (unsigned char c : bytes) {
    if (c < 0x80) {
      out += static_cast<char>(c);
    } else {
      out += static_cast<char>(0xC0 | (c >> 6));
      out += static_cast<char>(0x80 | (c & 0x3F));
    }
  }
  return out;
}

}  // namespace vxl
