#include "converter/readers/source_formats.h"

#include <array>
#include <cctype>

#include "converter/readers/read_tractogram.h"

namespace vxl {

namespace {

constexpr const char* kTck[] = {".tck"};
constexpr const char* kTrk[] = {".trk.gz", ".trk"};
constexpr const char* kTrx[] = {".trx"};
constexpr const char* kVtk[] = {".vtk"};
constexpr const char* kVtp[] = {".vtp"};

const std::array<SourceFormat, 5> kFormats = {{
    {"TCK", kTck, true, read_tck, ".tck"},
    {"TRK", kTrk, false, read_trk, ".trk, .trk.gz"},
    {"TRX", kTrx, false, read_trx, ".trx zip or directory"},
    {"VTK", kVtk, false, read_vtk, ".vtk legacy POLYDATA"},
    {"VTP", kVtp, false, read_vtp, ".vtp XML PolyData"},
}};

}  // namespace

std::span<const SourceFormat> source_formats() { return kFormats; }

SourceMatch source_format_of(const std::string& path) {
  std::string lower = path;
  while (lower.size() > 1 && lower.back() == '/') lower.pop_back();
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  for (const SourceFormat& f : kFormats)
    for (const char* suffix : f.suffixes)
      if (lower.ends_with(suffix)) return {&f, suffix};
  return {};
}

std::string source_descriptions_text() {
  std::string text;
  for (const SourceFormat& f : kFormats) text += std::string(&f == &kFormats[0] ? "" : ", ") + f.description;
  return text;
}

std::string supported_sources_text() { return "supported: " + source_descriptions_text(); }

std::string source_suffixes_text(const std::string& separator) {
  std::string text;
  for (const SourceFormat& f : kFormats)
    for (const char* suffix : f.suffixes) text += (text.empty() ? "" : separator) + std::string(suffix);
  return text;
}

std::string source_format_names_text(const std::string& separator, std::optional<bool> streamable) {
  std::string text;
  for (const SourceFormat& f : kFormats)
    if (!streamable || f.streamable == *streamable) text += (text.empty() ? "" : separator) + std::string(f.name);
  return text;
}

}  // namespace vxl
