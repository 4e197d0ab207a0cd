#include <cctype>
#include <filesystem>

#include "converter/readers/read_tractogram.h"
#include "converter/readers/source_formats.h"
#include "format/base/error.h"

namespace vxl {

Tractogram read_tractogram(const std::string& path) {
  if (const SourceMatch match = source_format_of(path); match.format) return match.format->read(path);
  if (!std::filesystem::exists(path)) fail_input(path, std::nullopt, "no such file");
  std::string lower = path;
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  const std::string what =
      lower.ends_with(".tsf") ? "a TSF file holds per-point scalars, not streamlines" : "unsupported file type";
  throw Error(ErrorKind::Unsupported, path, std::nullopt, what + " (" + supported_sources_text() + ")");
}

}  // namespace vxl
