#include "converter/streamline_outputs.h"

#include <algorithm>
#include <cctype>

namespace vxl {

const std::vector<StreamlineOutputFormat>& streamline_outputs() {
  static const std::vector<StreamlineOutputFormat> formats = {
      {StreamlineOutput::Tck, {".tck"}, true},  {StreamlineOutput::Trx, {".trx"}, true},
      {StreamlineOutput::Vtk, {".vtk"}, true},  {StreamlineOutput::Trk, {".trk", ".trk.gz"}, true},
      {StreamlineOutput::Vxl, {".vxl"}, false},
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
