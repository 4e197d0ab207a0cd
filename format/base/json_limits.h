// Parsing JSON from files: a TRX header.json, the PROV of a .vxl or .vxlz, a voxview view file. nlohmann's
// DOM copies, compares and prints values recursively, so a document nested a few ten thousand levels deep
// exhausts the stack when it is used; every JSON the programs read goes through parse_json, which refuses
// such nesting before the document is parsed.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

namespace vxl {

// The deepest nesting of arrays and objects accepted in any JSON read (real files nest a few levels).
inline constexpr std::size_t kMaxJsonDepth = 256;

// A source's own JSON (a TRX header.json) is kept in PROV two levels down (`source.header`): it is held
// to this, so that the PROV written from it is within kMaxJsonDepth.
inline constexpr std::size_t kMaxSourceJsonDepth = kMaxJsonDepth - 2;

// The byte offset in `text` of the first '[' or '{' nested deeper than `max_depth` (brackets inside
// strings do not count), or nothing. Linear, no recursion, no allocation.
std::optional<std::uint64_t> json_too_deep_at(std::string_view text, std::size_t max_depth = kMaxJsonDepth);

// `text` parsed as nlohmann::json::parse(text, nullptr, false) does: a discarded value when it is not
// well-formed JSON. Nesting deeper than `max_depth` is refused first, without parsing: vxl::Error (Input)
// naming `file`, the byte offset (`base` + the offset in `text`, or none when `base` is none) and `what`.
nlohmann::json parse_json(std::string_view text, const std::string& file, std::optional<std::uint64_t> base,
                          const std::string& what, std::size_t max_depth = kMaxJsonDepth);

}  // namespace vxl
