#include "converter/export/export_vtk.h"

#include <bit>
#include <cstring>
#include <filesystem>
#include <limits>
#include <vector>

#include "format/base/atomic_output.h"
#include "format/base/error.h"
#include "format/vxl_streamlines.h"

namespace vxl {
namespace {

// Big-endian 32-bit words, buffered.
class BigEndianWriter {
 public:
  explicit BigEndianWriter(AtomicOutputFile& out) : out_(out) { buffer_.reserve(1 << 16); }
  ~BigEndianWriter() = default;
  void word(std::uint32_t v) {
    buffer_.push_back(__builtin_bswap32(v));
    if (buffer_.size() == buffer_.capacity()) flush();
  }
  void real(float v) { word(std::bit_cast<std::uint32_t>(v)); }
  void text(const std::string& s) {
    flush();
    out_.write(s.data(), s.size());
  }
  void bytes(const std::vector<std::uint8_t>& b) {
    flush();
    out_.write(b.data(), b.size());
  }
  void flush() {
    out_.write(buffer_.data(), buffer_.size() * 4);
    buffer_.clear();
  }

 private:
  AtomicOutputFile& out_;
  std::vector<std::uint32_t> buffer_;
};

// VTK's legacy names are single words: blanks and '%' are written %XX, as VTK does (the readers decode them).
std::string legacy_name(const std::string& name) {
  std::string out;
  for (unsigned char c : name) {
    if (c <= ' ' || c == '%' || c >= 127) {
      char hex[4];
      std::snprintf(hex, sizeof hex, "%%%02X", c);
      out += hex;
    } else {
      out += static_cast<char>(c);
    }
  }
  return out.empty() ? "values" : out;
}

}  // namespace

void export_vtk(const VxlFile& file, const std::string& out_path, const StreamlineSubset* subset) {
  const SubsetCounts m = subset_counts(file, subset);
  const std::uint64_t lines_size = m.streamlines + m.points;
  if (m.points > std::numeric_limits<std::int32_t>::max() || lines_size > std::numeric_limits<std::int32_t>::max())
    throw Error(ErrorKind::Unsupported, out_path, std::nullopt,
                "legacy VTK LINES use 32-bit indices: " + std::to_string(m.points) + " points in " +
                    std::to_string(m.streamlines) + " streamlines are too many (export to .tck or .trx)");

  // One walk: points go straight to the file, the per-point values and the point counts are gathered.
  const ValueSets& vv = file.vertex_values();
  std::vector<std::vector<float>> point_values(vv.size());
  for (auto& v : point_values) v.reserve(m.points);
  std::vector<std::uint32_t> counts;
  counts.reserve(m.streamlines);

  // The title is one line: control characters in the file name would end it early.
  std::string source = std::filesystem::path(file.path()).filename().string();
  for (char& c : source)
    if (static_cast<unsigned char>(c) < ' ') c = '_';
  AtomicOutputFile out(out_path);
  BigEndianWriter w(out);
  w.text("# vtk DataFile Version 3.0\nvoxlines export of " + source + " SPACE=RAS\nBINARY\nDATASET POLYDATA\nPOINTS " +
         std::to_string(m.points) + " float\n");
  WalkCallbacks cb;
  cb.threads = 0;  // the points decoded on every core
  cb.read_points = [&](std::uint64_t s) { return in_subset(subset, s); };
  cb.voxline = [&](const VoxlineVisit& v) {
    if (!in_subset(subset, v.streamline)) return;
    // A synthetic first point has no source point.
    const std::uint64_t from = v.first_vertex + (v.synthetic_first ? 1 : 0), to = v.first_vertex + v.own_points;
    for (std::uint32_t k = 0; k < vv.size(); ++k) {
      const auto values = vv.values(k);
      point_values[k].insert(point_values[k].end(), values.begin() + from, values.begin() + to);
    }
  };
  cb.streamline = [&](std::uint64_t, std::span<const float> xyz) {
    for (float v : xyz) w.real(v);
    counts.push_back(static_cast<std::uint32_t>(xyz.size() / 3));
  };
  walk_streamlines(file, cb);

  w.text("\nLINES " + std::to_string(m.streamlines) + " " + std::to_string(lines_size) + "\n");
  std::uint32_t next = 0;
  for (std::uint32_t n : counts) {
    w.word(n);
    for (std::uint32_t k = 0; k < n; ++k) w.word(next++);
  }
  w.text("\n");
  const ValueSets& sv = file.streamline_values();
  const std::vector<StreamlineGroup> groups = file.groups();
  if (!sv.empty() || !groups.empty()) w.text("CELL_DATA " + std::to_string(m.streamlines) + "\n");
  if (!sv.empty()) {
    for (std::uint32_t k = 0; k < sv.size(); ++k) {
      w.text("SCALARS " + legacy_name(sv.name(k)) + " float 1\nLOOKUP_TABLE default\n");
      for (float v : subset ? subset->pick(sv.values(k)) : std::vector<float>(sv.values(k).begin(), sv.values(k).end()))
        w.real(v);
      w.text("\n");
    }
  }
  // A group is a 0/1 array: VTK has no groups, and every reader keeps cell arrays (ours as values).
  for (const StreamlineGroup& g : groups) {
    std::vector<std::uint8_t> member(file.meta().streamline_count, 0);
    for (std::uint64_t s : g.members) member[s] = 1;
    if (subset) {
      std::vector<std::uint8_t> picked;
      picked.reserve(subset->size());
      for (std::uint64_t s : subset->indices()) picked.push_back(member[s]);
      member = std::move(picked);
    }
    w.text("SCALARS " + legacy_name(g.name) + " unsigned_char 1\nLOOKUP_TABLE default\n");
    w.bytes(member);
    w.text("\n");
  }
  if (!point_values.empty()) {
    w.text("POINT_DATA " + std::to_string(m.points) + "\n");
    for (std::uint32_t k = 0; k < vv.size(); ++k) {
      w.text("SCALARS " + legacy_name(vv.name(k)) + " float 1\nLOOKUP_TABLE default\n");
      for (float v : point_values[k]) w.real(v);
      w.text("\n");
    }
  }
  w.flush();
  out.commit();
}

}  // namespace vxl
