// The formats streamlines are written back to, by `voxlines export` and `voxlines select`, in one table: the
// file-name suffixes that choose each, and which of the two commands writes it (a .vxl only by select: export
// gives the source streamlines back, a selection may be converted again). Help texts and messages list the
// suffixes from here, so that they cannot disagree with what the commands accept.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace vxl {

enum class StreamlineOutput { Tck, Trx, Vtk, Trk, Vxl };

struct StreamlineOutputFormat {
  StreamlineOutput format;
  std::vector<std::string> suffixes;  // lower case, the longest first where one ends another
  bool exported;                      // `export` writes it (select writes every format)
  std::string keeps;                  // what the written file holds, for help texts
};
const std::vector<StreamlineOutputFormat>& streamline_outputs();

// The format `path`'s suffix names (case-insensitive), among those `export` writes when `exported_only`.
std::optional<StreamlineOutput> streamline_output_of(const std::string& path, bool exported_only);
// ".tck, .trx, .vtk, .trk, .trk.gz or .vxl" (without .vxl when `exported_only`), for help texts and messages.
std::string streamline_output_suffixes(bool exported_only);
// Each format with what it keeps: ".tck (...), .trx (...), ... or .vxl (...)", for an output's help text.
std::string streamline_output_help(bool exported_only);
// "OUT.tck|.trx|.vtk|.trk|.trk.gz|.vxl", for a usage line.
std::string streamline_output_usage(bool exported_only);

}  // namespace vxl
