#include "viewer/render/scene_groups.h"

#include <algorithm>
#include <filesystem>
#include <limits>

namespace vxl {

SceneGroups::SceneGroups(std::span<const VxlFile* const> files) {
  files_.resize(files.size());
  const auto file_name = [](const VxlFile& f) { return std::filesystem::path(f.path()).filename().string(); };
  if (files.size() != 1) {
    for (std::size_t i = 0; i < files.size(); ++i) {
      files_[i].constant = static_cast<std::uint32_t>(i);
      groups_.push_back({file_name(*files[i]), files[i]->meta().streamline_count});
    }
    return;
  }
  const VxlFile& f = *files[0];
  const std::vector<StreamlineGroup> stored = f.groups();
  const std::uint64_t n = f.meta().streamline_count;
  if (stored.empty()) {
    groups_.push_back({file_name(f), n});
    return;
  }
  constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t>& of = files_[0].of_streamline;
  of.assign(n, kNone);
  for (std::size_t g = 0; g < stored.size(); ++g) {
    groups_.push_back({stored[g].name, 0});
    for (std::uint64_t s : stored[g].members)
      if (of[s] == kNone) {
        of[s] = static_cast<std::uint32_t>(g);
        groups_[g].streamlines++;
      }
  }
  std::uint64_t ungrouped = 0;
  for (std::uint32_t& g : of)
    if (g == kNone) {
      g = static_cast<std::uint32_t>(stored.size());
      ++ungrouped;
    }
  if (ungrouped > 0) groups_.push_back({"(ungrouped)", ungrouped});
}

SceneGroups SceneGroups::selection(std::span<const VxlFile* const> files,
                                   const std::vector<std::vector<std::uint64_t>>& kept) {
  SceneGroups out;
  out.groups_ = {{kSelected, 0}, {kContext, 0}};
  out.files_.resize(files.size());
  for (std::size_t i = 0; i < files.size(); ++i) {
    const std::uint64_t n = files[i]->meta().streamline_count;
    out.files_[i].constant = 1;
    out.files_[i].members = kept[i];
    out.files_[i].members_group = 0;
    out.groups_[0].streamlines += kept[i].size();
    out.groups_[1].streamlines += n - kept[i].size();
  }
  return out;
}

SceneGroups SceneGroups::focus_first(std::span<const VxlFile* const> files, std::size_t context_files,
                                     const std::vector<std::vector<std::uint64_t>>& kept) {
  SceneGroups out = selection(files.first(context_files), kept);
  out.groups_.push_back({kSelectedInContext, out.groups_[0].streamlines, true});
  for (std::size_t i = 0; i < context_files; ++i) out.files_[i].members_group = 2;
  out.files_.resize(files.size());  // the copies: every streamline selected (constant group 0)
  out.groups_[0].streamlines = 0;
  for (std::size_t i = context_files; i < files.size(); ++i)
    out.groups_[0].streamlines += files[i]->meta().streamline_count;
  return out;
}

std::uint32_t SceneGroups::group_of(std::size_t file, std::uint64_t streamline) const {
  const PerFile& f = files_[file];
  if (!f.of_streamline.empty()) return f.of_streamline[streamline];
  return std::binary_search(f.members.begin(), f.members.end(), streamline) ? f.members_group : f.constant;
}

void SceneGroups::write_table(std::size_t file, std::span<std::uint8_t> out, std::uint32_t modulo) const {
  const PerFile& f = files_[file];
  if (!f.of_streamline.empty()) {
    for (std::size_t s = 0; s < out.size(); ++s) out[s] = static_cast<std::uint8_t>(f.of_streamline[s] % modulo);
    return;
  }
  std::fill(out.begin(), out.end(), static_cast<std::uint8_t>(f.constant % modulo));
  const auto member = static_cast<std::uint8_t>(f.members_group % modulo);
  for (std::uint64_t s : f.members) out[s] = member;
}

int SceneGroups::find(const std::string& name) const {
  for (std::size_t g = 0; g < groups_.size(); ++g)
    if (groups_[g].name == name) return static_cast<int>(g);
  return -1;
}

glm::vec3 group_palette(std::size_t g) {
  static const glm::vec3 kTab10[] = {{31, 119, 180}, {255, 127, 14},  {44, 160, 44},   {214, 39, 40},  {148, 103, 189},
                                     {140, 86, 75},  {227, 119, 194}, {127, 127, 127}, {188, 189, 34}, {23, 190, 207}};
  return kTab10[g % 10] / 255.0f;
}

}  // namespace vxl
