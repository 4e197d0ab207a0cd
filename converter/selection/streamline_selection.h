// Virtual dissection: which streamlines of a .vxl pass a set of regions and length limits, with MRtrix
// tckedit's semantics (region.h for containment):
//
//   kept  when every include region contains at least one of the streamline's source points, every
//         ends-in region contains its first or its last point (tckedit's -include with -ends_only), no
//         exclude region contains any of its points, and its length (the sum of its segments' lengths)
//         passes tckedit's length thresholds (length_limits.h: the limits in float32, widened by the source
//         header's step_size, the length summed in float32); `invert` keeps exactly the others.
//   level  (optional, applied last, after `invert`) only those of that level of detail (spec §6.5: depth >= level,
//         about 1/8^level of them, spread over the whole tractogram): a whole tractogram made smaller alike
//         everywhere, e.g. to share one too large for a web browser.
//
// Points are the source points as the .vxl stores them (synthetic face points are not tested): bit for bit
// the source's with --positions float32, within the file's packed bound otherwise, so that a streamline
// whose deciding point lies within that bound of a region's surface may be decided differently from
// tckedit on the source file. Lengths are decided as tckedit decides them on the source: to the bit with float32
// positions (SLEN where it lies clearly on one side of a limit, the points measured otherwise); with packed
// positions from SLEN, the source points' length within a few float32 roundings of tckedit's.
//
// The voxel grid is the index: a region is tested only against the voxlines of the voxels whose bounds it
// may touch. With a VoxelVoxlines index (the file's VXIX, or one given) the streamlines crossing them are
// found from those voxels' lists alone, so that the cost follows the regions, not the file; without one
// (older files), by walking the voxline table (8 bytes a voxline, about a tenth of the source's bytes).
// Length limits read the lengths of the streamlines that pass the regions from the file's SLEN (4 bytes a
// streamline; their source points' lengths, format/streamline_length.h); files without SLEN have their
// points read instead, through the whole voxline table, as do the few float32 streamlines SLEN cannot decide.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "converter/selection/region.h"
#include "format/voxel_voxlines.h"
#include "format/vxl_file.h"

namespace vxl {

class LevelVoxlines;
class VoxlineBoxes;

struct SelectionCriteria {
  std::vector<Region> include, exclude, ends_in;
  std::optional<double> min_length, max_length;  // mm
  bool invert = false;
  std::optional<std::uint32_t> level;  // below the file's level count (Usage otherwise)
};

struct SelectionResult {
  std::vector<std::uint64_t> streamlines;  // the kept ones, increasing (source order)
  // What the query touched, for --verbose and the benchmark.
  std::uint32_t voxels_touched = 0;        // voxels some region may touch
  std::uint64_t points_tested = 0;         // vertices read for the regions
  std::uint64_t lengths_read = 0;          // SLEN lengths read for the length limits
  std::uint64_t streamlines_measured = 0;  // streamlines whose points were read for the length limits
  std::uint64_t bytes_read = 0;            // of the file: the tables walked and the vertices read
  // Per region (includes, then ends-in, then excludes, each in the order given): the streamlines it holds
  // a point of (ends-in: an end point), whatever the other criteria.
  std::vector<std::uint64_t> streamlines_per_region;
};

// At most this many regions in one selection (one bit each per streamline being tested).
inline constexpr std::size_t kMaxRegions = 64;

// Where the streamlines crossing the touched voxels are found: through an index when there is one (given, or
// the file's VXIX) and lengths in SLEN, or always by walking the voxline table, lengths measured from the stored
// points (tests and the benchmark compare both).
enum class SelectionPath { Fastest, ScanTable };

// Throws vxl::Error: Usage for more than kMaxRegions regions, min_length > max_length or a level the file has
// not, Input for a .vxl whose tables do not hold together or whose source header tckedit would refuse
// (length_limits.h). `index`, when given,
// must be VoxelVoxlines::of_file(file)'s: the result is the same with or without it (without it, the file's VXIX is
// used when it has one), and by either path. `boxes` (the file's, kept by a caller that selects again and again, as
// the window does while a region moves) lets a packed file's later selections pass over the voxlines they can
// decide from their boxes; the result is the same without it. `level_voxlines` (LevelVoxlines of criteria.level,
// which must be set) searches that level's voxlines alone, about 1/8^level of them: the same streamlines, and
// streamlines_per_region then counts that level's streamlines only (a viewer drawing that level needs no more).
SelectionResult select_streamlines(const VxlFile& file, const SelectionCriteria& criteria,
                                   const VoxelVoxlines* index = nullptr, SelectionPath path = SelectionPath::Fastest,
                                   VoxlineBoxes* boxes = nullptr, const LevelVoxlines* level_voxlines = nullptr);

// Asks the system to read ahead the tables a selection reads whole (VOXT, STRM, the voxel index VXIX or else the
// voxline table, SLEN): a window's first selection of a file not in the page cache then waits for those reads
// together, not for a page fault at a time (MappedFile::will_need).
void read_ahead_selection_tables(const VxlFile& file);

// Throws vxl::Error (Usage, naming `path`) unless `level` is one of the `levels` levels of detail of a file.
void check_level(const std::string& path, std::uint32_t level, std::uint32_t levels);

}  // namespace vxl
