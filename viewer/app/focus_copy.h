// A selection's focus as full-detail files of its own, so that under a GPU memory budget the focus is drawn
// at level 0 while the context is drawn coarser (README "Virtual dissection", docs/rendering.md#focus-first).
//
// Why a copy rather than the context's files at level 0: a file's level is one per layout span, and the
// selected streamlines of a large file lie in nearly every voxel, so drawing them at full detail from the
// file itself would upload most of the file at level 0 — what the budget forbids. A copy holds only the
// selected streamlines; beside the context's files in one SceneLayout (each file at its own level) it is
// sorted with them, voxel by voxel, in the one back-to-front pass every mode draws, as several files are.
// The copy is `voxlines select`'s .vxl output (selection_output.h: the input's voxel size, orders, position
// encoding and levels), written to a temporary file, mapped, and unlinked at once: nothing stays on disk.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "format/vxl_file.h"

namespace vxl::app {

class FocusCopy {
 public:
  // One copy per file with a selected streamline (kept[i]: file i's, increasing), in file order. Throws
  // vxl::Error when a copy cannot be written or read back.
  FocusCopy(std::span<const VxlFile* const> files, const std::vector<std::vector<std::uint64_t>>& kept);
  FocusCopy(const FocusCopy&) = delete;
  FocusCopy& operator=(const FocusCopy&) = delete;

  const std::vector<const VxlFile*>& files() const { return pointers_; }

 private:
  std::vector<VxlFile> copies_;
  std::vector<const VxlFile*> pointers_;
};

}  // namespace vxl::app
