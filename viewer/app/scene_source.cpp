#include "viewer/app/scene_source.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>

#include "converter/convert/temporary_vxl.h"
#include "converter/package/unpack.h"
#include "format/base/error.h"
#include "format/base/file_suffix.h"
#include "format/base/memory_size.h"
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

// A package is unpacked into a temporary .vxl removed at once: the mapping keeps it alive, nothing is left.
VxlFile open_package(const std::string& path, bool verify) {
  return open_through_temporary_vxl(path,
                                    [&](const std::string& temporary) {
                                      unpack_vxlz(path, temporary, {});
                                      if (verify) verify_or_refuse(temporary, path);
                                    })
      .file;
}

// How the source was converted, and the command that converts it once so that it opens instantly.
void print_convert_hint(const std::string& path, const SceneSourceOptions& options,
                        const SourceConversionReport& report) {
  std::string how = "in memory", options_text;
  if (report.streamed) {
    how = "streamed within " + format_memory_size(report.memory_limit) + " of memory (" +
          std::to_string(report.summary.passes) + " passes over the source)";
    if (options.memory_limit > 0) options_text += " --memory-limit " + memory_limit_argument(options.memory_limit);
  }
  if (options.voxel_size_auto) {
    options_text += " --voxel-size auto";
  } else if (options.voxel_size != 10.0) {
    char size[64];
    std::snprintf(size, sizeof size, " --voxel-size %g", options.voxel_size);
    options_text += size;
  }
  for (const std::string& f : options.tsf) options_text += " --tsf '" + f + "'";
  std::fprintf(stderr,
               "voxview: converted %s %s. To reopen it instantly, convert once:\n"
               "  voxlines convert '%s' '%s.vxl'%s\n",
               path.c_str(), how.c_str(), path.c_str(), std::filesystem::path(path).stem().string().c_str(),
               options_text.c_str());
}

}  // namespace

SceneSourceOptions scene_source_options(const ViewerOptions& o) {
  return {o.voxel_size, o.voxel_size_auto, o.tsf, o.verify, o.memory_limit};
}

bool opens_without_conversion(const std::string& path) {
  return has_suffix_ignoring_case(path, ".vxl") || has_suffix_ignoring_case(path, ".vxlz");
}

OpenedScene open_scene(const std::string& path, const SceneSourceOptions& options) {
  if (!options.tsf.empty() && opens_without_conversion(path))
    throw Error(ErrorKind::Usage, path, std::nullopt,
                "--tsf adds values to a source tractogram as it is converted; a .vxl keeps the values it was converted "
                "with (voxlines convert IN.tck OUT.vxl --tsf FILE.tsf)");
  if (has_suffix_ignoring_case(path, ".vxl")) {
    if (options.verify) verify_or_refuse(path, path);
    return {VxlFile::open(path), std::nullopt};
  }
  if (has_suffix_ignoring_case(path, ".vxlz")) return {open_package(path, options.verify), std::nullopt};

  SourceConversion conversion;
  conversion.settings.voxel_size = options.voxel_size;
  conversion.settings.voxel_size_auto = options.voxel_size_auto;
  conversion.settings.memory_limit = options.memory_limit;
  conversion.tsf = options.tsf;
  conversion.warn = [&](const std::string& w) {
    std::fprintf(stderr, "voxview: warning: %s: %s\n", path.c_str(), w.c_str());
  };
  conversion.notice = [](const std::string& line) { std::fprintf(stderr, "voxview: %s\n", line.c_str()); };
  OpenedSource opened = open_as_vxl(path, conversion);
  print_convert_hint(path, options, opened.report);
  if (opened.report.streamed && opened.temporary_in_ram)
    std::fprintf(stderr,
                 "voxview: note: the temporary .vxl is in a RAM file system (tmpfs, %s): it takes memory while "
                 "shown; set TMPDIR to a folder on disk, or convert once as above\n",
                 std::filesystem::path(opened.temporary_path).parent_path().c_str());
  return {std::move(opened.file), std::move(opened.report)};
}

std::vector<VxlFile> open_scenes(const std::vector<std::string>& paths, const SceneSourceOptions& options) {
  if (!options.tsf.empty() && paths.size() != 1)
    throw Error(ErrorKind::Usage, "", std::nullopt,
                "--tsf needs a single input tractogram (it has one value per point of that file); convert each with "
                "voxlines convert IN.tck OUT.vxl --tsf FILE.tsf and open the .vxl files together");
  std::vector<VxlFile> files;
  for (const std::string& p : paths) files.push_back(open_scene(p, options).file);
  return files;
}

std::vector<const VxlFile*> pointers(const std::vector<VxlFile>& files) {
  std::vector<const VxlFile*> out;
  for (const VxlFile& f : files) out.push_back(&f);
  return out;
}

void check_color_options(const std::string& path, const Renderer& r, const RenderSettings& s,
                         const ViewFileSettings& from_view_file, const std::vector<std::string>& groups_to_come) {
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
  // A .vxl's or a package's values were fixed when it was converted: --tsf cannot add them here.
  const std::string add_values =
      opens_without_conversion(path)
          ? "convert its source again with them: voxlines convert SOURCE OUT.vxl --tsf FILE.tsf, or from a TRK with "
            "scalars or properties, a TRX with dpv or dps"
          : "add a TSF with --tsf, or use a TRK with scalars or properties, a TRX with dpv or dps";
  if (s.color == ColorMode::Scalar && names.empty())
    refuse(from_view_file.color, "--color scalar", "color",
           "no per-point or per-streamline values to colour by (" + add_values + ")");
  if (!s.scalar.empty() && std::find(names.begin(), names.end(), s.scalar) == names.end())
    refuse(from_view_file.scalar, "--scalar", "scalar",
           "no value set '" + s.scalar + "'" + (names.empty() ? " (it has none)" : " (it has: " + available + ")"));
  std::vector<std::string> group_names = groups_to_come;
  if (group_names.empty())
    for (const SceneGroup& sg : r.groups().groups()) group_names.push_back(sg.name);
  for (const GroupStyle& g : s.group_styles)
    if (std::find(group_names.begin(), group_names.end(), g.name) == group_names.end()) {
      std::string groups;
      for (const std::string& name : group_names) groups += (groups.empty() ? "" : ", ") + name;
      const auto& file_groups = from_view_file.groups;
      refuse(std::find(file_groups.begin(), file_groups.end(), g.name) != file_groups.end(), "--group", "groups",
             "no group '" + g.name + "' (groups: " + groups + ")");
    }
}

}  // namespace vxl::app
