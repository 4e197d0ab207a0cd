#include "nifti_volume.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <memory>

#include <nifti2_io.h>

#include "error.h"

namespace vxl {
namespace {

struct ImageDeleter {
  void operator()(nifti_image* n) const { nifti_image_free(n); }
};
using ImagePtr = std::unique_ptr<nifti_image, ImageDeleter>;

struct ZnzCloser {
  znzFile f;
  ~ZnzCloser() {
    if (!znz_isnull(f)) znzclose(f);
  }
};

bool ends_with(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

// Up to `limit` bytes of `path`, through zlib when it is gzipped.
std::vector<unsigned char> read_start(const std::string& path, std::size_t limit) {
  ZnzCloser z{znzopen(path.c_str(), "rb", 1)};
  if (znz_isnull(z.f)) fail_input(path, std::nullopt, "cannot open the file");
  std::vector<unsigned char> bytes(limit);
  bytes.resize(znzread(bytes.data(), 1, limit, z.f));
  return bytes;
}

// How many bytes `path` holds, up to `wanted` (a gzipped file is decompressed to count: its size says
// nothing about its contents).
std::uint64_t available_bytes(const std::string& path, std::uint64_t wanted) {
  if (!ends_with(path, ".gz")) {
    std::error_code ec;
    const auto size = std::filesystem::file_size(path, ec);
    if (ec) fail_input(path, std::nullopt, "cannot read the file's size: " + ec.message());
    return size;
  }
  ZnzCloser z{znzopen(path.c_str(), "rb", 1)};
  if (znz_isnull(z.f)) fail_input(path, std::nullopt, "cannot open the file");
  std::vector<unsigned char> chunk(1 << 20);
  std::uint64_t total = 0;
  while (total < wanted) {
    const std::size_t n = znzread(chunk.data(), 1, chunk.size(), z.f);
    if (n == 0) break;
    total += n;
  }
  return total;
}

// The header must say NIfTI-1 (sizeof_hdr 348, magic "n+1"/"ni1" at byte 344) or NIfTI-2 (540, "n+2"/"ni2"
// at byte 4), in either byte order. nifti_clib alone would also take an ANALYZE 7.5 header (no magic).
void check_magic(const std::string& path) {
  const std::vector<unsigned char> h = read_start(path, 540);
  if (h.size() < 4) fail_input(path, 0, "not a NIfTI file: " + std::to_string(h.size()) + " bytes, shorter than any header");
  std::int32_t size = 0, swapped = 0;
  std::memcpy(&size, h.data(), 4);
  for (int i = 0; i < 4; ++i) reinterpret_cast<unsigned char*>(&swapped)[i] = h[3 - i];
  const std::int32_t sizeof_hdr = (size == 348 || size == 540) ? size : swapped;
  if (sizeof_hdr != 348 && sizeof_hdr != 540)
    fail_input(path, 0, "not a NIfTI file: expected sizeof_hdr 348 (NIfTI-1) or 540 (NIfTI-2), got " + std::to_string(size));
  if (h.size() < static_cast<std::size_t>(sizeof_hdr))
    fail_input(path, h.size(), "truncated NIfTI header: " + std::to_string(h.size()) + " of " + std::to_string(sizeof_hdr) + " bytes");
  const std::size_t at = sizeof_hdr == 348 ? 344 : 4;
  const char* m = reinterpret_cast<const char*>(h.data() + at);
  const char version = sizeof_hdr == 348 ? '1' : '2';
  if (!((m[0] == 'n' && (m[1] == '+' || m[1] == 'i') && m[2] == version && m[3] == '\0')))
    fail_input(path, at, std::string("wrong magic: expected \"n+") + version + "\" or \"ni" + version + "\" for a " +
                             (version == '1' ? "NIfTI-1" : "NIfTI-2") + " header");
}

template <typename T>
void widen(const void* data, std::size_t n, float* out) {
  const T* p = static_cast<const T*>(data);
  for (std::size_t i = 0; i < n; ++i) out[i] = static_cast<float>(p[i]);
}

// The voxels as float, whatever their type.
std::vector<float> to_float(const nifti_image& nim, std::size_t n, const std::string& path) {
  std::vector<float> v(n);
  const void* d = nim.data;
  const unsigned char* b = static_cast<const unsigned char*>(d);
  switch (nim.datatype) {
    case DT_UINT8: widen<std::uint8_t>(d, n, v.data()); break;
    case DT_INT8: widen<std::int8_t>(d, n, v.data()); break;
    case DT_INT16: widen<std::int16_t>(d, n, v.data()); break;
    case DT_UINT16: widen<std::uint16_t>(d, n, v.data()); break;
    case DT_INT32: widen<std::int32_t>(d, n, v.data()); break;
    case DT_UINT32: widen<std::uint32_t>(d, n, v.data()); break;
    case DT_INT64: widen<std::int64_t>(d, n, v.data()); break;
    case DT_UINT64: widen<std::uint64_t>(d, n, v.data()); break;
    case DT_FLOAT32: widen<float>(d, n, v.data()); break;
    case DT_FLOAT64: widen<double>(d, n, v.data()); break;
    case DT_FLOAT128: widen<long double>(d, n, v.data()); break;
    case DT_COMPLEX64:
      for (std::size_t i = 0; i < n; ++i) v[i] = std::abs(static_cast<const std::complex<float>*>(d)[i]);
      break;
    case DT_COMPLEX128:
      for (std::size_t i = 0; i < n; ++i) v[i] = static_cast<float>(std::abs(static_cast<const std::complex<double>*>(d)[i]));
      break;
    case DT_RGB24:
      for (std::size_t i = 0; i < n; ++i) v[i] = (float(b[3 * i]) + b[3 * i + 1] + b[3 * i + 2]) / 3.0f;
      break;
    case DT_RGBA32:
      for (std::size_t i = 0; i < n; ++i) v[i] = (float(b[4 * i]) + b[4 * i + 1] + b[4 * i + 2]) / 3.0f;
      break;
    default:
      fail_unsupported(path, std::string("NIfTI data type ") + nifti_datatype_string(nim.datatype) + " (" +
                                 std::to_string(nim.datatype) + ") is not supported");
  }
  return v;
}

}  // namespace

std::array<float, 2> percentile_window(const std::vector<float>& values, double low, double high) {
  // At most ~4M samples, taken at a fixed stride: the window of a large image in a fraction of a second.
  const std::size_t stride = std::max<std::size_t>(1, values.size() / (std::size_t(1) << 22));
  std::vector<float> picked;
  for (bool nonzero_only : {true, false}) {
    picked.clear();
    for (std::size_t i = 0; i < values.size(); i += stride)
      if (std::isfinite(values[i]) && (!nonzero_only || values[i] != 0.0f)) picked.push_back(values[i]);
    if (!picked.empty()) break;
  }
  if (picked.empty()) return {0, 1};
  auto at = [&](double percent) {
    const std::size_t k = static_cast<std::size_t>(std::llround(percent / 100.0 * double(picked.size() - 1)));
    std::nth_element(picked.begin(), picked.begin() + std::ptrdiff_t(k), picked.end());
    return picked[k];
  };
  return {at(low), at(high)};
}

Volume read_nifti_volume(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) fail_input(path, std::nullopt, "no such file (expected a NIfTI image)");
  check_magic(path);
  nifti_set_debug_level(0);  // the library would print its own messages; ours name the file and the cause
  ImagePtr nim(nifti_image_read(path.c_str(), 0));
  if (!nim) fail_input(path, std::nullopt, "nifti_clib cannot read the NIfTI header (inconsistent fields)");
  for (int a = 1; a <= 3; ++a)
    if (nim->dim[a] < 1 || nim->dim[a] > (std::int64_t(1) << 31))
      fail_input(path, std::nullopt, "absurd dimension " + std::to_string(a) + " of the image: " + std::to_string(nim->dim[a]) +
                                         " voxels (expected 1 to 2^31)");
  if (nim->nbyper < 1 || nim->nbyper > 32)
    fail_input(path, std::nullopt, "bytes per voxel " + std::to_string(nim->nbyper) + " for data type " + std::to_string(nim->datatype));
  // The first volume only (a 4D image's first time point).
  const double voxels = double(nim->dim[1]) * double(nim->dim[2]) * double(nim->dim[3]);
  const double bytes = voxels * nim->nbyper;
  if (nim->iname_offset < 0) fail_input(path, 108, "negative vox_offset " + std::to_string(nim->iname_offset));
  // Against the file before reading: a header that claims more than the file holds (truncated, or absurd
  // dimensions) must not make the library allocate for it.
  const std::string data_file = nim->iname ? nim->iname : path;
  const double wanted = double(nim->iname_offset) + bytes;
  const std::uint64_t have = available_bytes(data_file, wanted > 1.8e19 ? UINT64_MAX : static_cast<std::uint64_t>(wanted));
  if (double(have) < wanted)
    fail_input(data_file, have,
               "truncated NIfTI image: the header's " + std::to_string(nim->dim[1]) + "x" + std::to_string(nim->dim[2]) + "x" +
                   std::to_string(nim->dim[3]) + " voxels of " + std::to_string(nim->nbyper) + " bytes at offset " +
                   std::to_string(nim->iname_offset) + " need " + std::to_string(static_cast<std::uint64_t>(wanted)) +
                   " bytes, the file holds " + std::to_string(have));
  if (voxels > double(std::int64_t(1) << 30))
    fail_unsupported(path, "the image has " + std::to_string(static_cast<std::uint64_t>(voxels)) +
                               " voxels per volume; the viewer shows at most 2^30");
  for (int a = 4; a <= 7; ++a) nim->dim[a] = 1;
  nim->dim[0] = nim->ndim = 3;
  if (nifti_update_dims_from_array(nim.get()) != 0) fail_input(path, std::nullopt, "inconsistent NIfTI dimensions");
  if (nifti_image_load(nim.get()) < 0 || !nim->data)
    fail_input(data_file, static_cast<std::uint64_t>(nim->iname_offset), "cannot read the NIfTI voxel data");

