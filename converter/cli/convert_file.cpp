#include "converter/cli/convert_file.h"

#include <cstdio>

#include "converter/convert/source_to_vxl.h"
#include "format/base/memory_size.h"

namespace vxl::cli {

std::string convert_file(const std::string& input, const std::string& output, const std::vector<std::string>& tsf,
                         const ConvertSettings& settings, bool verbose,
                         const std::function<void(const std::string&)>& warn, unsigned concurrent_files) {
  SourceConversion conversion{settings, tsf, concurrent_files, warn,
                              [](const std::string& line) { std::fprintf(stderr, "voxlines: %s\n", line.c_str()); }};
  const SourceConversionReport r = convert_source(input, output, conversion);
  const ConvertSummary& s = r.summary;
  char line[512];
  std::snprintf(line, sizeof line,
                ": %llu streamlines, %llu points -> %llu voxels, %llu segments (%llu points added at voxel faces)\n",
                (unsigned long long)s.streamlines, (unsigned long long)s.points, (unsigned long long)s.voxels,
                (unsigned long long)s.segments, (unsigned long long)s.synthetic_points);
  std::string report = output + line;
  if (r.streamed) {
    std::snprintf(line, sizeof line, "memory limit %s: %llu passes over the source, voxels built in %llu part%s%s\n",
                  format_memory_size(r.memory_limit).c_str(), (unsigned long long)s.passes,
                  (unsigned long long)s.partitions, s.partitions == 1 ? "" : "s",
                  s.vertices_read_back ? " (vertex blocks written as placed and read back for the orders)" : "");
    report += line;
  }
  if (verbose) {
    std::snprintf(line, sizeof line, "stages: read %.3f s, voxelise %.3f s, orders %.3f s, write %.3f s\n",
                  r.read_seconds, s.voxelize_seconds, s.orders_seconds, s.write_seconds);
    report += line;
  }
  return report;
}

}  // namespace vxl::cli
