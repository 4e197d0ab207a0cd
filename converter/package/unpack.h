// `voxlines unpack`: a .vxlz package back to a .vxl (spec/vxlz-package-v2.md §7). The package is the source of
// a conversion whose voxelisation is given: the tables are taken as shipped (never re-voxelised: quantisation
// could move a point across a voxel face), the position chunks are decoded in parallel into the vertex blocks,
// the connecting vertices written as copies of the decoded next points, the tight bounds set from the decoded
// vertices, and the blocks packed, ordered (the conversion's orders stage, pipeline/range_orders.h) and written
// (VxlStreamWriter) as a conversion's are. The value sets come back bit-exact, per vertex as the converter laid
// them out. The result passes `voxlines verify`.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "converter/convert/voxelize.h"
#include "format/vxl_levels.h"
#include "format/vxl_positions.h"
#include "format/vxlz_layout.h"
#include "format/vxlz_package.h"

namespace vxl {

struct UnpackSettings {
  unsigned threads = 0;                                   // 0: all cores
  PositionEncoding positions = PositionEncoding::Packed;  // of the .vxl written (spec §5.4)
  // Levels of detail of the .vxl written (spec §5.12), 1 .. kMaxLevels; 0: the package's own (package_levels).
  std::uint32_t levels = 0;
  ProgressFn progress;  // stages "decoding", "ordering", "writing"; may be empty
  // > 0: only the streamlines of this level of the package's level order (spec §5.1, predictor 2), as a file of
  // their own without levels (the first look a viewer gets while the rest arrives); only the chunks that hold them
  // need be there (VxlzFile::open_prefix). Without groups and value sets.
  std::uint32_t level = 0;
  // What the decoded positions may take (0: half of the available memory): a packed .vxl's are kept as floats for one
  // decode of the chunks where they fit in it (12 bytes a vertex), else the chunks are decoded twice
  // (unpack_positions.h). A packed .vxl's whole VERT is held in memory where it takes at most half of it; else (or with
  // vertex_blocks) it is written block by block as the second decode goes and read back a chunk of voxels at a time for
  // the orders (write_positions_in_blocks), as a conversion under a tight limit does — where the package's shipping
  // order fills the blocks in order: streamline order, or level order unpacked with at least the levels it ships by
  // (`levels` >= PACK.level_count), and where the blocks' stagings take less than a quarter of VERT; else VERT is held
  // whole.
  std::uint64_t memory_limit = 0;
  bool vertex_blocks = false;
};

struct UnpackSummary {
  std::uint64_t streamlines = 0, points = 0, voxels = 0;
  PackSection pack{};             // quantisation and the stated bound
  double repack_error_bound = 0;  // of the packed positions written (0 for float32), per axis, in mm
  // How far, per axis, a written position may lie from the packed .vxl's: the package's quantisation
  // and then the output's own packing.
  double error_bound() const { return pack.error_bound + repack_error_bound; }
  std::uint32_t point_value_sets = 0, streamline_value_sets = 0;  // VVAL / SVAL written, bit-exact
  // decode: the package read, the positions decoded, each voxel's bounds set and its block packed; orders: the
  // orders built and written; write: the tables after them.
  double decode_seconds = 0, orders_seconds = 0, write_seconds = 0;
  bool decoded_twice = false;       // the positions did not fit UnpackSettings::memory_limit as floats
  bool vertices_read_back = false;  // VERT written block by block and read back for the orders
};

// Validates the whole package (spec §8) and writes `out_path` atomically: a refused package leaves
// nothing at the output path. Throws vxl::Error (Input for a damaged package, naming the file, the byte
// offset and what was expected; Unsupported for a newer version; Output).
UnpackSummary unpack_vxlz(const std::string& in_path, const std::string& out_path, const UnpackSettings& settings);
UnpackSummary unpack_vxlz(const VxlzFile& package, const std::string& out_path, const UnpackSettings& settings);
// The same, the package let go of once its positions are decoded: where it was read into memory (the web page's), its
// memory goes before the tables and the orders take theirs.
UnpackSummary unpack_vxlz(VxlzFile&& package, const std::string& out_path, const UnpackSettings& settings);

// The levels of detail of the .vxl a package was packed from: PACK.level_count in level order; in streamline order
// (a file without levels, or any file packed by a writer older than 2.3), the levels its conversion asked for as its
// PROV records them, else kDefaultLevels.
std::uint32_t package_levels(const VxlzFile& package);

// The size in bytes of the .vxl unpack_vxlz would write with `settings` (its levels, positions, level), from the
// package's tables alone: no position is decoded, nor a value (of a value section only its set count is read).
// Throws what unpack_vxlz throws for damaged or unsupported tables.
std::uint64_t unpacked_vxl_bytes(const VxlzFile& package, const UnpackSettings& settings);

// A package's levels as it ships them (spec §5.1): for each level d of its level order, from the coarsest, the
// streamlines and shipped points of depth d or more, and the bytes of the package (a prefix) that hold them. Empty
// for a package in streamline order. Reads the tables of the exact part only (a prefix will do).
struct ShippedLevel {
  std::uint32_t level = 0;
  std::uint64_t streamlines = 0, points = 0, bytes = 0;
};
std::vector<ShippedLevel> shipped_levels(const VxlzFile& package);

}  // namespace vxl
