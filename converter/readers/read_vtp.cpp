// VTK XML PolyData (`.vtp`): one Piece with Points and Lines (connectivity + offsets); PointData and
// CellData arrays become value sets (vtk_polydata.h says which). DataArray formats ascii, binary (base64)
// and appended (raw or base64), uncompressed or vtkZLibDataCompressor blocks, header_type UInt32 or UInt64,
// byte_order LittleEndian or BigEndian. Coordinates: see vtk_polydata.h.
//
// The XML is parsed by pugixml. Raw appended data is not XML, so the document is cut after the
// <AppendedData> start tag the parser finds, and its bytes are addressed directly. Base64 is decoded here (a few
// lines): VTK writes the header and the data of an array as separately padded base64 chunks, which general-purpose
// decoders reject or silently mangle; this one decodes chunk after chunk and refuses any character outside the
// alphabet.
//
// Nothing is allocated before it is checked against the file: an uncompressed array's size against the
// bytes that hold it, a compressed block's declared size against zlib's maximum ratio (1032:1), and all
// decoded arrays together against a budget proportional to the file size.
#include <charconv>
#include <cmath>
#include <cstring>
#include <functional>
#include <string_view>

#include <zlib.h>
#include <pugixml.hpp>

#include "converter/readers/read_tractogram.h"
#include "converter/readers/vtk_polydata.h"
#include "format/base/checked_count.h"
#include "format/base/error.h"
#include "format/base/mapped_file.h"

namespace vxl {
namespace {

// zlib cannot expand data by more than this (deflate's best case), plus a little for the block framing.
constexpr std::uint64_t kZlibMaxRatio = 1032;

struct XmlDataType {
  char kind = 0;  // 'i', 'u', 'f'; 0 for arrays we skip (String, Bit)
  unsigned size = 0;
};

XmlDataType parse_data_type(const std::string& name) {
  static const std::pair<const char*, XmlDataType> types[] = {
      {"Int8", {'i', 1}},    {"UInt8", {'u', 1}},   {"Int16", {'i', 2}}, {"UInt16", {'u', 2}},
      {"Int32", {'i', 4}},   {"UInt32", {'u', 4}},  {"Int64", {'i', 8}}, {"UInt64", {'u', 8}},
      {"Float32", {'f', 4}}, {"Float64", {'f', 8}}, {"Char", {'i', 1}},  {"UChar", {'u', 1}}};
  for (const auto& [n, t] : types)
    if (name == n) return t;
  return {};
}

// Reads the bytes of one array's header and data, from base64 text or raw appended bytes.
class ByteSource {
 public:
  ByteSource(const std::string& path, std::string_view text, std::uint64_t file_offset, bool base64)
      : path_(path), s_(text), at_(file_offset), base64_(base64) {}

  // An upper bound of the bytes still available, to check a size before allocating for it.
  std::uint64_t available() const { return base64_ ? (s_.size() - pos_) / 4 * 3 + (n_ - i_) : s_.size() - pos_; }

  void read(std::uint8_t* out, std::uint64_t n) {
    if (n > available())
      fail("needs " + std::to_string(n) + " bytes, but at most " + std::to_string(available()) + " remain");
    if (!base64_) {
      std::memcpy(out, s_.data() + pos_, n);
      pos_ += n;
      return;
    }
    while (n > 0) {
      if (i_ == n_) next_quartet();
      const std::uint64_t take = std::min<std::uint64_t>(n, n_ - i_);
      std::memcpy(out, carry_ + i_, take);
      out += take, i_ += take, n -= take;
    }
  }
  std::uint64_t read_uint(unsigned size, bool big) {
    std::uint8_t b[8];
    read(b, size);
    return vtk::load_uint(b, size, big);
  }
  [[noreturn]] void fail(const std::string& what) const { fail_input(path_, at_ + pos_, what); }

