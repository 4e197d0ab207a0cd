// Conversion in bounded memory (voxlines convert --memory-limit SIZE), for tractograms larger than the
// memory at hand. It writes exactly the bytes convert_tractogram writes for the same source and settings
// (the limit is not recorded), reading the source several times instead of holding it:
//
//   pass 1    bounds, checksum, warnings and the longest streamline                 (TckStream)
//   pass 2    voxelise every streamline, keeping only the counts and tight bounds per voxel
//             -> voxel table, layout
//   then      cut the voxel table into ranges whose vertex blocks (packed as they are placed: 4 bytes a
//             vertex) fit in what the limit leaves
//   pass 2+k  voxelise again, pack and place the vertices that fall in range k, then build their orders a
//             chunk of voxels at a time, and write both at their final offsets (VxlStreamWriter); pass 3
//             also writes the voxline and streamline tables
//
// With direct writes and few enough (voxel, level) blocks, VERT is not held at all: each block is
// written through a small staging of its own as it is placed, and read back a chunk at a time for the
// orders (one range, 3 passes for any size of source).
//
// Every pass cuts its batches in parts that share the threads with the next batch's read (the placing pass
// places in streamline order, one batch behind). What stays in memory: the voxel table (about 240 bytes per voxel),
// each streamline's length (4 bytes), its voxel runs where they fit (8 bytes a voxline: the placing passes then do not
// voxelise again), one part of the source read into a buffer and two batches of whole streamlines, two batches' staged
// voxlines, one range's blocks (or, written block by block, their stagings and then two chunks of them read
// back), an orders chunk or two and the sort buffers; the voxel index's lists while the first range is placed, where
// they fit (else, at the end, a buffer to sort them in). The source is read a part at a time (pread); the output is
// written with pwrite, or past the page cache (O_DIRECT) under limits of 256 MiB or more, so neither
// stays in resident memory. Only TCK sources stream.
#pragma once

#include <cstdint>
#include <string>

#include "converter/convert/convert.h"
#include "converter/pipeline/conversion_plan.h"

namespace vxl {

// Converts the TCK file `source_path` to `out_path` (atomically) using at most settings.memory_limit
// bytes (> 0). Throws vxl::Error: Unsupported for a source other than TCK, and when the limit is too
// small for some part of the work — naming the part, what it needs and a limit that would do — before
// anything is written; Input when the source changes between passes; as convert_tractogram otherwise.
// The summary's passes and partitions say how the work was split; its warnings are the source's.
ConvertSummary convert_streaming(const std::string& source_path, const std::string& out_path,
                                 const ConvertSettings& settings);

ConvertSummary convert_streaming(const std::string& source_path, const std::string& out_path,
                                 const ConvertSettings& settings, const StreamingTuning& tuning);

// Converts a source already in memory by the same passes, reading it a batch at a time (TractogramBatchSource)
// within settings.memory_limit (> 0; the tractogram itself not counted), with its value sets and groups, which
// must be prepared as convert_tractogram prepares them. The summary has no warnings (the reader's are in `held`).
ConvertSummary convert_streaming(const Tractogram& held, const std::string& out_path, const ConvertSettings& settings,
                                 const StreamingTuning& tuning = {});

}  // namespace vxl
