#include "converter/export/export_trk.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <stdexcept>

#include <zlib.h>
#include <nlohmann/json.hpp>

#include "converter/export/export_trx.h"
#include "converter/export/export_values.h"
#include "converter/export/groups_not_written.h"
#include "converter/readers/trk_header.h"
#include "format/base/atomic_output.h"
#include "format/base/error.h"
#include "format/base/json_limits.h"
#include "format/vxl_streamlines.h"

namespace vxl {
namespace {

static_assert(std::endian::native == std::endian::little, "TRK is written little-endian from native floats");

// The geometry fields of the header.
struct Geometry {
  std::array<std::int16_t, 3> dim{1, 1, 1};
  std::array<float, 3> voxel_size{1, 1, 1}, origin{0, 0, 0};
  std::array<float, 16> vox_to_ras{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  std::string voxel_order = "RAS";  // Latin-1, at most 4 bytes
  std::array<float, 6> image_orientation{0, 0, 0, 0, 0, 0};
  std::array<std::uint8_t, 6> invert_swap{0, 0, 0, 0, 0, 0};
};

// UTF-8 (as the readers made it from Latin-1) back to Latin-1; nullopt for a character beyond U+00FF.
std::optional<std::string> latin1(const std::string& utf8) {
  std::string out;
  for (std::size_t i = 0; i < utf8.size(); ++i) {
    const unsigned char c = static_cast<unsigned char>(utf8[i]);
    if (c < 0x80) {
      out += static_cast<char>(c);
    } else if ((c == 0xC2 || c == 0xC3) && i + 1 < utf8.size() && (utf8[i + 1] & 0xC0) == 0x80) {
      out += static_cast<char>(((c & 0x03) << 6) | (utf8[++i] & 0x3F));
    } else {
      return std::nullopt;
    }
  }
  return out;
}

// `n` numbers from a JSON array, or nullopt (PROV may hold any JSON).
template <typename T, std::size_t N>
std::optional<std::array<T, N>> numbers(const nlohmann::json& j) {
  if (!j.is_array() || j.size() != N) return std::nullopt;
  std::array<T, N> out{};
  for (std::size_t i = 0; i < N; ++i) {
    if (!j[i].is_number()) return std::nullopt;
    const double v = j[i].get<double>();
    if (!std::isfinite(v) || v < double(std::numeric_limits<T>::lowest()) || v > double(std::numeric_limits<T>::max()))
      return std::nullopt;
    out[i] = static_cast<T>(v);
  }
  return out;
}

// A TRK source's header fields, as read_trk recorded them in the provenance.
std::optional<Geometry> trk_source_geometry(const nlohmann::json& header) {
  if (!header.is_object()) return std::nullopt;
  Geometry g;
  const auto dim = numbers<std::int16_t, 3>(header.value("dim", nlohmann::json()));
  const auto size = numbers<float, 3>(header.value("voxel_size", nlohmann::json()));
  const nlohmann::json order = header.value("voxel_order", nlohmann::json());
  const std::optional<std::string> order_text = order.is_string() ? latin1(order.get<std::string>()) : std::nullopt;
  if (!dim || !size || !order_text || order_text->size() > 4) return std::nullopt;
  // Zero voxel sizes record no geometry (read_trk takes such points as RAS mm, nibabel makes them NaN):
  // the reference describes the points better.
  if (std::any_of(size->begin(), size->end(), [](float v) { return v == 0; })) return std::nullopt;
  g.dim = *dim;
  g.voxel_size = *size;
  g.voxel_order = *order_text;
  if (const auto o = numbers<float, 3>(header.value("origin", nlohmann::json()))) g.origin = *o;
  if (const auto iop = numbers<float, 6>(header.value("image_orientation_patient", nlohmann::json())))
    g.image_orientation = *iop;
  static const char* kFlags[6] = {"invert_x", "invert_y", "invert_z", "swap_xy", "swap_yz", "swap_zx"};
  for (int i = 0; i < 6; ++i)
    if (const nlohmann::json f = header.value(kFlags[i], nlohmann::json());
        f.is_number_unsigned() && f.get<unsigned>() < 256)
      g.invert_swap[i] = static_cast<std::uint8_t>(f.get<unsigned>());
  // Version 1 has no vox_to_ras: written as "not recorded" (all zero), which reads back as it did.
  const nlohmann::json rows = header.value("vox_to_ras", nlohmann::json());
  g.vox_to_ras.fill(0);
  if (rows.is_array() && rows.size() == 4)
    for (int r = 0; r < 4; ++r) {
      const auto row = numbers<float, 4>(rows[r]);
      if (!row) return std::nullopt;
      std::copy(row->begin(), row->end(), g.vox_to_ras.begin() + 4 * r);
    }
  return g;
}

// Any other source: the TRX export's reference, its voxel sizes the lengths of the affine's columns.
Geometry reference_geometry(const VxlFile& file, const std::string& out_path) {
  const TrxReference ref = trx_reference(file);
  Geometry g;
  for (int c = 0; c < 3; ++c) {
    if (ref.dimensions[c] > std::numeric_limits<std::int16_t>::max())
      fail_unsupported(out_path, "the reference grid is " + std::to_string(ref.dimensions[c]) + " voxels along axis " +
                                     std::to_string(c) + "; a TRK header holds at most 32767");
    g.dim[c] = static_cast<std::int16_t>(ref.dimensions[c]);
    g.voxel_size[c] =
        static_cast<float>(std::hypot(ref.voxel_to_rasmm[0][c], ref.voxel_to_rasmm[1][c], ref.voxel_to_rasmm[2][c]));
  }
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) g.vox_to_ras[4 * r + c] = static_cast<float>(ref.voxel_to_rasmm[r][c]);
  const std::optional<std::string> code = trk::orientation_code(ref.voxel_to_rasmm);
  if (!code) fail_unsupported(out_path, "the reference's vox_to_ras is singular: no TRK header can describe it");
  g.voxel_order = *code;
  return g;
}

// The sets written, in slot order, and each slot's bytes: one slot per run of sets (export_values.h), a run
// NAME[0..m-1] as "NAME\0m" (nibabel's way, which read_trk reads back as the same names); at most 10 slots
// of 20 Latin-1 bytes. A warning names the sets left out.
std::vector<std::uint32_t> slot_sets(const ValueSets& sets, const char* kind, std::vector<std::string>& warnings,
                                     std::vector<std::string>& slots) {
  std::vector<std::uint32_t> chosen;
  std::string dropped;
  for (const ValueSetRun& run : value_set_runs(sets)) {
    std::optional<std::string> slot = latin1(run.name);
    const bool named =
        slot && !slot->empty() && slot->find('\0') == std::string::npos && slot->back() != ' ' && slot->back() != '\t';
    if (named && run.components > 1) *slot += std::string(1, '\0') + std::to_string(run.components);
    const bool fits = named && slot->size() <= static_cast<std::size_t>(trk::kNameSlotBytes);
    if (fits && slots.size() < static_cast<std::size_t>(trk::kNameSlots)) {
      for (std::uint32_t c = 0; c < run.components; ++c) chosen.push_back(run.first + c);
      slots.push_back(*slot);
    } else {
      dropped += (dropped.empty() ? "'" : ", '") + run.name + "'" + (fits ? "" : " (name)");
    }
  }
  if (!dropped.empty())
    warnings.push_back(std::string(kind) + " value set(s) not written: " + dropped + "; a TRK names at most " +
                       std::to_string(trk::kNameSlots) + ", each in " + std::to_string(trk::kNameSlotBytes) +
                       " Latin-1 bytes (export to .trx for all)");
  return chosen;
}

std::array<std::uint8_t, trk::kHeaderSize> header_bytes(const Geometry& g, const std::vector<std::string>& scalars,
                                                        std::size_t n_scalars,
                                                        const std::vector<std::string>& properties,
                                                        std::size_t n_properties, std::int32_t count) {
  std::array<std::uint8_t, trk::kHeaderSize> h{};
  auto put = [&](std::size_t at, const auto& value) { std::memcpy(h.data() + at, &value, sizeof value); };
  std::memcpy(h.data(), "TRACK", 5);
  put(trk::kOffDim, g.dim);
  put(trk::kOffVoxelSize, g.voxel_size);
  put(trk::kOffOrigin, g.origin);
  put(trk::kOffNScalars, static_cast<std::int16_t>(n_scalars));
  put(trk::kOffNProperties, static_cast<std::int16_t>(n_properties));
  for (std::size_t i = 0; i < scalars.size(); ++i)
    std::memcpy(h.data() + trk::kOffScalarNames + trk::kNameSlotBytes * i, scalars[i].data(), scalars[i].size());
  for (std::size_t i = 0; i < properties.size(); ++i)
    std::memcpy(h.data() + trk::kOffPropertyNames + trk::kNameSlotBytes * i, properties[i].data(),
                properties[i].size());
  put(trk::kOffVoxToRas, g.vox_to_ras);
  std::memcpy(h.data() + trk::kOffVoxelOrder, g.voxel_order.data(), g.voxel_order.size());
  put(trk::kOffImageOrient, g.image_orientation);
  put(trk::kOffInvertSwap, g.invert_swap);
  put(trk::kOffNCount, count);
  put(trk::kOffVersion, std::int32_t{2});
  put(trk::kOffHdrSize, static_cast<std::int32_t>(trk::kHeaderSize));
  return h;
}

// The stored (voxmm) point for a RAS point: the inverse affine's answer in double, rounded to float32. With a
// TRK source's own header, every RAS point came from a stored point through trk::voxmm_point_to_ras, and that
// point lies within two float32 steps of the answer on each axis: it is found, so that a reader gets the very
// same float32 coordinates back (the export is lossless). With another header a RAS point generally has no such
// stored point (voxmm coordinates, measured from the volume's corner, are coarser than RAS ones near the
// origin), and the answer is within one float32 step at the voxmm coordinate's magnitude.
struct VoxmmInverse {
  trk::Mat4 to_voxmm, to_ras;
  bool search;

