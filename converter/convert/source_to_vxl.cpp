#include "converter/convert/source_to_vxl.h"

#include <algorithm>
#include <chrono>
#include <filesystem>

#include "converter/convert/memory_choice.h"
#include "converter/convert/streaming_convert.h"
#include "converter/convert/temporary_vxl.h"
#include "converter/pipeline/memory_budget.h"
#include "converter/readers/read_tractogram.h"
#include "converter/readers/read_tsf.h"
#include "converter/readers/source_formats.h"
#include "format/base/error.h"
#include "format/base/memory_available.h"
#include "format/base/memory_size.h"

namespace vxl {
namespace {

bool is_streamable(const std::string& path) {
  const SourceMatch match = source_format_of(path);
  return match.format && match.format->streamable;
}

// The memory available to one of the conversions running at once.
std::optional<std::uint64_t> memory_share(const SourceConversion& c) {
  std::optional<std::uint64_t> share = available_memory();
  if (share) *share /= std::max(1u, c.concurrent_files);
  return share;
}

// Streams `input` within the limit given, or else within memory_choice's for its size and its share of the available
// memory (said by `notice` when that share limits it), raised up to the largest chosen limit where some part of the
// work needs more: a chosen limit does not refuse a source the memory holds.
void stream_source(const std::string& input, const std::string& output, ConvertSettings settings,
                   const SourceConversion& c, SourceConversionReport& report) {
  const std::optional<std::uint64_t> share = memory_share(c);
  const bool chosen = settings.memory_limit == 0;
  if (chosen) {
    std::error_code ec;
    const std::uintmax_t size = std::filesystem::file_size(input, ec);
    const std::uint64_t bytes = ec ? 0 : size;
    settings.memory_limit = default_memory_limit(bytes, share);
    if (c.notice && limited_by_available_memory(bytes, share))
      c.notice(input + ": " + format_memory_size(*share) + " of memory available" +
               (c.concurrent_files > 1 ? " to each file converted at once" : "") +
               ": converting within --memory-limit " + memory_limit_argument(settings.memory_limit) +
               " (more passes over the source; the output is the same)");
  }
  for (;;) {
    try {
      report.summary = convert_streaming(input, output, settings);
      break;
    } catch (const MemoryLimitTooSmall& e) {
      const std::uint64_t largest = largest_chosen_memory_limit(share);
      if (!chosen || settings.memory_limit >= largest || e.suggested() <= settings.memory_limit) throw;
      settings.memory_limit = std::min(largest, e.suggested());
    }
  }
  report.read_seconds = report.summary.read_seconds;
  report.streamed = true;
  report.memory_limit = settings.memory_limit;
}

void warn_each(const SourceConversion& c, const std::vector<std::string>& warnings) {
  if (c.warn)
    for (const std::string& w : warnings) c.warn(w);
}

}  // namespace

SourceConversionReport convert_source(const std::string& input, const std::string& output, const SourceConversion& c) {
  const auto t0 = std::chrono::steady_clock::now();
  SourceConversionReport report;
  ConvertSettings settings = c.settings;
  if (!c.tsf.empty() && settings.memory_limit > 0)
    throw Error(ErrorKind::Unsupported, input, std::nullopt,
                "--memory-limit does not carry --tsf values yet; convert without the limit");
  // A memory limit with a source that cannot stream is refused there, naming the formats that can.
  if (c.tsf.empty() && (is_streamable(input) || settings.memory_limit > 0)) {
    stream_source(input, output, settings, c, report);
    warn_each(c, report.summary.warnings);
    return report;
  }
  Tractogram t = read_tractogram(input);
  for (const std::string& f : c.tsf) attach_tsf(t, f);
  report.read_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  warn_each(c, t.source.warnings);
  if (settings.memory_limit == 0) settings.memory_limit = largest_chosen_memory_limit(memory_share(c));
  report.summary = convert_tractogram(std::move(t), output, settings);
  warn_each(c, report.summary.warnings);
  return report;
}

OpenedSource open_as_vxl(const std::string& input, const SourceConversion& c, const std::string& temporary_dir) {
  SourceConversionReport report;
  TemporaryVxl t = open_through_temporary_vxl(
      input, [&](const std::string& path) { report = convert_source(input, path, c); }, temporary_dir);
  return {std::move(t.file), std::move(report), std::move(t.path), t.in_ram};
}

}  // namespace vxl
