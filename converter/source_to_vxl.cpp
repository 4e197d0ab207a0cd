#include "converter/source_to_vxl.h"

#include <linux/magic.h>
#include <stdlib.h>
#include <sys/vfs.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>

#include "converter/memory_available.h"
#include "converter/memory_size.h"
#include "converter/readers/read_tractogram.h"
#include "converter/readers/read_tsf.h"
#include "converter/readers/source_formats.h"
#include "converter/streaming_convert.h"
#include "format/error.h"

namespace vxl {
namespace {

bool is_streamable(const std::string& path) {
  const SourceMatch match = source_format_of(path);
  return match.format && match.format->streamable;
}

// The limit to stream `input` within when none was given: only for a streamable source without TSF values
// whose conversion in memory would not fit in its share of the available memory. 0: convert in memory.
std::uint64_t chosen_memory_limit(const std::string& input, const SourceConversion& c) {
  if (c.settings.memory_limit > 0 || !c.tsf.empty() || !is_streamable(input)) return c.settings.memory_limit;
  std::error_code ec;
  const std::uintmax_t bytes = std::filesystem::file_size(input, ec);
  const std::optional<std::uint64_t> available = available_memory();
  if (ec || !available) return 0;
  const std::uint64_t share = *available / std::max(1u, c.concurrent_files);
  const std::optional<std::uint64_t> limit = automatic_memory_limit(bytes, share);
  if (!limit) return 0;
  if (c.notice)
    c.notice(input + ": converting in memory would take about " + format_memory_size(in_memory_estimate(bytes)) +
             " of the " + format_memory_size(share) + " available" +
             (c.concurrent_files > 1 ? " to each file converted at once" : "") +
             ": streaming it within --memory-limit " + memory_limit_argument(*limit) + " (the output is the same)");
  return *limit;
}

void warn_each(const SourceConversion& c, const std::vector<std::string>& warnings) {
  if (c.warn)
    for (const std::string& w : warnings) c.warn(w);
}

// A fresh, empty file "voxlines-XXXXXX-NAME.vxl" in `dir`: the name is this conversion's alone (mkstemps), and
// the conversion's atomic output replaces the empty file when complete.
std::string reserve_temporary_vxl(const std::string& input, const std::string& dir) {
  std::string name = input;
  while (name.size() > 1 && name.back() == '/') name.pop_back();  // a TRX directory given as "x.trx/"
  std::string path =
      (std::filesystem::path(dir) / ("voxlines-XXXXXX-" + std::filesystem::path(name).filename().string() + ".vxl"))
          .string();
  const int suffix = static_cast<int>(path.size() - path.rfind("XXXXXX") - 6);
  const int fd = ::mkstemps(path.data(), suffix);
  if (fd < 0)
    throw Error(ErrorKind::Output, dir, std::nullopt,
                std::string("cannot create a temporary .vxl for ") + input + ": " + std::strerror(errno));
  ::close(fd);
  return path;
}

bool on_tmpfs(const std::string& dir) {
  struct statfs fs {};
  return ::statfs(dir.c_str(), &fs) == 0 && fs.f_type == TMPFS_MAGIC;
}

}  // namespace

SourceConversionReport convert_source(const std::string& input, const std::string& output, const SourceConversion& c) {
  const auto t0 = std::chrono::steady_clock::now();
  SourceConversionReport report;
  ConvertSettings settings = c.settings;
  settings.memory_limit = chosen_memory_limit(input, c);
  if (settings.memory_limit > 0) {
    if (!c.tsf.empty())
      throw Error(ErrorKind::Unsupported, input, std::nullopt,
                  "--memory-limit does not carry --tsf values yet; convert without the limit");
    report.summary = convert_streaming(input, output, settings);
    report.read_seconds = report.summary.read_seconds;
    report.streamed = true;
    report.memory_limit = settings.memory_limit;
    warn_each(c, report.summary.warnings);
    return report;
  }
  Tractogram t = read_tractogram(input);
  for (const std::string& f : c.tsf) attach_tsf(t, f);
  report.read_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  warn_each(c, t.source.warnings);
  report.summary = convert_tractogram(std::move(t), output, settings);
  warn_each(c, report.summary.warnings);
  return report;
}

OpenedSource open_as_vxl(const std::string& input, const SourceConversion& c, const std::string& temporary_dir) {
  const std::string dir = temporary_dir.empty() ? std::filesystem::temp_directory_path().string() : temporary_dir;
  const std::string temporary = reserve_temporary_vxl(input, dir);
  try {
    SourceConversionReport report = convert_source(input, temporary, c);
    VxlFile file = VxlFile::open(temporary);
    std::filesystem::remove(temporary);  // the mapping keeps the data
    return {std::move(file), std::move(report), temporary, on_tmpfs(dir)};
  } catch (...) {
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    throw;
  }
}

}  // namespace vxl
