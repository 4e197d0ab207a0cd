#include "converter/export/streamline_outputs.h"

#include <algorithm>
#include <cctype>

namespace vxl {

const std::vector<StreamlineOutputFormat>& streamline_outputs() {
  static const std::vector<StreamlineOutputFormat> formats = {
      {StreamlineOutput::Tck,
       {".tck"},
       true,
       "Float32LE, the source TCK header's properties kept; --tsf writes one per-point value set beside it"},
      {StreamlineOutput::Trx,
       {".trx"},
       true,
       "zip, stored: float32 positions, uint64 offsets; groups, dpv, dps and dpg kept"},
      {StreamlineOutput::Vtk,
       {".vtk"},
       true,
       "legacy BINARY POLYDATA: values as POINT_DATA / CELL_DATA scalars, groups as 0/1 CELL_DATA arrays"},
      {StreamlineOutput::Trk,
       {".trk", ".trk.gz"},
       true,
       "TrackVis v2: a TRK source's header, values as scalars and properties"},
      {StreamlineOutput::Vxl, {".vxl"}, false, "converted again with the input's conversion settings"},
  };
  return formats;
}

std::optional<StreamlineOutput> streamline_output_of(const std::string& path, bool exported_only) {
  std::string lower = path;
  std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return std::tolower(c); });
  for (const StreamlineOutputFormat& f : streamline_outputs())
    if (f.exported || !exported_only)
      for (const std::string& suffix : f.suffixes)
        if (lower.ends_with(suffix)) return f.format;
  return std::nullopt;
}

namespace {

std::vector<std::string> suffixes_of(bool exported_only) {
  std::vector<std::string> all;
  for (const StreamlineOutputFormat& f : streamline_outputs())
    if (f.exported || !exported_only) all.insert(all.end(), f.suffixes.begin(), f.suffixes.end());
  return all;
}

}  // namespace

std::string streamline_output_help(bool exported_only) {
  std::vector<const StreamlineOutputFormat*> formats;
  for (const StreamlineOutputFormat& f : streamline_outputs())
    if (f.exported || !exported_only) formats.push_back(&f);
  std::string text;
  for (std::size_t i = 0; i < formats.size(); ++i) {
    text += i == 0 ? "" : i + 1 == formats.size() ? " or " : ", ";
    for (std::size_t k = 0; k < formats[i]->suffixes.size(); ++k)
      text += (k == 0 ? "" : " / ") + formats[i]->suffixes[k];
    text += " (" + formats[i]->keeps + ")";
  }
  return text;
}

std::string streamline_output_usage(bool exported_only) {
  std::string text = "OUT";
  for (const std::string& suffix : suffixes_of(exported_only)) text += (text == "OUT" ? "" : "|") + suffix;
  return text;
}

std::string streamline_output_suffixes(bool exported_only) {
  const std::vector<std::string> all = suffixes_of(exported_only);
  std::string text;
  for (std::size_t i = 0; i < all.size(); ++i) text += (i == 0 ? "" : i + 1 == all.size() ? " or " : ", ") + all[i];
  return text;
}

}  // namespace vxl
