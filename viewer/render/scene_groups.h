// Which group each streamline belongs to, for colour and opacity per group (--color group, --group):
//
//   several files shown together  one group per file, named after the file;
//   one file with groups (GRPS)    its groups (TRX bundles); a streamline listed in several takes the
//                                  first that lists it; those in none form a last group, "(ungrouped)";
//   one file without groups        one group, named after the file;
//   a selection (voxlines select's rules, one kept list per file)
//                                  two groups, "selected" (the focus) and "context" (every other streamline),
//                                  whatever the files' own groups;
//   a selection drawn focus first  the same two, the focus drawn from its own full-detail files (the
//                                  scene's last files, viewer_session.h), and a third, hidden group: the
//                                  selected streamlines in the context's files, drawn once only.
//
// Group g gets palette colour g (matplotlib's tab10, repeating) unless the user chose one.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "format/vxl_file.h"

namespace vxl {

struct SceneGroup {
  std::string name;
  std::uint64_t streamlines = 0;
  bool hidden = false;  // never drawn, whatever its style (drawn from another file instead)
};

class SceneGroups {
 public:
  SceneGroups() = default;
  // Reads GRPS (throws vxl::Error naming the file when it is malformed).
  explicit SceneGroups(std::span<const VxlFile* const> files);
  // The focus and context of a selection: `kept[i]` lists file i's selected streamlines (increasing).
  static SceneGroups selection(std::span<const VxlFile* const> files,
                               const std::vector<std::vector<std::uint64_t>>& kept);
  // The focus drawn first (at full detail): files[0, context_files) are the scene's own files at the context's
  // level, files[context_files, ...) the selection's full-detail copies, one per file with a selected
  // streamline, in file order (all of theirs selected).
  static SceneGroups focus_first(std::span<const VxlFile* const> files, std::size_t context_files,
                                 const std::vector<std::vector<std::uint64_t>>& kept);
  static constexpr const char* kSelected = "selected";
  static constexpr const char* kContext = "context";
  static constexpr const char* kSelectedInContext = "selected (drawn from its full-detail copy)";

  const std::vector<SceneGroup>& groups() const { return groups_; }
  std::uint32_t group_of(std::size_t file, std::uint64_t streamline) const;
  // Whether every streamline of `file` is in one group (no per-streamline lookup needed).
  bool uniform(std::size_t file) const { return files_[file].of_streamline.empty() && files_[file].members.empty(); }
  // Writes each of `file`'s streamlines' group modulo `modulo` to out[0 .. streamline count): the table the
  // renderer uploads (one plain pass, 10^7 streamlines at each selection).
  void write_table(std::size_t file, std::span<std::uint8_t> out, std::uint32_t modulo) const;
  int find(const std::string& name) const;

 private:
  // A file's streamlines are in `constant`, but for those listed in `of_streamline` (a group per streamline: a
  // file's own groups) or in `members` (increasing: a selection's, in `members_group`). A selection lists its kept
  // streamlines rather than a group per streamline: a few hundred thousand against 4 bytes for each of 10^7,
  // made anew at every position of a dragged region.
  struct PerFile {
    std::uint32_t constant = 0;
    std::vector<std::uint32_t> of_streamline;
    std::vector<std::uint64_t> members;
    std::uint32_t members_group = 0;
  };
  std::vector<SceneGroup> groups_;
  std::vector<PerFile> files_;
};

// Palette colour of group g.
glm::vec3 group_palette(std::size_t g);

}  // namespace vxl
