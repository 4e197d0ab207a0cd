// One conversion IN -> OUT.vxl, shared by `voxlines convert IN OUT.vxl` and the cohort form
// (convert_cohort.h): converts through convert_source (converter/convert/source_to_vxl.h, which decides whether the
// source streams, as voxview's opening of a source does) and describes the result.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "converter/convert/convert.h"

namespace vxl::cli {

// Converts `input` into `output` (written atomically) and returns the lines to print on stdout: the counts,
// the passes under a memory limit and, with `verbose`, the stage times. Each warning of the source is
// handed to `warn` (without the file's name) as soon as it is known. Without a memory limit, a TCK whose
// conversion in memory would not fit in the available memory (convert/memory_choice.h; shared by
// `concurrent_files` conversions) is streamed under a limit that fits, and a line on stderr says so
// ("voxlines: IN: converting in memory would take ...").
// Throws vxl::Error.
std::string convert_file(const std::string& input, const std::string& output, const std::vector<std::string>& tsf,
                         const ConvertSettings& settings, bool verbose,
                         const std::function<void(const std::string&)>& warn, unsigned concurrent_files = 1);

}  // namespace vxl::cli