  std::array<float, 3> voxmm(const float* ras) const {
    const double x = ras[0], y = ras[1], z = ras[2];
    std::array<float, 3> v;
    for (int r = 0; r < 3; ++r)
      v[r] = static_cast<float>(to_voxmm[r][0] * x + to_voxmm[r][1] * y + to_voxmm[r][2] * z + to_voxmm[r][3]);
    if (!search || maps_to(v, ras)) return v;
    constexpr int kSteps[] = {-1, 1, -2, 2, 0};
    for (const int a : kSteps)
      for (const int b : kSteps)
        for (const int c : kSteps) {
          const std::array<float, 3> w{step(v[0], a), step(v[1], b), step(v[2], c)};
          if (maps_to(w, ras)) return w;
        }
    return v;
  }

 private:
  static float step(float f, int k) {
    for (; k > 0; --k) f = std::nextafter(f, INFINITY);
    for (; k < 0; ++k) f = std::nextafter(f, -INFINITY);
    return f;
  }
  bool maps_to(const std::array<float, 3>& v, const float* ras) const {
    for (int r = 0; r < 3; ++r)
      if (std::bit_cast<std::uint32_t>(trk::voxmm_point_to_ras(to_ras, r, v[0], v[1], v[2])) !=
          std::bit_cast<std::uint32_t>(ras[r]))
        return false;
    return true;
  }
};

// The inverse of an affine whose last row is 0 0 0 1, or nullopt when it is singular.
std::optional<trk::Mat4> inverse_affine(const trk::Mat4& a) {
  const double det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
                     a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
                     a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
  if (!std::isfinite(det) || std::fabs(det) < 1e-300) return std::nullopt;
  trk::Mat4 inv{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const int i1 = (j + 1) % 3, i2 = (j + 2) % 3, j1 = (i + 1) % 3, j2 = (i + 2) % 3;
      inv[i][j] = (a[i1][j1] * a[i2][j2] - a[i1][j2] * a[i2][j1]) / det;
    }
  for (int i = 0; i < 3; ++i) inv[i][3] = -(inv[i][0] * a[0][3] + inv[i][1] * a[1][3] + inv[i][2] * a[2][3]);
  inv[3][3] = 1;
  return inv;
}

// The bytes of the file, stored or gzip-deflated into the output.
class TrkSink {
 public:
  TrkSink(const std::string& path, bool gz) : out_(path), gz_(gz) {
    if (gz && deflateInit2(&z_, Z_DEFAULT_COMPRESSION, Z_DEFLATED, 16 + MAX_WBITS, 8, Z_DEFAULT_STRATEGY) != Z_OK)
      throw std::bad_alloc();
  }
  ~TrkSink() {
    if (gz_) deflateEnd(&z_);
  }
  TrkSink(const TrkSink&) = delete;
  TrkSink& operator=(const TrkSink&) = delete;

