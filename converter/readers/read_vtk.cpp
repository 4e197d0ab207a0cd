// Legacy VTK (`# vtk DataFile Version N.M`), DATASET POLYDATA, ASCII or BINARY (big-endian, as VTK writes
// it). Points float or double; line cells in the classic layout (`LINES n size`, each cell its count then
// its indices) or the VTK 5.1+ one (`LINES n+1 size`, then `OFFSETS type` and `CONNECTIVITY type`).
// POINT_DATA and CELL_DATA attributes (SCALARS, COLOR_SCALARS, VECTORS, NORMALS, TENSORS,
// TEXTURE_COORDINATES, FIELD arrays, ...) become value sets (vtk_polydata.h says which); dataset-level
// FIELD data and METADATA blocks are skipped. Coordinates: see vtk_polydata.h.
//
// Every count is checked against the bytes left before anything is allocated for it.
#include <charconv>
#include <cmath>
#include <cstring>
#include <string_view>

#include "converter/readers/read_tractogram.h"
#include "converter/readers/vtk_polydata.h"
#include "format/base/checked_count.h"
#include "format/base/error.h"
#include "format/base/mapped_file.h"

namespace vxl {
namespace {

struct Type {
  char kind = 0;      // 'i', 'u', 'f'; 's' string, 'b' bit
  unsigned size = 0;  // bytes per value in BINARY
};

class LegacyParser {
 public:
  LegacyParser(const std::string& path, std::span<const std::uint8_t> bytes)
      : path_(path), data_(reinterpret_cast<const char*>(bytes.data()), bytes.size()) {}

  Tractogram parse() {
    const std::string title = read_header();
    while (skip_space() < data_.size()) {
      const std::uint64_t key_at = pos_;
      const std::string key = word();
      if (key == "POINTS")
        read_points(key_at);
      else if (key == "LINES" || key == "VERTICES" || key == "POLYGONS" || key == "TRIANGLE_STRIPS")
        read_cells(key, key_at);
      else if (key == "POINT_DATA" || key == "CELL_DATA")
        start_attributes(key);
      else if (key == "METADATA")
        skip_metadata();
      else if (key == "FIELD")
        read_field();
      else if (key == "SCALARS" || key == "VECTORS" || key == "NORMALS" || key == "TENSORS" || key == "TENSORS6" ||
               key == "TEXTURE_COORDINATES" || key == "COLOR_SCALARS" || key == "GLOBAL_IDS" || key == "PEDIGREE_IDS")
        read_attribute(key, key_at);
      else if (key == "LOOKUP_TABLE")
        skip_lookup_table(key_at);
      else
        fail(key_at,
             "unexpected keyword '" + key + "' (expected POINTS, LINES, POINT_DATA, CELL_DATA, FIELD or an attribute)");
    }
    check_sections();
    return tractogram(title);
  }

 private:
  // The first lines up to DATASET POLYDATA; returns the title (empty when the file has none).
  std::string read_header() {
    const std::string first = line();
    if (!first.starts_with("# vtk DataFile Version")) fail(0, "expected '# vtk DataFile Version' on the first line");
    version_ = trim(first.substr(22));
    std::string title = line();
    std::string encoding = trim(title);
    // tckconvert leaves the title out; the encoding line then comes second.
    if (encoding == "ASCII" || encoding == "BINARY")
      title.clear();
    else
      encoding = trim(line());
    if (encoding == "BINARY")
      binary_ = true;
    else if (encoding != "ASCII")
      fail(pos_, "expected ASCII or BINARY on line 3, found '" + encoding + "'");
    const std::uint64_t at = skip_space();
    if (word() != "DATASET") fail(at, "expected DATASET");
    const std::string dataset = word();
    if (dataset != "POLYDATA")
      fail_unsupported(path_, "DATASET " + dataset + ": only POLYDATA (streamlines as LINES) is read");
    end_line();
    return title;
  }

  void read_points(std::uint64_t key_at) {
    p_.point_count = count();
    points_type_ = word();
    const Type type = parse_type(points_type_, key_at);
    if (type.kind != 'f') fail(key_at, "POINTS must be float or double");
    end_line();
    p_.points = numbers(checked_product(3, p_.point_count, path_, key_at, "POINTS count"), type, "POINTS");
    have_points_ = true;
  }

