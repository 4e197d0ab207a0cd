// Rebuilds the source streamlines from a .vxl's voxel blocks by walking the voxline table (spec §5.6).
#pragma once

#include <cstdint>
#include <functional>
#include <span>

#include "format/vxl_file.h"

namespace vxl {

// One voxline as the walk meets it: where its vertices are and what it is to its streamline.
struct VoxlineVisit {
  std::uint64_t streamline;    // its streamline's index in the source
  std::uint32_t voxel;         // its voxel (index into VOXT)
  std::uint64_t first_vertex;  // global index in VERT of its first vertex
  std::uint32_t own_points;    // its own vertices (the connecting vertex, if any, follows them)
  bool synthetic_first;        // its first own vertex is a point inserted at a voxel face, not a source point
  bool first_of_streamline;    // it holds the streamline's first point
  bool connected;              // a connecting vertex follows (it is not the streamline's last voxline)
};

struct WalkCallbacks {
  // Called once per streamline whose points are read (see `read_points`), in order, with its source
  // points (synthetic face points dropped).
  std::function<void(std::uint64_t streamline, std::span<const float> xyz)> streamline;
  // Optional: called for every voxline, in table order, before the streamline callback of its streamline.
  std::function<void(const VoxlineVisit&)> voxline;
  // Optional: which streamlines' points are read and handed to `streamline` (default: all). The others
  // are walked through the table only (their vertices are not read), so a walk over a few streamlines
  // costs the table plus their points.
  std::function<bool(std::uint64_t streamline)> read_points;
  // Threads that decode the points (0: all cores). The callbacks are called one at a time and in order
  // whatever this is, though not always on the calling thread.
  unsigned threads = 1;
};

// Checks the walk as it goes (table ranges, blocks consumed exactly, connecting vertices equal to the
// next voxline's first vertex for the streamlines read, totals matching META) and throws vxl::Error
// (Input) on any inconsistency.
void walk_streamlines(const VxlFile& file, const WalkCallbacks& callbacks);

}  // namespace vxl
