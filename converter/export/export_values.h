// The value sets of a .vxl as export writes them: per source point (synthetic face points and
// connecting vertices dropped, the order of walk_streamlines) and per streamline, and as TRX members.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "converter/export/streamline_subset.h"
#include "format/vxl_file.h"

namespace vxl {

// The VERT index of every source point, streamline after streamline (meta().point_count entries), of the
// subset's streamlines only when there is one. Throws vxl::Error (Input) for an inconsistent .vxl, as
// walk_streamlines does.
std::vector<std::uint64_t> source_vertex_indices(const VxlFile& file, const StreamlineSubset* subset = nullptr);

// VVAL set `set` at the given vertices.
std::vector<float> values_at(const VxlFile& file, std::uint32_t set, const std::vector<std::uint64_t>& vertices);

// The sets as runs: NAME[0], NAME[1], … NAME[m-1] in a row (how the readers split a multi-component
// TRX, TRK or VTK array, .vxl spec §5.11) as one run {NAME, first set, m}; every other set a run of one
// under its own name (a lone NAME[0] too).
struct ValueSetRun {
  std::string name;
  std::uint32_t first = 0, components = 1;
};
std::vector<ValueSetRun> value_set_runs(const ValueSets& sets);

struct TrxValueMember {
  std::string name;         // "dpv/NAME.float32", "dps/NAME.3.float32", ...
  std::vector<float> data;  // row-major: one row of `components` values per point or streamline
};

// Whether `name` (a group's or a value set's) can name a TRX member FOLDER/NAME.SUFFIX: one file inside the folder
// (not empty, not "." or "..", no '/', '\\' or NUL) whose path fits the zip's 16-bit name length.
bool usable_trx_member_name(const std::string& name, const std::string& folder, const std::string& suffix);

// The dpv (from VVAL) and dps (from SVAL) members of a TRX. Sets named NAME[0], NAME[1], … NAME[m-1] in a
// row (how the readers split a multi-component TRX array, .vxl spec §5.11) become one NAME.m.float32
// member again. Throws vxl::Error (Unsupported) for a name that cannot be a member name.
std::vector<TrxValueMember> trx_value_members(const VxlFile& file, const StreamlineSubset* subset = nullptr);

}  // namespace vxl
