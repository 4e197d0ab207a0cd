// One way to turn a source tractogram (readers/source_formats.h) into a .vxl, for both programs: `voxlines
// convert` writes it to the output it is given (convert_source), `voxview` opens it through a temporary file
// (open_as_vxl). Both follow one policy, so that a source too big for memory streams in either program:
//
//   * with a memory limit (settings.memory_limit > 0) the source is streamed within it (streaming_convert.h;
//     TCK only, refused for other formats and with TSF values);
//   * without one, a TCK whose conversion in memory would not fit in the available memory
//     (memory_choice.h, shared by `concurrent_files` conversions at once) is streamed within a limit that
//     fits, and `notice` says so; everything else is converted in memory (convert.h).
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
  // The choice to stream a source without a limit, as a line naming the source (without a program name).
  std::function<void(const std::string&)> notice;
};

struct SourceConversionReport {
  ConvertSummary summary;
  double read_seconds = 0;         // reading the source (in memory), or the first pass over it (streamed)
  bool streamed = false;           // through convert_streaming, the source read several times
  std::uint64_t memory_limit = 0;  // the limit it streamed within, given or chosen; 0 in memory
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