 private:
  static int value(char c) {
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    if (c == '+') return 62;
    if (c == '/') return 63;
    return c == '=' ? 64 : -1;
  }
  // Decodes the next four characters (whitespace skipped); a padded quartet ends a chunk and gives 1 or 2 bytes.
  void next_quartet() {
    int v[4];
    for (int k = 0; k < 4; ++k) {
      while (pos_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[pos_]))) ++pos_;
      if (pos_ >= s_.size()) fail("base64 data ends inside a group of four characters");
      v[k] = value(s_[pos_]);
      if (v[k] < 0) fail("invalid base64 character '" + std::string(1, s_[pos_]) + "'");
      ++pos_;
    }
    if (v[0] == 64 || v[1] == 64 || (v[2] == 64 && v[3] != 64)) fail("misplaced base64 padding '='");
    const std::uint32_t bits = (std::uint32_t(v[0]) << 18) | (std::uint32_t(v[1]) << 12) |
                               (std::uint32_t(v[2] & 63) << 6) | std::uint32_t(v[3] & 63);
    carry_[0] = static_cast<std::uint8_t>(bits >> 16);
    carry_[1] = static_cast<std::uint8_t>(bits >> 8);
    carry_[2] = static_cast<std::uint8_t>(bits);
    n_ = v[2] == 64 ? 1 : v[3] == 64 ? 2 : 3;
    i_ = 0;
  }

  const std::string& path_;
  std::string_view s_;
  std::uint64_t at_;
  bool base64_;
  std::uint64_t pos_ = 0;
  std::uint8_t carry_[3] = {};
  unsigned n_ = 0, i_ = 0;
};

class VtpParser {
 public:
  VtpParser(const std::string& path, std::span<const std::uint8_t> bytes)
      : path_(path),
        all_(reinterpret_cast<const char*>(bytes.data()), bytes.size()),
        budget_(64 * static_cast<std::uint64_t>(bytes.size()) + (std::uint64_t(64) << 20)) {}

