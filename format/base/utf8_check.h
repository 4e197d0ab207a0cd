// UTF-8 checks for the names a .vxl carries (section ids, value-set and group names): they end up in JSON
// (`info --json`), in zip member names (`export` to TRX) and on screen, all of which need valid UTF-8.
#pragma once

#include <string>
#include <string_view>

namespace vxl {

// Well-formed UTF-8 as RFC 3629 defines it: no overlong forms, no surrogates, nothing above U+10FFFF.
bool is_valid_utf8(std::string_view s);

// `s` itself when it is valid UTF-8, else every byte read as Latin-1 (one code point per byte), so that a
// name from a file system or an old archive still says what its bytes were.
std::string to_valid_utf8(std::string_view s);

}  // namespace vxl