  // LINES are the streamlines; VERTICES are counted (they come first in VTK's cell numbering); surface
  // cells are noted and skipped.
  void read_cells(const std::string& key, std::uint64_t key_at) {
    std::vector<std::uint64_t> offsets{0};
    std::vector<double> connectivity;
    const std::uint64_t n = cells(offsets, connectivity, key_at, key);
    p_.cell_count = checked_sum(p_.cell_count, n, path_, key_at, "the number of cells");
    if (key == "LINES") {
      if (have_lines_) fail(key_at, "a second LINES section");
      p_.line_offsets = std::move(offsets);
      p_.line_connectivity = std::move(connectivity);
      have_lines_ = true;
    } else if (key == "VERTICES") {
      verts_ = checked_sum(verts_, n, path_, key_at, "the number of VERTICES cells");
    } else if (n > 0) {
      surface_ = key;
    }
  }

  void start_attributes(const std::string& key) {
    section_ = key == "POINT_DATA" ? Section::Points : Section::Cells;
    tuples_ = count();
    end_line();
  }

  // Information keys, up to an empty line: nothing we use.
  void skip_metadata() {
    end_line();
    while (pos_ < data_.size() && !trim(line()).empty()) {
    }
  }

  // The arrays of a section's attributes (or, before POINT_DATA and CELL_DATA, of the dataset: skipped).
  std::vector<vtk::DataArray>& attributes() { return section_ == Section::Points ? p_.point_data : p_.cell_data; }

  void read_field() {
    word();  // the field's name
    const std::uint64_t arrays = count();
    end_line();
    for (std::uint64_t k = 0; k < arrays; ++k) {
      skip_space();
      const std::uint64_t array_at = pos_;
      vtk::DataArray a;
      a.name = vtk::decode_name(word());
      a.components = count();
      const std::uint64_t n = count();
      const Type type = parse_type(word(), array_at);
      end_line();
      if (a.components == 0) fail(array_at, "FIELD array '" + a.name + "' with 0 components");
      if (n > data_.size() || (n > 0 && a.components > data_.size() / n))
        fail(array_at, "FIELD array '" + a.name + "' larger than the file");
      const std::uint64_t values = checked_product(a.components, n, path_, array_at, "FIELD array size");
      if (type.kind == 's' || type.kind == 'b') {
        skip_special(values, type);
        if (section_ != Section::Dataset)
          warnings_.push_back("array '" + a.name + "' holds " + (type.kind == 's' ? "strings" : "bits") + "; skipped");
        continue;
      }
      a.values = numbers(values, type, "FIELD array '" + a.name + "'");
      if (section_ == Section::Dataset) continue;  // dataset-level field data: not per point or cell
      if (n != tuples_)
        fail(array_at,
             "FIELD array '" + a.name + "' has " + std::to_string(n) + " tuples; expected " + std::to_string(tuples_));
      attributes().push_back(std::move(a));
    }
  }

  // SCALARS, VECTORS, NORMALS, TENSORS, COLOR_SCALARS, ...: one array of the current section.
  void read_attribute(const std::string& key, std::uint64_t key_at) {
    if (section_ == Section::Dataset) fail(key_at, key + " before POINT_DATA or CELL_DATA");
    vtk::DataArray a;
    a.name = vtk::decode_name(word());
    Type type{'f', 4};
    if (key == "COLOR_SCALARS") {
      a.components = count();
      type = binary_ ? Type{'u', 1} : Type{'f', 4};
    } else if (key == "TEXTURE_COORDINATES") {
      a.components = count();
      type = parse_type(word(), key_at);
    } else {
      type = parse_type(word(), key_at);
      a.components = key == "VECTORS" || key == "NORMALS" ? 3 : key == "TENSORS" ? 9 : key == "TENSORS6" ? 6 : 1;
      if (key == "SCALARS" && !at_line_end()) a.components = count();
    }
    end_line();
    if (a.components == 0 || a.components > data_.size() || (tuples_ > 0 && a.components > data_.size() / tuples_))
      fail(key_at, key + " '" + a.name + "' with an impossible number of components");
    if (key == "SCALARS") skip_optional_lookup_table_name();
    const std::uint64_t values = checked_product(a.components, tuples_, path_, key_at, key + " size");
    if (type.kind == 's' || type.kind == 'b') {
      skip_special(values, type);
      warnings_.push_back("array '" + a.name + "' holds " + std::string(type.kind == 's' ? "strings" : "bits") +
                          "; skipped");
      return;
    }
    if (tuples_ > 0 && a.components > data_.size() / tuples_)
      fail(key_at, key + " '" + a.name + "' larger than the file");
    a.values = numbers(values, type, key + " '" + a.name + "'");
    if (key == "COLOR_SCALARS" && binary_)
      for (double& v : a.values) v /= 255.0;  // as in ASCII files: 0 to 1
    attributes().push_back(std::move(a));
  }