  Tractogram parse() {
    // Raw appended bytes are not XML: the document is parsed up to the end of the <AppendedData> start tag,
    // then closed. Which tag that is, the parser says, not a text search: the first "<AppendedData" in the
    // text is taken when the parsed prefix has it as the element (the usual case: only the prefix is
    // copied); otherwise (it was in a comment, say) the whole file is parsed, and as a parse that fails keeps
    // the nodes before the error, the element found there is the real one.
    constexpr unsigned kFlags = pugi::parse_default | pugi::parse_comments;
    pugi::xml_document doc;
    pugi::xml_parse_result r;
    // Parses the document cut after the tag at `at`: true when that tag is the <AppendedData> element.
    auto parse_cut_at = [&](std::size_t at) {
      const std::size_t gt = tag_end(at);
      if (gt == std::string_view::npos) return false;
      const std::string xml = std::string(all_.substr(0, gt + 1)) + "</AppendedData></VTKFile>";
      r = doc.load_buffer(xml.data(), xml.size(), kFlags);
      const pugi::xml_node element = doc.child("VTKFile").child("AppendedData");
      return r && element && offset(element) == at + 1;  // offset_debug: the name, after the '<'
    };
    std::size_t app = all_.find("<AppendedData");
    if (app == std::string_view::npos || !parse_cut_at(app)) {
      r = doc.load_buffer(all_.data(), all_.size(), kFlags);
      const pugi::xml_node element = doc.child("VTKFile").child("AppendedData");
      app = element ? offset(element) - 1 : std::string_view::npos;
      if (app != std::string_view::npos && !parse_cut_at(app)) fail(app, "<AppendedData> tag is not well-formed");
    }
    if (app != std::string_view::npos) {
      std::size_t us = tag_end(app) + 1;
      while (us < all_.size() && std::isspace(static_cast<unsigned char>(all_[us]))) ++us;
      if (us >= all_.size() || all_[us] != '_') fail(us, "expected '_' at the start of the appended data");
      appended_ = all_.substr(us + 1);
      appended_at_ = us + 1;
    }
    if (!r) fail(static_cast<std::uint64_t>(r.offset), std::string("not well-formed XML: ") + r.description());

    const pugi::xml_node root = doc.child("VTKFile");
    if (!root) fail(0, "expected a <VTKFile> root element");
    const std::string type = root.attribute("type").as_string();
    if (type != "PolyData")
      fail_unsupported(path_, "VTKFile type '" + type + "': only PolyData (streamlines as Lines) is read");
    const std::string order = root.attribute("byte_order").as_string("LittleEndian");
    if (order == "BigEndian")
      big_ = true;
    else if (order != "LittleEndian")
      fail(offset(root), "byte_order '" + order + "' (expected LittleEndian or BigEndian)");
    const std::string header = root.attribute("header_type").as_string("UInt32");
    if (header == "UInt64")
      header_size_ = 8;
    else if (header != "UInt32")
      fail(offset(root), "header_type '" + header + "' (expected UInt32 or UInt64)");
    const std::string compressor = root.attribute("compressor").as_string();
    if (compressor == "vtkZLibDataCompressor")
      zlib_ = true;
    else if (!compressor.empty())
      fail_unsupported(path_, "compressor '" + compressor + "' (only vtkZLibDataCompressor, or none, is read)");
    if (app != std::string_view::npos) {
      const std::string encoding = root.child("AppendedData").attribute("encoding").as_string("raw");
      if (encoding == "base64")
        appended_base64_ = true;
      else if (encoding != "raw")
        fail(app, "AppendedData encoding '" + encoding + "' (expected raw or base64)");
    }

    bool lps = false;
    for (const pugi::xpath_node& n : doc.select_nodes("//comment()")) lps = lps || vtk::says_lps(n.node().value());

    const pugi::xml_node poly = root.child("PolyData");
    if (!poly) fail(offset(root), "expected a <PolyData> element");
    std::size_t pieces = 0;
    for (pugi::xml_node p = poly.child("Piece"); p; p = p.next_sibling("Piece")) ++pieces;
    Tractogram t;
    if (pieces > 1) fail_unsupported(path_, std::to_string(pieces) + " pieces: only single-piece PolyData is read");
    if (pieces == 1) read_piece(poly.child("Piece"), t, lps);
    t.source.warnings.insert(t.source.warnings.end(), warnings_.begin(), warnings_.end());
    t.source.dtype = points_type_;
    t.source.header = {{"version", root.attribute("version").as_string()},
                       {"byte_order", big_ ? "BigEndian" : "LittleEndian"},
                       {"header_type", header_size_ == 8 ? "UInt64" : "UInt32"},
                       {"compressor", compressor},
                       {"coordinates", lps ? "LPS (comment says SPACE=LPS): x and y negated" : "as written (RAS)"}};
    return t;
  }

 private:
  [[noreturn]] void fail(std::optional<std::uint64_t> at, const std::string& what) const {
    fail_input(path_, at, what);
  }
  std::uint64_t offset(const pugi::xml_node& n) const { return static_cast<std::uint64_t>(n.offset_debug()); }
  // The '>' that ends the tag starting at `at` ('>' inside quoted attribute values does not), or npos.
  std::size_t tag_end(std::size_t at) const {
    char quote = 0;
    for (std::size_t k = at; k < all_.size(); ++k) {
      if (quote) {
        if (all_[k] == quote) quote = 0;
      } else if (all_[k] == '"' || all_[k] == '\'') {
        quote = all_[k];
      } else if (all_[k] == '>') {
        return k;
      }
    }
    return std::string_view::npos;
  }

  std::uint64_t count_attribute(const pugi::xml_node& n, const char* name) {
    const pugi::xml_attribute a = n.attribute(name);
    if (!a) return 0;
    const std::string s = a.value();
    std::uint64_t v = 0;
    auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (s.empty() || ec != std::errc() || end != s.data() + s.size())
      fail(offset(n), std::string(name) + " is '" + s + "'; expected a non-negative integer");
    return v;
  }

