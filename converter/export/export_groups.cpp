#include "converter/export/export_groups.h"

#include <algorithm>
#include <filesystem>
#include <set>

#include "format/base/error.h"

namespace vxl {
namespace {

std::string lower_case(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

}  // namespace

std::vector<std::string> group_file_names(const std::vector<StreamlineGroup>& groups) {
  std::vector<std::string> out;
  std::set<std::string> taken;  // lower case: a case-insensitive file system would merge "A" and "a"
  for (const StreamlineGroup& g : groups) {
    std::string name = g.name;
    for (char& c : name)
      if (c == '/' || c == '\\' || static_cast<unsigned char>(c) < ' ' || c == 127) c = '_';
    if (name.empty() || name.front() == '.') name = "_" + name;
    if (name.size() > kMaxGroupFileNameBytes) {
      std::size_t cut = kMaxGroupFileNameBytes;
      while (cut > 0 && (static_cast<unsigned char>(name[cut]) & 0xC0) == 0x80) --cut;  // not inside a character
      name.resize(cut);
    }
    std::string unique = name;
    for (int k = 2; taken.contains(lower_case(unique)); ++k) unique = name + "_" + std::to_string(k);
    taken.insert(lower_case(unique));
    out.push_back(unique);
  }
  return out;
}

std::vector<SplitGroupFile> export_tck_per_group(const VxlFile& file, const std::string& dir,
                                                 const std::optional<std::string>& value) {
  const std::vector<StreamlineGroup> groups = file.groups();
  if (groups.empty())
    throw Error(ErrorKind::Usage, file.path(), std::nullopt, "has no groups to split (--split-groups)");
  std::error_code ec;
  std::filesystem::create_directory(dir, ec);
  if (ec || !std::filesystem::is_directory(dir))
    throw Error(ErrorKind::Output, dir, std::nullopt,
                "cannot be made a folder for the groups' files" + (ec ? ": " + ec.message() : std::string()));
  const std::vector<std::string> names = group_file_names(groups);
  std::vector<SplitGroupFile> out;
  for (std::size_t i = 0; i < groups.size(); ++i) {
    SplitGroupFile f;
    f.group = groups[i].name;
    f.tck = (std::filesystem::path(dir) / (names[i] + ".tck")).string();
    TckExportSettings settings;
    settings.group = groups[i].name;
    if (value) {
      f.tsf = (std::filesystem::path(dir) / (names[i] + ".tsf")).string();
      settings.tsf_path = f.tsf;
      settings.value = value;
    }
    f.summary = export_tck(file, f.tck, settings);
    out.push_back(std::move(f));
  }
  return out;
}

}  // namespace vxl
