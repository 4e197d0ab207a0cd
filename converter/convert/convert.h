// The conversion pipeline: tractogram -> voxel blocks -> orders -> .vxl (with provenance).
#pragma once

#include <string>
#include <vector>

#include "converter/convert/voxelize.h"
#include "converter/tractogram.h"
#include "format/vxl_levels.h"
#include "format/vxl_positions.h"

namespace vxl {

struct ConvertSettings {
  double voxel_size = 10.0;  // mm; the paper's balance of speed and quality
  // Choose the voxel size from the data instead (voxel_size_auto.h); the choice is recorded in PROV.
  bool voxel_size_auto = false;
  unsigned threads = 0;  // 0: all hardware threads
  std::string orders = "axis";
  // Packed: 4 bytes per vertex within packed_error_bound (spec §5.4); float32: the source's bits exactly.
  PositionEncoding positions = PositionEncoding::Packed;
  // Levels of detail (spec §5.12): 1 .. kMaxLevels; 1 writes none.
  std::uint32_t levels = kDefaultLevels;
  ProgressFn progress;
  // Bytes of memory the conversion's passes may use (streaming_convert.h); 0: chosen from the source's size and the
  // memory available (memory_choice.h). Not recorded in the output: every limit writes the same bytes.
  std::uint64_t memory_limit = 0;
};

struct ConvertSummary {
  std::uint64_t streamlines = 0, points = 0, voxels = 0, vertices = 0, segments = 0, synthetic_points = 0;
  double voxelize_seconds = 0, orders_seconds = 0, write_seconds = 0;
  double read_seconds = 0;                      // the first pass over the source
  std::uint64_t passes = 1;                     // times the source was read
  std::uint64_t partitions = 1;                 // voxel ranges whose blocks and orders were built one after another
  std::vector<std::uint64_t> partition_starts;  // the first voxel of each range
  bool vertices_read_back = false;              // VERT written block by block, not held
  // the placing passes cut the streamlines by the voxel runs the counting pass kept
  // (false: they voxelised again, the limit leaving no room for the runs).
  bool voxelised_once = false;
  // the voxel index's lists were filled as the first range was placed (false: sorted at
  // the write stage from the voxline and streamline tables read back, the limit leaving no room to hold them).
  bool voxel_index_while_placing = false;
  // convert_streaming from a file: the source's; convert_tractogram: the conversion's own (the reader's are in the
  // Tractogram, for its caller to show).
  std::vector<std::string> warnings;

  // The counts, as written in the file's META.
  void take_counts(const MetaSection& meta) {
    streamlines = meta.streamline_count;
    points = meta.point_count;
    voxels = meta.voxel_count;
    vertices = meta.vertex_count;
    segments = meta.segment_count;
    synthetic_points = meta.synthetic_point_count;
  }
};

// Converts a tractogram read whole (its value sets checked and named as every reader of the file accepts, its
// groups kept) by the passes of streaming_convert.h, reading it from memory a batch at a time, and writes
// `out_path` atomically. settings.memory_limit bounds what the passes take besides the tractogram (0: chosen
// for its size). Throws vxl::Error.
ConvertSummary convert_tractogram(Tractogram&& tractogram, const std::string& out_path,
                                  const ConvertSettings& settings);

// The PROV payload (spec §5.8) for a source converted with these settings; `voxel_size_choice`: why --voxel-size
// auto chose settings.voxel_size (empty: it was given). Nothing of the machine (threads, memory limit) goes in, so
// that the same source and options give the same bytes everywhere.
std::string provenance_json(const SourceInfo& source, const ConvertSettings& settings,
                            const std::string& voxel_size_choice = {});

}  // namespace vxl
