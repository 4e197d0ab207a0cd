#include "viewer/app/scene_source.h"

#include <unistd.h>
#include <algorithm>
#include <cstdio>
#include <filesystem>

#include "converter/convert.h"
#include "converter/readers/read_tractogram.h"
#include "converter/readers/read_tsf.h"
#include "converter/unpack.h"
#include "format/error.h"
#include "format/vxl_verify.h"
#include "viewer/render/renderer.h"

namespace vxl::app {
namespace {

// Full verification (spec §7, `verify`) of the .vxl at `path`; `shown` is the name the user gave.
void verify_or_refuse(const std::string& path, const std::string& shown) {
  const VerifyResult r = verify_vxl(path);
  if (r.valid) return;
  std::string problem = r.problem;
  if (problem.starts_with(path + ": ")) problem.erase(0, path.size() + 2);  // the error names the file already
  throw Error(ErrorKind::Input, shown, std::nullopt, "--verify: the file is damaged or malformed: " + problem);
}

}  // namespace

VxlFile open_scene(const std::string& path, double voxel_size, const std::vector<std::string>& tsf, bool verify) {
  std::string lower = path;
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (!tsf.empty() && (lower.ends_with(".vxl") || lower.ends_with(".vxlz")))
    throw Error(
        ErrorKind::Usage, path, std::nullopt,
        "--tsf adds values to a source tractogram converted in memory; a .vxl keeps the values it was converted "
        "with (voxlines convert IN.tck OUT.vxl --tsf FILE.tsf)");
  if (lower.ends_with(".vxl")) {
    if (verify) verify_or_refuse(path, path);
    return VxlFile::open(path);
  }
  if (lower.ends_with(".vxlz")) {
    // A package is unpacked into an unlinked temporary .vxl: the mapping keeps it alive, nothing is left.
    std::filesystem::path temp =
        std::filesystem::temp_directory_path() /
        ("voxview-" + std::to_string(::getpid()) + "-" + std::filesystem::path(path).filename().string() + ".vxl");
    unpack_vxlz(path, temp.string(), {});
    try {
      if (verify) verify_or_refuse(temp.string(), path);
      VxlFile f = VxlFile::open(temp.string());
      std::filesystem::remove(temp);
      return f;
    } catch (...) {
      std::filesystem::remove(temp);
      throw;
    }
  }

  Tractogram t = read_tractogram(path);
  for (const std::string& f : tsf) attach_tsf(t, f);
  for (const std::string& w : t.source.warnings)
    std::fprintf(stderr, "voxview: warning: %s: %s\n", path.c_str(), w.c_str());
  std::filesystem::path temp =
      std::filesystem::temp_directory_path() /
      ("voxview-" + std::to_string(::getpid()) + "-" + std::filesystem::path(path).filename().string() + ".vxl");
  ConvertSettings settings;
  settings.voxel_size = voxel_size;
  for (const std::string& w : convert_tractogram(std::move(t), temp.string(), settings).warnings)
    std::fprintf(stderr, "voxview: warning: %s: %s\n", path.c_str(), w.c_str());
  VxlFile f = VxlFile::open(temp.string());
  std::filesystem::remove(temp);  // the mapping keeps the data; nothing is left behind
  std::string tsf_options;
  for (const std::string& f : tsf) tsf_options += " --tsf '" + f + "'";
  std::fprintf(stderr,
               "voxview: converted %s in memory. To reopen it instantly, convert once:\n"
               "  voxlines convert '%s' '%s.vxl'%s\n",
               path.c_str(), path.c_str(), std::filesystem::path(path).stem().string().c_str(), tsf_options.c_str());
  return f;
}

std::vector<VxlFile> open_scenes(const std::vector<std::string>& paths, double voxel_size,
                                 const std::vector<std::string>& tsf, bool verify) {
  if (!tsf.empty() && paths.size() != 1)
    throw Error(ErrorKind::Usage, "", std::nullopt,
                "--tsf needs a single input tractogram (it has one value per point of that file); convert each with "
                "voxlines convert IN.tck OUT.vxl --tsf FILE.tsf and open the .vxl files together");
  std::vector<VxlFile> files;
  for (const std::string& p : paths) files.push_back(open_scene(p, voxel_size, tsf, verify));
  return files;
}

std::vector<const VxlFile*> pointers(const std::vector<VxlFile>& files) {
  std::vector<const VxlFile*> out;
  for (const VxlFile& f : files) out.push_back(&f);
  return out;
}

void check_color_options(const std::string& path, const Renderer& r, const RenderSettings& s,
                         const ViewFileSettings& from_view_file) {
  // The option's error, or the view file's when it set the value: "--scalar: ..." or "FILE: settings.scalar: ...
  // in INPUT".
  auto refuse = [&](bool from_file, const std::string& option, const std::string& key, const std::string& what) {
    if (from_file)
      throw Error(ErrorKind::Input, from_view_file.path, std::nullopt, "settings." + key + ": " + what + " in " + path);
    throw Error(ErrorKind::Usage, path, std::nullopt, option + ": " + what);
  };
  const auto& names = r.value_set_names();
  std::string available;
  for (const std::string& n : names) available += (available.empty() ? "" : ", ") + n;
  if (s.color == ColorMode::Scalar && names.empty())
    refuse(from_view_file.color, "--color scalar", "color",
           "no per-point or per-streamline values to colour by (add a TSF with --tsf, or use a TRK with scalars or "
           "properties, a TRX with dpv or dps)");
  if (!s.scalar.empty() && std::find(names.begin(), names.end(), s.scalar) == names.end())
    refuse(from_view_file.scalar, "--scalar", "scalar",
           "no value set '" + s.scalar + "'" + (names.empty() ? " (it has none)" : " (it has: " + available + ")"));
  for (const GroupStyle& g : s.group_styles)
    if (r.groups().find(g.name) < 0) {
      std::string groups;
      for (const SceneGroup& sg : r.groups().groups()) groups += (groups.empty() ? "" : ", ") + sg.name;
      const auto& file_groups = from_view_file.groups;
      refuse(std::find(file_groups.begin(), file_groups.end(), g.name) != file_groups.end(), "--group", "groups",
             "no group '" + g.name + "' (groups: " + groups + ")");
    }
}

}  // namespace vxl::app