  // LOOKUP_TABLE name after SCALARS: always present in files VTK writes, optional in the specification.
  void skip_optional_lookup_table_name() {
    const std::uint64_t save = pos_;
    skip_space();
    if (word() == "LOOKUP_TABLE") {
      word();
      end_line();
    } else {
      pos_ = save;
    }
  }

  void skip_lookup_table(std::uint64_t key_at) {
    word();
    const std::uint64_t n = count();
    end_line();
    if (n > data_.size()) fail(key_at, "LOOKUP_TABLE larger than the file");
    numbers(checked_product(4, n, path_, key_at, "LOOKUP_TABLE size"), binary_ ? Type{'u', 1} : Type{'f', 4},
            "LOOKUP_TABLE");
  }

  // What the sections must add up to, once all are read.
  void check_sections() {
    if (!surface_.empty() && !have_lines_)
      fail_unsupported(path_, "a surface mesh (" + surface_ + ", no LINES): only streamlines (LINES) are read");
    if (!surface_.empty()) warnings_.push_back(surface_ + " cells are not streamlines; skipped");
    if (verts_ > 0) warnings_.push_back(std::to_string(verts_) + " VERTICES cells are not streamlines; skipped");
    if (!have_points_ && have_lines_) fail(std::nullopt, "LINES without POINTS");
    if (!have_lines_ && p_.point_count > 0)
      fail_unsupported(path_,
                       "POLYDATA without LINES: " + std::to_string(p_.point_count) + " points but no streamlines");
    for (const vtk::DataArray& a : p_.cell_data)
      if (a.values.size() / a.components != p_.cell_count)
        fail(std::nullopt, "CELL_DATA for " + std::to_string(a.values.size() / a.components) + " cells; the file has " +
                               std::to_string(p_.cell_count));
  }

  Tractogram tractogram(const std::string& title) {
    Tractogram t;
    // VTK numbers the cells vertices first, then lines, whatever order the sections come in.
    p_.cells_before_lines = verts_;
    const bool lps = vtk::says_lps(title);
    vtk::fill_tractogram(t, path_, p_, lps);
    t.source.warnings.insert(t.source.warnings.end(), warnings_.begin(), warnings_.end());
    t.source.dtype = std::string(binary_ ? "BINARY " : "ASCII ") + points_type_;
    t.source.header = {{"version", version_},
                       {"title", title},
                       {"encoding", binary_ ? "BINARY" : "ASCII"},
                       {"coordinates", lps ? "LPS (title says SPACE=LPS): x and y negated" : "as written (RAS)"}};
    return t;
  }

  [[noreturn]] void fail(std::optional<std::uint64_t> at, const std::string& what) const {
    fail_input(path_, at, what);
  }

  static std::string trim(std::string s) {
    while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.pop_back();
    std::size_t b = 0;
    while (b < s.size() && std::isspace(static_cast<unsigned char>(s[b]))) ++b;
    return s.substr(b);
  }

  std::string line() {
    const std::size_t end = data_.find('\n', pos_);
    const std::size_t stop = end == std::string_view::npos ? data_.size() : end;
    std::string s(data_.substr(pos_, stop - pos_));
    pos_ = end == std::string_view::npos ? data_.size() : end + 1;
    if (!s.empty() && s.back() == '\r') s.pop_back();
    return s;
  }

  std::uint64_t skip_space() {
    while (pos_ < data_.size() && std::isspace(static_cast<unsigned char>(data_[pos_]))) ++pos_;
    return pos_;
  }

  std::string word() {
    skip_space();
    const std::size_t b = pos_;
    while (pos_ < data_.size() && !std::isspace(static_cast<unsigned char>(data_[pos_]))) ++pos_;
    if (b == pos_) fail(b, "unexpected end of file");
    return std::string(data_.substr(b, pos_ - b));
  }

  bool at_line_end() {
    std::size_t q = pos_;
    while (q < data_.size() && (data_[q] == ' ' || data_[q] == '\t' || data_[q] == '\r')) ++q;
    return q >= data_.size() || data_[q] == '\n';
  }

  // After a keyword line: only blanks up to the newline, which BINARY data follows directly.
  void end_line() {
    while (pos_ < data_.size() && (data_[pos_] == ' ' || data_[pos_] == '\t' || data_[pos_] == '\r')) ++pos_;
    if (pos_ < data_.size()) {
      if (data_[pos_] != '\n') fail(pos_, "expected the end of the line, found '" + std::string(1, data_[pos_]) + "'");
      ++pos_;
    }
  }