  void read_piece(const pugi::xml_node& piece, Tractogram& t, bool lps) {
    vtk::PolyData p;
    p.point_count = count_attribute(piece, "NumberOfPoints");
    const std::uint64_t lines = count_attribute(piece, "NumberOfLines"),
                        verts = count_attribute(piece, "NumberOfVerts"),
                        polys = count_attribute(piece, "NumberOfPolys"),
                        strips = count_attribute(piece, "NumberOfStrips");
    if (lines == 0 && (polys > 0 || strips > 0))
      fail_unsupported(path_, "a surface mesh (Polys or Strips, no Lines): only streamlines (Lines) are read");
    if (lines == 0 && p.point_count > 0)
      fail_unsupported(path_,
                       "PolyData without Lines: " + std::to_string(p.point_count) + " points but no streamlines");
    if (polys > 0 || strips > 0) warnings_.push_back("Polys and Strips are not streamlines; skipped");
    if (verts > 0) warnings_.push_back(std::to_string(verts) + " Verts cells are not streamlines; skipped");
    p.cells_before_lines = verts;
    const auto cells = [&](std::uint64_t a, std::uint64_t b) {
      return checked_sum(a, b, path_, offset(piece), "NumberOfVerts + NumberOfLines + NumberOfPolys + NumberOfStrips");
    };
    p.cell_count = cells(cells(cells(verts, lines), polys), strips);

    const pugi::xml_node points = piece.child("Points").child("DataArray");
    if (p.point_count > 0) {
      if (!points) fail(offset(piece), "expected <Points><DataArray>");
      if (count_attribute(points, "NumberOfComponents") != 3)
        fail(offset(points), "Points must have NumberOfComponents=\"3\"");
      const XmlDataType pt = parse_data_type(points.attribute("type").as_string());
      if (pt.kind != 'f') fail(offset(points), "Points must be Float32 or Float64");
      points_type_ = points.attribute("type").as_string();
      p.points = decode(points, 3, p.point_count, "Points");
    }
    if (lines > 0) {
      pugi::xml_node conn, offs;
      for (pugi::xml_node a = piece.child("Lines").child("DataArray"); a; a = a.next_sibling("DataArray")) {
        const std::string name = a.attribute("Name").as_string();
        if (name == "connectivity") conn = a;
        if (name == "offsets") offs = a;
      }
      if (!conn || !offs) fail(offset(piece), "expected <Lines> with DataArrays 'connectivity' and 'offsets'");
      const std::vector<double> o = decode(offs, 1, lines, "Lines offsets");
      p.line_offsets.resize(lines + 1);
      for (std::uint64_t k = 0; k < lines; ++k) {
        if (!(o[k] >= static_cast<double>(p.line_offsets[k])) || o[k] >= 9007199254740992.0 || o[k] != std::floor(o[k]))
          fail(offset(offs), "Lines offsets must be non-decreasing integers; offset " + std::to_string(k) + " is " +
                                 std::to_string(o[k]));
        p.line_offsets[k + 1] = static_cast<std::uint64_t>(o[k]);
      }
      p.line_connectivity = decode(conn, 1, p.line_offsets.back(), "Lines connectivity");
    }
    read_arrays(piece.child("PointData"), p.point_count, p.point_data);
    read_arrays(piece.child("CellData"), p.cell_count, p.cell_data);
    vtk::fill_tractogram(t, path_, p, lps);
  }

  void read_arrays(const pugi::xml_node& data, std::uint64_t tuples, std::vector<vtk::DataArray>& out) {
    for (pugi::xml_node a = data.child("DataArray"); a; a = a.next_sibling("DataArray")) {
      vtk::DataArray d;
      d.name = a.attribute("Name").as_string();
      d.components = a.attribute("NumberOfComponents") ? count_attribute(a, "NumberOfComponents") : 1;
      if (d.components == 0) fail(offset(a), "DataArray '" + d.name + "' with NumberOfComponents=\"0\"");
      if (parse_data_type(a.attribute("type").as_string()).kind == 0) {
        warnings_.push_back("array '" + d.name + "' of type " + a.attribute("type").as_string() + " skipped");
        continue;
      }
      if (d.components > vtk::kMaxComponentsKept) {
        warnings_.push_back("array '" + d.name + "' has " + std::to_string(d.components) +
                            " components; only arrays of 1 to 4 are kept as value sets");
        continue;  // not decoded at all: nothing would use it
      }
      d.values = decode(a, d.components, tuples, "DataArray '" + d.name + "'");
      out.push_back(std::move(d));
    }
  }

