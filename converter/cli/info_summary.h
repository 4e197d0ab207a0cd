// What `info` shows alike of a .vxl and of a .vxlz package: the header's version, META's counts and grid, and the
// provenance (PROV: the JSON a .vxl carries and a package ships deflated): the source it was converted from and how
// its voxel size was chosen.
#pragma once

#include <nlohmann/json.hpp>

#include "format/vxl_layout.h"

namespace vxl::cli {

// Adds "version", "streamlines", "points", "voxels", "voxlines", "voxel_size", "grid_dims", "bounds" and
// "stored_orders" to `info`.
void add_meta_summary(const FileHeader& header, const MetaSection& meta, nlohmann::json& info);

// Adds "source" ({name, format, bytes}) and "voxel_size_choice" to `info` where `provenance` holds them. PROV is any
// JSON as far as open() is concerned (verify checks only that it parses), so every field is read only when it has
// the expected type: a damaged provenance must not end `info` with a type error.
void add_provenance_summary(const nlohmann::json& provenance, nlohmann::json& info);

// The "source" line of `info`'s text, when `info` has a source.
void print_source_line(const nlohmann::json& info);

}  // namespace vxl::cli
