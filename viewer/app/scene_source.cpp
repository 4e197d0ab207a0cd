#include "scene_source.h"

#include <cstdio>
#include <filesystem>
#include <unistd.h>

#include "convert.h"
#include "read_tractogram.h"
#include "unpack.h"

namespace vxl::app {

VxlFile open_scene(const std::string& path, double voxel_size) {
  std::string lower = path;
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (lower.ends_with(".vxl")) return VxlFile::open(path);
  if (lower.ends_with(".vxlz")) {
    // A package is unpacked into an unlinked temporary .vxl: the mapping keeps it alive, nothing is left.
    std::filesystem::path temp = std::filesystem::temp_directory_path() /
                                 ("voxview-" + std::to_string(::getpid()) + "-" + std::filesystem::path(path).filename().string() + ".vxl");
    unpack_vxlz(path, temp.string(), {});
    VxlFile f = VxlFile::open(temp.string());
    std::filesystem::remove(temp);
    return f;
  }

  Tractogram t = read_tractogram(path);
  for (const std::string& w : t.source.warnings) std::fprintf(stderr, "voxview: warning: %s: %s\n", path.c_str(), w.c_str());
  std::filesystem::path temp = std::filesystem::temp_directory_path() /
                               ("voxview-" + std::to_string(::getpid()) + "-" + std::filesystem::path(path).filename().string() + ".vxl");
  ConvertSettings settings;
  settings.voxel_size = voxel_size;
  convert_tractogram(std::move(t), temp.string(), settings);
  VxlFile f = VxlFile::open(temp.string());
  std::filesystem::remove(temp);  // the mapping keeps the data; nothing is left behind
  std::fprintf(stderr,
               "voxview: converted %s in memory. To reopen it instantly, convert once:\n"
               "  voxlines convert '%s' '%s.vxl'\n",
               path.c_str(), path.c_str(), std::filesystem::path(path).stem().string().c_str());
  return f;
}

}  // namespace vxl::app