  std::uint64_t count() {
    skip_space();
    const std::uint64_t at = pos_;
    const std::string w = word();
    std::uint64_t v = 0;
    auto [end, ec] = std::from_chars(w.data(), w.data() + w.size(), v);
    if (ec != std::errc() || end != w.data() + w.size()) fail(at, "expected a count, found '" + w + "'");
    return v;
  }

  Type parse_type(const std::string& name, std::uint64_t at) {
    static const std::pair<const char*, Type> types[] = {
        {"bit", {'b', 0}},           {"unsigned_char", {'u', 1}},
        {"char", {'i', 1}},          {"unsigned_short", {'u', 2}},
        {"short", {'i', 2}},         {"unsigned_int", {'u', 4}},
        {"int", {'i', 4}},           {"unsigned_long", {'u', 8}},
        {"long", {'i', 8}},          {"vtktypeint64", {'i', 8}},
        {"vtktypeuint64", {'u', 8}}, {"vtkIdType", {'i', 4}},  // VTK writes vtkIdType arrays as 32-bit int
        {"float", {'f', 4}},         {"double", {'f', 8}},
        {"string", {'s', 0}},        {"utf8_string", {'s', 0}},
        {"vtktypeint8", {'i', 1}},   {"vtktypeuint8", {'u', 1}},
        {"vtktypeint16", {'i', 2}},  {"vtktypeuint16", {'u', 2}},
        {"vtktypeint32", {'i', 4}},  {"vtktypeuint32", {'u', 4}},
        {"signed_char", {'i', 1}}};
    for (const auto& [n, t] : types)
      if (name == n) return t;
    fail(at, "unknown data type '" + name + "'");
  }

  // `n` numbers, checked against what is left of the file before anything is allocated.
  std::vector<double> numbers(std::uint64_t n, Type type, const std::string& what) {
    const std::uint64_t left = data_.size() - pos_;
    std::vector<double> out;
    if (binary_) {
      if (n > left / type.size)
        fail(pos_, what + ": " + std::to_string(n) + " values of " + std::to_string(type.size) + " bytes, but only " +
                       std::to_string(left) + " bytes are left");
      out.resize(n);
      const auto* p = reinterpret_cast<const std::uint8_t*>(data_.data() + pos_);
      for (std::uint64_t k = 0; k < n; ++k) out[k] = vtk::load_number(p + k * type.size, type.kind, type.size, true);
      pos_ += n * type.size;
      return out;
    }
    if (n > (left + 1) / 2)
      fail(pos_, what + ": " + std::to_string(n) + " values cannot fit in the " + std::to_string(left) + " bytes left");
    out.resize(n);
    for (std::uint64_t k = 0; k < n; ++k) {
      skip_space();
      const std::uint64_t at = pos_;
      const char* b = data_.data() + pos_;
      const char* e = data_.data() + data_.size();
      const char* stop = b;
      while (stop < e && !std::isspace(static_cast<unsigned char>(*stop))) ++stop;
      auto [end, ec] = std::from_chars(b, stop, out[k]);
      if (b == stop) fail(at, what + ": file ends after " + std::to_string(k) + " of " + std::to_string(n) + " values");
      if (ec != std::errc() || end != stop)
        fail(at, what + ": expected a number, found '" + std::string(b, stop) + "'");
      if (type.kind != 'f' && out[k] != std::floor(out[k]))
        fail(at, what + ": expected an integer, found '" + std::string(b, stop) + "'");
      pos_ = static_cast<std::uint64_t>(stop - data_.data());
    }
    return out;
  }

  // Skips `n` strings or bits.
  void skip_special(std::uint64_t n, Type type) {
    if (type.kind == 'b') {
      if (binary_) {
        const std::uint64_t bytes = n / 8 + (n % 8 != 0);
        if (bytes > data_.size() - pos_) fail(pos_, "bit array larger than the rest of the file");
        pos_ += bytes;
      } else {
        numbers(n, Type{'u', 1}, "bit array");
      }
      return;
    }
    for (std::uint64_t k = 0; k < n; ++k) {
      if (pos_ >= data_.size()) fail(pos_, "file ends inside a string array");
      if (!binary_) {
        line();
        continue;
      }
      // VTK's length prefix: the top two bits of the first byte say 1, 2, 4 or 8 bytes, big-endian.
      const auto* p = reinterpret_cast<const std::uint8_t*>(data_.data() + pos_);
      const unsigned tag = p[0] >> 6, size = tag == 3 ? 1 : tag == 2 ? 2 : tag == 1 ? 4 : 8;
      if (size > data_.size() - pos_) fail(pos_, "file ends inside a string length");
      std::uint64_t length = vtk::load_uint(p, size, true);
      length &= size == 8 ? ~std::uint64_t(0) >> 2 : (std::uint64_t(1) << (8 * size - 2)) - 1;
      pos_ += size;
      if (length > data_.size() - pos_) fail(pos_, "string longer than the rest of the file");
      pos_ += length;
    }
  }

