// The source formats `voxlines convert` and `voxview` read, in one table: the file-name suffixes that
// choose each reader, whether it can be streamed (--memory-limit), and its reader. read_tractogram, the
// streaming converter, the cohort's output names and the viewer all look formats up here.
#pragma once

#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "converter/tractogram.h"

namespace vxl {

struct SourceFormat {
  const char* name;                       // "TCK", ...
  std::span<const char* const> suffixes;  // lower case, longest first where one ends another (.trk.gz, .trk)
  bool streamable;                        // convert_streaming reads it in bounded memory
  Tractogram (*read)(const std::string& path);
  const char* description;  // for messages: what of the format is read
};

std::span<const SourceFormat> source_formats();

// The format of `path` by its suffix (case-insensitive; a directory given as "x.trx/" counts as x.trx), and
// the suffix that matched; null when none does.
struct SourceMatch {
  const SourceFormat* format = nullptr;
  std::string_view suffix;
};
SourceMatch source_format_of(const std::string& path);

// ".tck, .trk, .trk.gz, .trx zip or directory, ..." for help texts, and the same after "supported: " for
// messages.
std::string source_descriptions_text();
std::string supported_sources_text();

// Every suffix that chooses a reader, joined by `separator`: ".tck/.trk.gz/.trk/.trx/.vtk/.vtp" for help texts.
std::string source_suffixes_text(const std::string& separator);

// The formats' names joined by `separator` ("TCK / TRK / TRX / VTK / VTP"): all of them, or only those that
// stream (`streamable` true) or only those that do not (false), for help texts.
std::string source_format_names_text(const std::string& separator, std::optional<bool> streamable = std::nullopt);

}  // namespace vxl