  Volume v;
  v.name = path;
  v.dims = {nim->nx, nim->ny, nim->nz};
  const std::size_t n = static_cast<std::size_t>(nim->nx * nim->ny * nim->nz);
  v.values = to_float(*nim, n, path);
  const double slope = nim->scl_slope, inter = nim->scl_inter;
  const bool scaled = slope != 0.0 && std::isfinite(slope) && std::isfinite(inter);
  for (float& x : v.values) {
    if (scaled) x = static_cast<float>(x * slope + inter);
    if (!std::isfinite(x)) x = 0.0f;
  }
  const nifti_dmat44& m = nim->sform_code > 0 ? nim->sto_xyz : nim->qto_xyz;
  const double unit = nim->xyz_units == NIFTI_UNITS_METER ? 1000.0 : nim->xyz_units == NIFTI_UNITS_MICRON ? 0.001 : 1.0;
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 4; ++col) v.voxel_to_ras[col][row] = m.m[row][col] * unit;  // glm: [column][row]
  const double det = glm::determinant(glm::dmat3(v.voxel_to_ras));
  if (!std::isfinite(det) || std::abs(det) < 1e-12 || !std::isfinite(v.voxel_to_ras[3][0] + v.voxel_to_ras[3][1] + v.voxel_to_ras[3][2]))
    fail_input(path, std::nullopt, std::string("the ") + (nim->sform_code > 0 ? "sform" : "qform") +
                                       " is singular or not finite: no voxel-to-RAS mapping");
  v.window = percentile_window(v.values, 2.0, 98.0);
  return v;
}

}  // namespace vxl