  void write(const void* data, std::size_t size) {
    if (!gz_) return out_.write(data, size);
    const auto* p = static_cast<const Bytef*>(data);
    while (size > 0) {  // zlib counts in 32 bits
      const std::size_t n = std::min<std::size_t>(size, 1u << 30);
      deflate_all(p, n, Z_NO_FLUSH);
      p += n;
      size -= n;
    }
  }
  void commit() {
    if (gz_) deflate_all(nullptr, 0, Z_FINISH);
    out_.commit();
  }

 private:
  void deflate_all(const Bytef* p, std::size_t n, int flush) {
    z_.next_in = const_cast<Bytef*>(p);
    z_.avail_in = static_cast<uInt>(n);
    int r = Z_OK;
    do {
      z_.next_out = chunk_.data();
      z_.avail_out = static_cast<uInt>(chunk_.size());
      r = deflate(&z_, flush);
      if (r == Z_STREAM_ERROR) throw std::logic_error("zlib deflate: inconsistent stream state");
      out_.write(chunk_.data(), chunk_.size() - z_.avail_out);
    } while (z_.avail_out == 0 || (flush == Z_FINISH && r != Z_STREAM_END));
  }

  AtomicOutputFile out_;
  bool gz_;
  z_stream z_{};
  std::array<Bytef, 1 << 16> chunk_{};
};

}  // namespace

TrkExportSummary export_trk(const VxlFile& file, const std::string& out_path, const StreamlineSubset* subset) {
  TrkExportSummary summary;
  const SubsetCounts counts = subset_counts(file, subset);
  if (counts.streamlines > std::uint64_t(std::numeric_limits<std::int32_t>::max()))
    fail_unsupported(out_path, std::to_string(counts.streamlines) +
                                   " streamlines are more than a TRK header counts (2^31 - 1; export to .trx)");

  // The header: the source's when it was a TRK, else the reference.
  const nlohmann::json prov = parse_json(file.provenance_json(), file.path(), file.provenance_offset(), "PROV");
  std::optional<Geometry> geometry;
  if (prov.is_object() && prov.contains("source") && prov["source"].is_object() &&
      prov["source"].value("format", nlohmann::json()) == "trk")
    geometry = trk_source_geometry(prov["source"].value("header", nlohmann::json()));
  // A TRK source's points were mapped to RAS by this header's affine: each has a stored point to go back to.
  bool source_header = geometry.has_value();
  if (!geometry) geometry = reference_geometry(file, out_path);

  std::vector<std::string> scalar_names, property_names;
  const std::vector<std::uint32_t> scalars =
      slot_sets(file.vertex_values(), "per-point", summary.warnings, scalar_names);
  const std::vector<std::uint32_t> properties =
      slot_sets(file.streamline_values(), "per-streamline", summary.warnings, property_names);
  if (std::optional<std::string> lost = groups_not_written(file, "a TRK", subset)) summary.warnings.push_back(*lost);
  if (std::optional<std::string> lost = group_values_not_written(file, "a TRK")) summary.warnings.push_back(*lost);

  // Empty streamlines are not written, so the count is known only after the walk: the header is built
  // first with the count of the non-empty ones, from the tables.
  std::uint64_t empty = 0;
  {
    const auto strm = file.streamline_first_voxline();
    for (std::uint64_t s = 0; s + 1 < strm.size(); ++s)
      if (in_subset(subset, s) && strm[s] == strm[s + 1]) ++empty;
  }
  const auto count = static_cast<std::int32_t>(counts.streamlines - empty);
  std::vector<std::string> ignored;  // the reader's remarks on a header that is the source's own
  std::array<std::uint8_t, trk::kHeaderSize> header =
      header_bytes(*geometry, scalar_names, scalars.size(), property_names, properties.size(), count);
  std::optional<trk::Mat4> to_voxmm;
  try {
    to_voxmm = inverse_affine(trk::voxmm_to_rasmm(header, out_path, ignored));
  } catch (const Error&) {
    // A provenance header the reader would refuse (PROV may hold anything): the reference instead.
    header = header_bytes(reference_geometry(file, out_path), scalar_names, scalars.size(), property_names,
                          properties.size(), count);
    source_header = false;
    to_voxmm = inverse_affine(trk::voxmm_to_rasmm(header, out_path, ignored));
  }
  if (!to_voxmm) fail_unsupported(out_path, "the header's voxmm to RAS mapping is singular");
  const trk::Mat4 to_ras = trk::voxmm_to_rasmm(header, out_path, ignored);
  const VoxmmInverse inverse{*to_voxmm, to_ras, source_header};

  std::vector<std::vector<float>> point_values;
  if (!scalars.empty()) {
    const std::vector<std::uint64_t> vertices = source_vertex_indices(file, subset);
    for (std::uint32_t k : scalars) point_values.push_back(values_at(file, k, vertices));
  }
  std::vector<std::vector<float>> streamline_values;
  for (std::uint32_t k : properties) {
    const std::span<const float> v = file.streamline_values().values(k);
    streamline_values.push_back(subset ? subset->pick(v) : std::vector<float>(v.begin(), v.end()));
  }

  std::string lower = out_path;
  std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return std::tolower(c); });
  TrkSink out(out_path, lower.ends_with(".gz"));
  out.write(header.data(), header.size());
  std::vector<float> record;
  std::uint64_t point = 0, walked = 0;  // source points and streamlines of the subset so far
  WalkCallbacks cb;
  cb.threads = 0;  // the points decoded on every core
  cb.read_points = [&](std::uint64_t s) { return in_subset(subset, s); };
  cb.streamline = [&](std::uint64_t, std::span<const float> xyz) {
    const std::uint64_t n = xyz.size() / 3;
    const std::uint64_t index = walked++;
    if (n == 0) return;
    if (n > std::uint64_t(std::numeric_limits<std::int32_t>::max()))
      fail_unsupported(out_path, "a streamline of " + std::to_string(n) + " points is more than TRK counts");
    record.clear();
    record.push_back(std::bit_cast<float>(static_cast<std::int32_t>(n)));
    for (std::uint64_t i = 0; i < n; ++i, ++point) {
      const std::array<float, 3> v = inverse.voxmm(&xyz[3 * i]);
      record.insert(record.end(), v.begin(), v.end());
      for (const std::vector<float>& values : point_values) record.push_back(values[point]);
    }
    for (const std::vector<float>& v : streamline_values) record.push_back(v[index]);
    out.write(record.data(), record.size() * sizeof(float));
    ++summary.streamlines;
    summary.points += n;
  };
  walk_streamlines(file, cb);
  out.commit();
  if (empty > 0)
    summary.warnings.push_back(std::to_string(empty) +
                               " streamline(s) without points not written: TRK cannot hold one");
  return summary;
}

}  // namespace vxl