  // The values of one DataArray: `tuples` x `components`, as double.
  std::vector<double> decode(const pugi::xml_node& a, std::uint64_t components, std::uint64_t tuples,
                             const std::string& what) {
    const XmlDataType type = parse_data_type(a.attribute("type").as_string());
    if (type.kind == 0)
      fail(offset(a), what + ": type '" + std::string(a.attribute("type").as_string()) + "' is not numeric");
    if (a.attribute("NumberOfComponents") && count_attribute(a, "NumberOfComponents") != components)
      fail(offset(a), what + ": NumberOfComponents differs from " + std::to_string(components));
    const std::uint64_t n = checked_product(components, tuples, path_, offset(a), what + " size");
    // Charged once the array's own headers (or text) agree with the count: a count they contradict, or
    // beyond the bytes an uncompressed array has, is malformed (exit 3), not a likely bomb (exit 4).
    auto charge_budget = [&] {
      if (n > budget_ / 8)
        fail_unsupported(path_, what + ": " + std::to_string(n) +
                                    " values exceed what a file of this size may decode to (" +
                                    "64 x its size + 64 MiB in all); refused as a likely decompression bomb");
      budget_ -= 8 * n;
    };
    const std::string format = a.attribute("format").as_string("ascii");
    std::vector<double> out;
    if (format == "ascii") {
      const std::string_view text = a.child_value();
      if (n > text.size() / 2 + 1) fail(offset(a), what + ": " + std::to_string(n) + " values cannot fit in its text");
      charge_budget();
      out.resize(n);
      std::size_t pos = 0;
      for (std::uint64_t k = 0; k < n; ++k) {
        while (pos < text.size() && std::isspace(static_cast<unsigned char>(text[pos]))) ++pos;
        std::size_t stop = pos;
        while (stop < text.size() && !std::isspace(static_cast<unsigned char>(text[stop]))) ++stop;
        if (pos == stop) fail(offset(a), what + ": " + std::to_string(k) + " of " + std::to_string(n) + " values");
        auto [end, ec] = std::from_chars(text.data() + pos, text.data() + stop, out[k]);
        if (ec != std::errc() || end != text.data() + stop)
          fail(offset(a), what + ": expected a number, found '" + std::string(text.substr(pos, stop - pos)) + "'");
        if (type.kind != 'f' && out[k] != std::floor(out[k]))
          fail(offset(a), what + ": expected an integer, found '" + std::string(text.substr(pos, stop - pos)) + "'");
        pos = stop;
      }
      while (pos < text.size() && std::isspace(static_cast<unsigned char>(text[pos]))) ++pos;
      if (pos < text.size())
        fail(offset(a), what + ": more values than the " + std::to_string(n) + " declared (from '" +
                            std::string(text.substr(pos, std::min<std::size_t>(20, text.size() - pos))) + "')");
      return out;
    }
    std::vector<std::uint8_t> bytes;
    if (format == "binary") {
      const std::string_view text = a.child_value();
      // The text's own node gives its file offset (the parsed copy starts with the file's bytes).
      const pugi::xml_node text_node = a.first_child();
      ByteSource src(path_, text, text_node ? offset(text_node) : offset(a), true);
      bytes = block_bytes(src, n * type.size, what, charge_budget);
    } else if (format == "appended") {
      if (appended_at_ == 0) fail(offset(a), what + ": format=\"appended\" but the file has no <AppendedData>");
      const std::uint64_t off = count_attribute(a, "offset");
      if (off > appended_.size())
        fail(offset(a), what + ": appended offset " + std::to_string(off) + " is past the end of the file");
      ByteSource src(path_, appended_.substr(off), appended_at_ + off, appended_base64_);
      bytes = block_bytes(src, n * type.size, what, charge_budget);
    } else {
      fail(offset(a), what + ": format '" + format + "' (expected ascii, binary or appended)");
    }
    out.resize(n);
    for (std::uint64_t k = 0; k < n; ++k)
      out[k] = vtk::load_number(bytes.data() + k * type.size, type.kind, type.size, big_);
    return out;
  }

