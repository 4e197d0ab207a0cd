#include "converter/cli/convert_file.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <filesystem>

#include "converter/memory_available.h"
#include "converter/memory_size.h"
#include "converter/readers/read_tractogram.h"
#include "converter/readers/read_tsf.h"
#include "converter/readers/source_formats.h"
#include "converter/streaming_convert.h"
#include "format/error.h"

namespace vxl::cli {
namespace {

bool is_streamable(const std::string& path) {
  const SourceMatch match = source_format_of(path);
  return match.format && match.format->streamable;
}

}  // namespace

std::string convert_file(const std::string& input, const std::string& output, const std::vector<std::string>& tsf,
                         const ConvertSettings& given, bool verbose,
                         const std::function<void(const std::string&)>& warn, unsigned concurrent_files) {
  auto t0 = std::chrono::steady_clock::now();
  ConvertSettings settings = given;
  if (settings.memory_limit == 0 && tsf.empty() && is_streamable(input)) {
    std::error_code ec;
    const std::uintmax_t bytes = std::filesystem::file_size(input, ec);
    const std::optional<std::uint64_t> available = available_memory();
    if (!ec && available) {
      const std::uint64_t share = *available / std::max(1u, concurrent_files);
      if (const auto limit = automatic_memory_limit(bytes, share)) {
        settings.memory_limit = *limit;
        std::fprintf(stderr,
                     "voxlines: %s: converting in memory would take about %s of the %s available%s: "
                     "streaming it within --memory-limit %s (the output is the same)\n",
                     input.c_str(), format_memory_size(in_memory_estimate(bytes)).c_str(),
                     format_memory_size(share).c_str(), concurrent_files > 1 ? " to each file converted at once" : "",
                     memory_limit_argument(*limit).c_str());
      }
    }
  }
  ConvertSummary s;
  double read_seconds = 0;
  if (settings.memory_limit > 0) {
    if (!tsf.empty())
      throw Error(ErrorKind::Unsupported, input, std::nullopt,
                  "--memory-limit does not carry --tsf values yet; convert without the limit");
    s = convert_streaming(input, output, settings);
    read_seconds = s.read_seconds;
    for (const std::string& w : s.warnings) warn(w);
  } else {
    Tractogram t = read_tractogram(input);
    for (const std::string& f : tsf) attach_tsf(t, f);
    read_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    for (const std::string& w : t.source.warnings) warn(w);
    s = convert_tractogram(std::move(t), output, settings);
    for (const std::string& w : s.warnings) warn(w);
  }
  char line[512];
  std::snprintf(line, sizeof line,
                ": %llu streamlines, %llu points -> %llu voxels, %llu segments (%llu points added at voxel faces)\n",
                (unsigned long long)s.streamlines, (unsigned long long)s.points, (unsigned long long)s.voxels,
                (unsigned long long)s.segments, (unsigned long long)s.synthetic_points);
  std::string report = output + line;
  if (settings.memory_limit > 0) {
    std::snprintf(line, sizeof line, "memory limit %s: %llu passes over the source, voxels built in %llu part%s%s\n",
                  format_memory_size(settings.memory_limit).c_str(), (unsigned long long)s.passes,
                  (unsigned long long)s.partitions, s.partitions == 1 ? "" : "s",
                  s.vertices_read_back ? " (vertex blocks written as placed and read back for the orders)" : "");
    report += line;
  }
  if (verbose) {
    std::snprintf(line, sizeof line, "stages: read %.3f s, voxelise %.3f s, orders %.3f s, write %.3f s\n",
                  read_seconds, s.voxelize_seconds, s.orders_seconds, s.write_seconds);
    report += line;
  }
  return report;
}

}  // namespace vxl::cli
