#include "converter/readers/mrtrix_image.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <optional>
#include <vector>

#include "converter/readers/image_file.h"
#include "converter/readers/mrtrix_header.h"
#include "converter/readers/regular_file.h"
#include "converter/readers/voxel_samples.h"
#include "format/base/error.h"
#include "format/base/mapped_file.h"

namespace vxl {
namespace {

// Longer than any real header (a DW scheme of thousands of lines is a few hundred KB).
constexpr std::size_t kMaxHeaderBytes = std::size_t(16) << 20;
constexpr std::size_t kMaxAxes = 16;

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = s.find(',', start);
    std::string piece = s.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    piece.erase(0, piece.find_first_not_of(" \t"));
    piece.erase(piece.find_last_not_of(" \t") + 1);
    out.push_back(piece);
    if (comma == std::string::npos) return out;
    start = comma + 1;
  }
}

[[noreturn]] void bad_field(const std::string& path, const std::string& key, const std::string& value,
                            const std::string& expected) {
  fail_input(path, std::nullopt, "MRtrix image '" + key + ": " + value + "': expected " + expected);
}

std::vector<double> numbers(const std::string& path, const std::string& key, const std::string& value) {
  std::vector<double> out;
  for (const std::string& piece : split(value)) {
    double v = 0;
    const auto [end, ec] = std::from_chars(piece.data(), piece.data() + piece.size(), v);
    if (piece.empty() || ec != std::errc() || end != piece.data() + piece.size() || !std::isfinite(v))
      bad_field(path, key, value, "comma-separated finite numbers");
    out.push_back(v);
  }
  return out;
}

struct Datatype {
  SampleType type;
  bool big_endian;
};

Datatype datatype(const std::string& path, const std::string& text) {
  std::string name = lower(text);
  bool big = false;
  if (name.ends_with("le") || name.ends_with("be")) {
    big = name.ends_with("be");
    name.resize(name.size() - 2);
  }
  static const std::pair<const char*, SampleType> kTypes[] = {
      {"int8", SampleType::kInt8},       {"uint8", SampleType::kUInt8},        {"int16", SampleType::kInt16},
      {"uint16", SampleType::kUInt16},   {"int32", SampleType::kInt32},        {"uint32", SampleType::kUInt32},
      {"int64", SampleType::kInt64},     {"uint64", SampleType::kUInt64},      {"float32", SampleType::kFloat32},
      {"float64", SampleType::kFloat64}, {"cfloat32", SampleType::kComplex64}, {"cfloat64", SampleType::kComplex128},
  };
  for (const auto& [n, t] : kTypes)
    if (name == n) return {t, big};
  if (name == "bit")
    fail_unsupported(path,
                     "MRtrix image datatype Bit (one bit per voxel) is not supported; convert it with "
                     "mrconvert -datatype uint8 first");
  fail_unsupported(path, "MRtrix image datatype '" + text +
                             "' is not supported (expected Int8, UInt8, Int16, UInt16, Int32, UInt32, Int64, UInt64, "
                             "Float32, Float64, CFloat32 or CFloat64, with LE or BE)");
}

// The header's bytes, taken from the stream up to and including the END line (`ended`), or to the end of
// the stream.
std::vector<std::uint8_t> header_bytes(const std::string& path, GzipBytes& stream, bool& ended) {
  std::vector<std::uint8_t> bytes;
  ended = false;
  while (bytes.size() < kMaxHeaderBytes) {
    const std::uint8_t* p = stream.take(1);
    if (!p) return bytes;
    bytes.push_back(*p);
    if (*p != '\n') continue;
    const std::size_t line_end = bytes.size() - 1;
    std::size_t start = line_end;
    while (start > 0 && bytes[start - 1] != '\n') --start;
    std::string line(bytes.begin() + std::ptrdiff_t(start), bytes.begin() + std::ptrdiff_t(line_end));
    line.erase(line.find_last_not_of(" \t\r") + 1);
    line.erase(0, line.find_first_not_of(" \t"));
    if (line == "END") {
      ended = true;
      return bytes;
    }
  }
  fail_input(path, kMaxHeaderBytes, "MRtrix image header has no END line in its first 16 MiB");
}

// Where axis a's stored index c lands in the image, for the layout's order and directions.
struct Layout {
  std::vector<std::size_t> order;  // the axes, fastest first
  std::vector<bool> reversed;      // per axis
};

Layout layout(const std::string& path, const std::string& text, std::size_t axes) {
  Layout l;
  l.reversed.assign(axes, false);
  const std::vector<std::string> pieces = split(text);
  if (pieces.size() != axes) bad_field(path, "layout", text, std::to_string(axes) + " entries, one per axis");
  std::vector<int> rank(axes, -1);
  for (std::size_t a = 0; a < axes; ++a) {
    const std::string& p = pieces[a];
    int r = -1;
    const char* digits = p.data() + (!p.empty() && (p[0] == '+' || p[0] == '-') ? 1 : 0);
    const auto [end, ec] = std::from_chars(digits, p.data() + p.size(), r);
    if (p.size() < 2 || (p[0] != '+' && p[0] != '-') || ec != std::errc() || end != p.data() + p.size() || r < 0 ||
        r >= int(axes) || std::count(rank.begin(), rank.end(), r) > 0)
      bad_field(path, "layout", text, "a sign and a distinct rank 0 to " + std::to_string(axes - 1) + " per axis");
    rank[a] = r;
    l.reversed[a] = p[0] == '-';
  }
  for (int r = 0; r < int(axes); ++r)
    l.order.push_back(static_cast<std::size_t>(std::find(rank.begin(), rank.end(), r) - rank.begin()));
  return l;
}