  // A cell section; returns the number of cells.
  std::uint64_t cells(std::vector<std::uint64_t>& offsets, std::vector<double>& connectivity, std::uint64_t key_at,
                      const std::string& key) {
    const std::uint64_t n = count(), size = count();
    end_line();
    const std::uint64_t save = pos_;
    skip_space();
    if (pos_ < data_.size() && data_.substr(pos_, 7) == "OFFSETS") {
      // VTK 5.1+: n is the number of offsets (cells + 1), size the connectivity length.
      word();
      const Type ot = parse_type(word(), key_at);
      end_line();
      if (ot.kind != 'i' && ot.kind != 'u') fail(key_at, "OFFSETS must be integers");
      const std::vector<double> o = numbers(n, ot, key + " OFFSETS");
      skip_space();
      const std::uint64_t conn_at = pos_;
      if (word() != "CONNECTIVITY") fail(conn_at, "expected CONNECTIVITY after OFFSETS");
      const Type ct = parse_type(word(), conn_at);
      end_line();
      if (ct.kind != 'i' && ct.kind != 'u') fail(conn_at, "CONNECTIVITY must be integers");
      connectivity = numbers(size, ct, key + " CONNECTIVITY");
      if (o.empty()) {
        if (size != 0) fail(key_at, key + ": connectivity without offsets");
        return 0;
      }
      if (o[0] != 0) fail(key_at, key + ": the first offset must be 0");
      offsets.resize(o.size());
      for (std::size_t k = 0; k < o.size(); ++k) {
        if (o[k] < (k ? static_cast<double>(offsets[k - 1]) : 0.0) || o[k] > static_cast<double>(size))
          fail(key_at, key + ": offset " + std::to_string(k) + " is " + std::to_string(o[k]) +
                           "; expected non-decreasing, at most " + std::to_string(size));
        offsets[k] = static_cast<std::uint64_t>(o[k]);
      }
      if (offsets.back() != size) fail(key_at, key + ": the last offset must equal the connectivity size");
      return o.size() - 1;
    }
    pos_ = save;
    // Classic: `size` integers, each cell its point count followed by its indices.
    std::vector<double> all = numbers(size, Type{'i', 4}, key);
    offsets.reserve(std::min<std::uint64_t>(n, size) + 1);
    connectivity.reserve(size);
    std::uint64_t k = 0;
    for (std::uint64_t c = 0; c < n; ++c) {
      if (k >= all.size())
        fail(key_at, key + ": " + std::to_string(n) + " cells declared but the data ends after " + std::to_string(c));
      const double m = all[k++];
      if (!(m >= 0) || m > static_cast<double>(all.size() - k))
        fail(key_at,
             key + ": cell " + std::to_string(c) + " claims " + std::to_string(m) + " points, more than the data left");
      connectivity.insert(connectivity.end(), all.begin() + k, all.begin() + k + static_cast<std::uint64_t>(m));
      k += static_cast<std::uint64_t>(m);
      offsets.push_back(connectivity.size());
    }
    if (k != all.size())
      fail(key_at, key + ": " + std::to_string(all.size() - k) + " values left after " + std::to_string(n) + " cells");
    return n;
  }

  const std::string& path_;
  std::string_view data_;
  std::uint64_t pos_ = 0;
  bool binary_ = false;
  std::string version_, points_type_;
  std::vector<std::string> warnings_;
  // What the sections read so far hold.
  enum class Section { Dataset, Points, Cells };  // whose attributes come next
  Section section_ = Section::Dataset;
  std::uint64_t tuples_ = 0;  // of the current section
  vtk::PolyData p_;
  bool have_points_ = false, have_lines_ = false;
  std::string surface_;  // POLYGONS or TRIANGLE_STRIPS seen
  std::uint64_t verts_ = 0;
};

}  // namespace

Tractogram read_vtk(const std::string& path) {
  MappedFile file(path);
  Tractogram t = LegacyParser(path, file.bytes()).parse();
  vtk::describe_source(t, path, "vtk", file.bytes());
  return t;
}

}  // namespace vxl