  // An array's bytes. `charge_budget` is called once the block headers agree with the `expected` size,
  // before anything is allocated for it.
  std::vector<std::uint8_t> block_bytes(ByteSource& src, std::uint64_t expected, const std::string& what,
                                        const std::function<void()>& charge_budget) {
    std::vector<std::uint8_t> out;
    if (!zlib_) {
      const std::uint64_t size = src.read_uint(header_size_, big_);
      if (size != expected)
        src.fail(what + ": the header says " + std::to_string(size) + " bytes; expected " + std::to_string(expected));
      if (expected > src.available())
        src.fail(what + ": " + std::to_string(expected) + " bytes, but at most " + std::to_string(src.available()) +
                 " remain");
      charge_budget();
      out.resize(expected);
      src.read(out.data(), expected);
      return out;
    }
    const std::uint64_t blocks = src.read_uint(header_size_, big_), block = src.read_uint(header_size_, big_),
                        last = src.read_uint(header_size_, big_);
    if (blocks > src.available() / header_size_)
      src.fail(what + ": " + std::to_string(blocks) + " compressed blocks cannot fit in the file");
    std::vector<std::uint64_t> sizes(blocks);
    for (std::uint64_t& s : sizes) {
      s = src.read_uint(header_size_, big_);
      if (s > src.available())
        src.fail(what + ": a compressed block of " + std::to_string(s) + " bytes is larger than the file");
    }
    const std::uint64_t last_size = last == 0 ? block : last;
    if (blocks > 0 && (last_size > block || (blocks - 1) > (expected / std::max<std::uint64_t>(block, 1))))
      src.fail(what + ": inconsistent compression header (block size " + std::to_string(block) + ", last " +
               std::to_string(last) + ")");
    const std::uint64_t total = blocks == 0 ? 0 : (blocks - 1) * block + last_size;
    if (total != expected)
      src.fail(what + ": the compression header says " + std::to_string(total) + " bytes; expected " +
               std::to_string(expected));
    charge_budget();
    out.resize(expected);
    std::vector<std::uint8_t> in;
    std::uint64_t at = 0;
    for (std::uint64_t k = 0; k < blocks; ++k) {
      const std::uint64_t want = k + 1 == blocks ? last_size : block;
      if (want > kZlibMaxRatio * sizes[k] + 64)
        src.fail(what + ": compressed block " + std::to_string(k) + " claims " + std::to_string(want) + " bytes from " +
                 std::to_string(sizes[k]) + ", beyond zlib's maximum ratio (a decompression bomb)");
      in.resize(sizes[k]);
      src.read(in.data(), sizes[k]);
      uLongf got = static_cast<uLongf>(want);
      uLong used = static_cast<uLong>(sizes[k]);
      const int z = uncompress2(out.data() + at, &got, in.data(), &used);
      if (z == Z_OK && got == want && used != sizes[k])
        src.fail(what + ": compressed block " + std::to_string(k) + " ends after " + std::to_string(used) + " of its " +
                 std::to_string(sizes[k]) + " bytes (junk after the zlib stream)");
      if (z != Z_OK || got != want)
        src.fail(what + ": compressed block " + std::to_string(k) + " does not inflate to its declared " +
                 std::to_string(want) + " bytes (zlib: " +
                 (z == Z_BUF_ERROR    ? "more data than declared or truncated"
                  : z == Z_DATA_ERROR ? "corrupt data"
                                      : std::to_string(z)) +
                 ")");
      at += want;
    }
    return out;
  }

  const std::string& path_;
  std::string_view all_;
  std::string_view appended_;
  std::uint64_t appended_at_ = 0;
  bool appended_base64_ = false, big_ = false, zlib_ = false;
  unsigned header_size_ = 4;
  std::uint64_t budget_;
  std::string points_type_;
  std::vector<std::string> warnings_;
};

}  // namespace

Tractogram read_vtp(const std::string& path) {
  MappedFile file(path);
  Tractogram t = VtpParser(path, file.bytes()).parse();
  vtk::describe_source(t, path, "vtp", file.bytes());
  return t;
}

}  // namespace vxl
