#include "converter/readers/mrtrix_header.h"

#include <charconv>
#include <string_view>

#include "format/base/error.h"

namespace vxl {
namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  return s;
}

}  // namespace

MrtrixDatatype mrtrix_datatype(const std::string& path, const std::string& datatype, const MrtrixFileKind& kind) {
  if (datatype == "Float32LE") return MrtrixDatatype::kFloat32LE;
  if (datatype == "Float32BE") return MrtrixDatatype::kFloat32BE;
  if (datatype == "Float64LE") return MrtrixDatatype::kFloat64LE;
  if (datatype == "Float64BE") return MrtrixDatatype::kFloat64BE;
  fail_unsupported(path, std::string(kind.name) + " datatype '" + datatype +
                             "' (expected Float32LE, Float32BE, Float64LE or Float64BE)");
}

std::optional<MrtrixHeader> parse_mrtrix_header(const std::string& path, std::span<const std::uint8_t> bytes,
                                                std::uint64_t file_size, const MrtrixFileKind& kind) {
  const std::string name = kind.name;
  MrtrixHeader h;
  std::string_view text(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  std::size_t pos = 0;
  // With only the first bytes of a longer file, a line that runs to their end may be cut: it is not
  // judged (nor the magic line) until more is read, so a streamed header fails exactly where a whole one does.
  const bool partial = bytes.size() < file_size;
  bool cut = false;
  auto next_line = [&](std::string_view& line) {
    if (pos >= text.size()) return false;
    std::size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) {
      if (partial) {
        cut = true;
        return false;
      }
      end = text.size();
    }
    line = text.substr(pos, end - pos);
    pos = end + 1;
    return true;
  };
  std::string_view line;
  if (!next_line(line)) {
    if (cut) return std::nullopt;
    fail_input(path, 0, "expected the " + name + " magic line '" + kind.magic + "'");
  }
  if (trim(line) != kind.magic) fail_input(path, 0, "expected the " + name + " magic line '" + kind.magic + "'");
  bool ended = false;
  std::string last_key;
  while (true) {
    std::size_t line_start = pos;
    if (!next_line(line)) break;
    std::string_view t = trim(line);
    if (t == "END") {
      ended = true;
      break;
    }
    if (t.empty()) continue;
    std::size_t colon = t.find(':');
    if (colon == std::string_view::npos) {
      // A line without a colon continues the previous value (seen in real command_history fields).
      if (last_key.empty()) fail_input(path, line_start, "expected a 'key: value' header line or 'END'");
      auto& values = h.fields[last_key];
      values.back() = values.back().get<std::string>() + "\n" + std::string(t);
      continue;
    }
    std::string key(trim(t.substr(0, colon)));
    last_key = key;
    std::string value(trim(t.substr(colon + 1)));
    h.fields[key].push_back(value);
  }
  if (!ended) {
    if (bytes.size() < file_size) return std::nullopt;
    fail_input(path, bytes.size(), name + " header has no 'END' line");
  }

  auto single = [&](const char* key) -> std::string {
    if (!h.fields.contains(key)) fail_input(path, std::nullopt, name + " header lacks '" + key + ":'");
    return h.fields[key].back().get<std::string>();
  };
  h.datatype = single("datatype");
  std::string file = single("file");
  if (kind.data_elsewhere) {
    if (h.fields["file"].size() > 1)
      fail_unsupported(path, name + " data split across " + std::to_string(h.fields["file"].size()) +
                                 " files ('file:' entries); convert it to a single .mif first");
    // "NAME [OFFSET]": the name may hold spaces, the offset is the last word when it is a number. A negative one
    // is a bad offset, as MRtrix says, not part of the name.
    const std::size_t space = file.rfind(' ');
    const std::string tail = space == std::string::npos ? "" : file.substr(space + 1);
    const bool numbered = !tail.empty() && tail.find_first_not_of("0123456789") == std::string::npos;
    if (tail.size() > 1 && tail[0] == '-' && tail.find_first_not_of("0123456789", 1) == std::string::npos)
      fail_input(path, std::nullopt,
                 name + " 'file:' has a bad offset: '" + tail + "' (a number of bytes into the data file, 0 or more)");
    h.data_file = numbered ? std::string(trim(std::string_view(file).substr(0, space))) : file;
    if (h.data_file.empty()) fail_input(path, std::nullopt, name + " 'file:' names no file: '" + file + "'");
    file = ". " + (numbered ? tail : "0");
    if (h.data_file != ".") {
      std::uint64_t off = 0;
      const auto [end, ec] = std::from_chars(tail.data(), tail.data() + tail.size(), off);
      if (numbered && (ec != std::errc() || end != tail.data() + tail.size()))
        fail_input(path, std::nullopt, name + " 'file:' offset is not a number: '" + file + "'");
      h.data_offset = off;
    }
  }
  if (h.data_file == ".") {
    if (file.size() < 2 || file[0] != '.' || file[1] != ' ')
      fail_unsupported(path, name + " 'file:' must be '. OFFSET' (data in the same file); got '" + file + "'");
    try {
      std::size_t used = 0;
      long long off = std::stoll(file.substr(2), &used);
      if (off < 0) throw std::out_of_range("negative");
      h.data_offset = static_cast<std::uint64_t>(off);
    } catch (const std::exception&) {
      fail_input(path, std::nullopt, name + " 'file:' offset is not a number: '" + file + "'");
    }
    if (h.data_offset < pos) fail_input(path, h.data_offset, name + " data offset points inside the header");
    if (h.data_offset > file_size)
      fail_input(path, h.data_offset,
                 name + " data offset is past the end of the file (" + std::to_string(file_size) + " bytes)");
  }
  if (h.fields.contains("count")) {
    // Digits only: std::stoull would read "-5" as 2^64 - 5. A malformed count is as good as a stale one.
    const std::string text = h.fields["count"].back().get<std::string>();
    h.count_text = text;
    std::uint64_t v = 0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
    if (!text.empty() && ec == std::errc() && end == text.data() + text.size()) h.count = v;
  }
  return h;
}

std::optional<std::string> count_warning(const MrtrixHeader& h, std::uint64_t streamlines) {
  if (!h.count_text) return std::nullopt;
  const std::string data = "the data (" + std::to_string(streamlines) + " streamlines)";
  if (!h.count) return "header count '" + *h.count_text + "' is not a number of streamlines; " + data + " is trusted";
  if (*h.count != streamlines)
    return "header count " + *h.count_text + " disagrees with " + data + ": the data is trusted";
  return std::nullopt;
}

std::optional<std::string> MrtrixHeader::last(const char* key) const {
  auto it = fields.find(key);
  if (it == fields.end() || it->empty()) return std::nullopt;
  return it->back().get<std::string>();
}

}  // namespace vxl
