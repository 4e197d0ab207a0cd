// One way to turn a source tractogram (readers/source_formats.h) into a .vxl, for both programs: `voxlines
// convert` writes it to the output it is given (convert_source), `voxview` opens it through a temporary file
// (open_as_vxl). Every conversion runs the same passes within a memory limit (streaming_convert.h):
//
//   * a TCK without TSF values is read from its file pass after pass (streamed) within the limit given
//     (settings.memory_limit > 0), or else the one memory_choice.h chooses from its size and its share of the
//     available memory (`concurrent_files` conversions at once); `notice` says when that share is too small
//     for what the source wants;
//   * other formats, and a TCK with TSF values, are read whole first and converted from memory (convert.h);
//     a memory limit is refused for them.
//
// Either way the output's bytes are the same.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "converter/convert/convert.h"
#include "format/vxl_file.h"

namespace vxl {

struct SourceConversion {
  // settings.memory_limit: the limit to stream within; 0 chooses (see above).
  ConvertSettings settings;
  std::vector<std::string> tsf;   // MRtrix track scalar files attached to the source (in memory only)
  unsigned concurrent_files = 1;  // conversions sharing the available memory at once
  // Each warning of the source or of the conversion, without the file's name, as soon as it is known.
  std::function<void(const std::string&)> warn;
  // That the memory available limits a conversion without --memory-limit, as a line naming the source (without a
  // program name).
  std::function<void(const std::string&)> notice;
};

struct SourceConversionReport {
  ConvertSummary summary;
  double read_seconds = 0;         // reading the source (in memory), or the first pass over it (streamed)
  bool streamed = false;           // read from its file several times (a TCK), not held in memory
  std::uint64_t memory_limit = 0;  // the limit it streamed within, given or chosen; 0 when held in memory
};

// Converts `input` into `output` (written atomically: nothing is left at `output` on failure). Throws vxl::Error.
SourceConversionReport convert_source(const std::string& input, const std::string& output,
                                      const SourceConversion& conversion);

struct OpenedSource {
  VxlFile file;
  SourceConversionReport report;
  std::string temporary_path;  // where the .vxl was written; already removed
  // The temporary folder is a RAM file system (tmpfs): the mapped .vxl takes memory, streamed or not.
  bool temporary_in_ram = false;
};

// Converts `input` as convert_source does into a temporary .vxl in `temporary_dir` (temporary_vxl.h: empty is
// the system's temporary folder, $TMPDIR or else /tmp; a fresh name "voxlines-XXXXXX-NAME.vxl"), maps it and
// removes it at once: the mapping keeps the data, and nothing is left behind, also when the conversion or the
// opening fails. A streamed conversion's .vxl lives in that folder's file system while it is mapped (its
// pages can be evicted, unlike a conversion in memory): where /tmp is a RAM file system (tmpfs), set TMPDIR
// to a folder on disk for sources larger than the memory. Throws vxl::Error.
OpenedSource open_as_vxl(const std::string& input, const SourceConversion& conversion,
                         const std::string& temporary_dir = {});

}  // namespace vxl