// The geometry as MRtrix derives it from 'transform:' (centred without it) and 'vox:' (image_geometry.h), its
// voxel-to-RAS mapping checked.
ImageGeometry geometry(const std::string& path, const MrtrixHeader& h, const std::vector<double>& vox,
                       const std::array<std::int64_t, 3>& dims) {
  std::optional<std::array<double, 12>> transform;
  if (h.fields.contains("transform")) {
    const auto& rows = h.fields["transform"];
    if (rows.size() != 3)
      fail_input(path, std::nullopt,
                 "MRtrix image header has " + std::to_string(rows.size()) + " 'transform:' rows, expected 3");
    transform.emplace();
    for (int r = 0; r < 3; ++r) {
      const std::string row = rows[std::size_t(r)].get<std::string>();
      const std::vector<double> v = numbers(path, "transform", row);
      if (v.size() != 4) bad_field(path, "transform", row, "4 numbers per row");
      for (int c = 0; c < 4; ++c) (*transform)[std::size_t(4 * r + c)] = v[std::size_t(c)];
    }
  }
  std::array<double, 3> sizes{1.0, 1.0, 1.0};
  for (std::size_t a = 0; a < std::min<std::size_t>(3, vox.size()); ++a) sizes[a] = vox[a];
  if (transform) {  // refused as stored (MRtrix would replace a non-finite one), then as MRtrix makes it
    std::array<double, 16> stored{};
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c)
        stored[std::size_t(4 * r + c)] = (*transform)[std::size_t(4 * r + c)] * (c < 3 ? sizes[std::size_t(c)] : 1.0);
    stored[15] = 1.0;
    check_voxel_to_ras(path, stored, "the transform and vox");
  }
  const ImageGeometry g = mrtrix_geometry(transform, sizes, dims);
  check_voxel_to_ras(path, g.voxel_to_ras(), "the transform and vox");
  return g;
}

// The sizes of the axes ('dim:'), whole numbers 1 to 2^31 written in digits (MRtrix reads them as integers:
// "4e1" is none), at most kMaxAxes of them.
std::vector<std::int64_t> dimensions(const std::string& path, const std::string& text) {
  std::vector<std::int64_t> dim;
  for (const std::string& piece : split(text)) {
    std::int64_t d = 0;
    const auto [end, ec] = std::from_chars(piece.data(), piece.data() + piece.size(), d);
    if (piece.empty() || ec != std::errc() || end != piece.data() + piece.size() || d < 1 ||
        d > (std::int64_t(1) << 31))
      bad_field(path, "dim", text, "whole numbers 1 to 2^31, in digits");
    dim.push_back(d);
  }
  if (dim.size() > kMaxAxes) bad_field(path, "dim", text, "at most 16 axes");
  return dim;
}

// 'scaling: OFFSET,MULTIPLIER' (value = offset + multiplier * stored); {0, 1} without it.
std::pair<double, double> scaling(const std::string& path, const MrtrixHeader& h) {
  const auto s = h.last("scaling");
  if (!s) return {0.0, 1.0};
  const std::vector<double> v = numbers(path, "scaling", *s);
  if (v.size() != 2) bad_field(path, "scaling", *s, "OFFSET,MULTIPLIER");
  return {v[0], v[1]};
}

}  // namespace

