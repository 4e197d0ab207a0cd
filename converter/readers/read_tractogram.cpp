#include <algorithm>
#include <filesystem>

#include "converter/readers/read_tractogram.h"
#include "format/error.h"

namespace vxl {

Tractogram read_tractogram(const std::string& path) {
  std::string lower = path;
  while (lower.size() > 1 && lower.back() == '/') lower.pop_back();
  std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return std::tolower(c); });
  auto ends = [&](const char* suffix) { return lower.ends_with(suffix); };
  if (ends(".tck")) return read_tck(path);
  if (ends(".trk") || ends(".trk.gz")) return read_trk(path);
  if (ends(".trx")) return read_trx(path);
  if (ends(".vtk")) return read_vtk(path);
  if (ends(".vtp")) return read_vtp(path);
  if (!std::filesystem::exists(path)) fail_input(path, std::nullopt, "no such file");
  std::string what = "unsupported file type";
  if (ends(".tsf")) what = "a TSF file holds per-point scalars, not streamlines";
  throw Error(
      ErrorKind::Unsupported, path, std::nullopt,
      what + " (supported: .tck, .trk, .trk.gz, .trx zip or directory, .vtk legacy POLYDATA, .vtp XML PolyData)");
}

}  // namespace vxl