VolumeImage read_mrtrix_image(const std::string& path, const ImageLimits& limits) {
  ImageFile file(path, "an MRtrix");
  GzipBytes& stream = file.bytes();
  const bool gz = file.gzipped();

  bool ended = false;
  std::vector<std::uint8_t> text = header_bytes(path, stream, ended);
  std::uint64_t known_size = gz ? (stream.at_end() ? text.size() : UINT64_MAX) : file.file_size();
  // MRtrix ends a .mih (a header alone) at the end of the file, without an END line.
  const bool mih = lower(path).ends_with(".mih");
  if (mih && !gz && !ended) {
    if (!text.empty() && text.back() != '\n') text.push_back('\n');
    for (char c : std::string("END\n")) text.push_back(static_cast<std::uint8_t>(c));
    known_size = text.size();
  }
  const std::optional<MrtrixHeader> parsed = parse_mrtrix_header(path, text, known_size, kImageFile);
  if (!parsed) fail_input(path, text.size(), "MRtrix image header has no 'END' line");
  const MrtrixHeader& h = *parsed;
  auto field = [&](const char* key) -> std::string {
    const std::optional<std::string> v = h.last(key);
    if (!v) fail_input(path, std::nullopt, "MRtrix image header lacks '" + std::string(key) + ":'");
    return *v;
  };

  const std::vector<std::int64_t> dim = dimensions(path, field("dim"));
  const std::vector<double> vox = numbers(path, "vox", field("vox"));
  if (vox.size() != dim.size()) bad_field(path, "vox", field("vox"), std::to_string(dim.size()) + " sizes, as dim");
  for (std::size_t a = 0; a < std::min<std::size_t>(3, vox.size()); ++a)
    if (!(vox[a] > 0)) bad_field(path, "vox", field("vox"), "positive voxel sizes (mm)");
  // MRtrix writes 'layout:' in every image header and will not read one without it.
  const Layout order = layout(path, field("layout"), dim.size());
  const Datatype type = datatype(path, h.datatype);
  const std::size_t axes = dim.size();
  std::array<std::int64_t, 3> dims{1, 1, 1};
  for (std::size_t a = 0; a < std::min<std::size_t>(3, axes); ++a) dims[a] = dim[a];
  check_image_size(path, dims, limits);

  const ImageGeometry image_geometry = geometry(path, h, vox, dims);
  const auto [inter, slope] = scaling(path, h);

  // The file offset (in samples) of each axis' step, and of the last sample of the first volume.
  const std::size_t size = sample_bytes(type.type);
  std::vector<double> stride(axes);
  double step = 1;
  for (std::size_t a : order.order) stride[a] = step, step *= double(dim[a]);
  double last = 0;
  for (std::size_t a = 0; a < axes; ++a)
    if (a < 3 || order.reversed[a]) last += double(dim[a] - 1) * stride[a];
  const double wanted = double(h.data_offset) + (last + 1) * double(size);
  file.check_claim(wanted, "the header's data");

  // The data: this stream, or the file a .mih names beside it.
  std::optional<MappedFile> other;
  std::optional<GzipBytes> other_stream;
  GzipBytes* data = &stream;
  std::string data_path = path;
  std::uint64_t skip = h.data_offset - (h.data_file == "." ? text.size() : 0);
  if (h.data_file != ".") {
    if (gz) fail_unsupported(path, "a gzipped MRtrix header naming another data file");
    data_path = (std::filesystem::path(path).parent_path() / h.data_file).string();
    if (std::error_code ec; !std::filesystem::exists(data_path, ec))
      fail_input(path, std::nullopt, "the data file '" + h.data_file + "' it names does not exist");
    require_regular_file(data_path);
    other.emplace(data_path);
    other_stream.emplace(other->bytes());
    data = &*other_stream;
  }
  const auto truncated = [&](std::uint64_t at) {
    fail_input(data_path, at,
               "truncated MRtrix image data: the header's " + field("dim") + " voxels of " + std::to_string(size) +
                   " bytes at offset " + std::to_string(h.data_offset) + " need " +
                   std::to_string(static_cast<std::uint64_t>(wanted)) + " bytes, the file holds " + std::to_string(at) +
                   file.offset_note());
  };
  const std::uint64_t data_size = other ? other->size() : file.file_size();
  if (!gz && wanted > double(data_size)) truncated(data_size);
  if (!data->skip(skip)) truncated(data->offset() + data->left());

  VolumeImage v;
  v.path = path;
  v.dims = dims;
  v.geometry = image_geometry;
  v.voxel_to_ras = image_geometry.voxel_to_ras();
  const std::size_t n = static_cast<std::size_t>(dims[0] * dims[1] * dims[2]);
  reserve_values(v, path, n);
  v.values.assign(n, 0.0f);
  // Through the stored samples in file order (an odometer over the axes, fastest first), keeping those of
  // the first volume.
  const std::int64_t samples = static_cast<std::int64_t>(last) + 1;
  const std::int64_t destination_step[3] = {1, dims[0], dims[0] * dims[1]};
  std::vector<std::int64_t> stored(axes, 0);
  const std::size_t block = std::max<std::size_t>(1, (std::size_t(1) << 20) / size);
  std::vector<float> converted(block);
  for (std::int64_t at = 0; at < samples;) {
    const std::size_t count = static_cast<std::size_t>(std::min<std::int64_t>(std::int64_t(block), samples - at));
    const std::uint8_t* p = data->take(count * size);
    if (!p) truncated(data->offset() + data->left());
    samples_to_float(type.type, type.big_endian, p, count, converted.data(), slope, inter);
    for (std::size_t i = 0; i < count; ++i) {
      bool first_volume = true;
      std::int64_t to = 0;
      for (std::size_t a = 0; a < axes; ++a) {
        const std::int64_t index = order.reversed[a] ? dim[a] - 1 - stored[a] : stored[a];
        if (a < 3)
          to += index * destination_step[a];
        else if (index != 0)
          first_volume = false;
      }
      if (first_volume) v.values[static_cast<std::size_t>(to)] = converted[i];
      for (std::size_t a : order.order) {
        if (++stored[a] < dim[a]) break;
        stored[a] = 0;
      }
    }
    at += std::int64_t(count);
  }
  file.finish();
  return v;
}

}  // namespace vxl
