#include "converter/readers/nifti_image.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <memory>

#include <nifti2_io.h>

#include "format/error.h"

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

// The header of exactly `path`, checked before nifti_clib sees it: sizeof_hdr 348 (NIfTI-1, magic "n+1" at
// byte 344) or 540 (NIfTI-2, "n+2" at byte 4), in either byte order, and sane dimensions. (nifti_clib
// alone would take an ANALYZE 7.5 header without magic, turn negative dimensions into 1, and, given
// T1.nii.gz, read T1.nii instead when both exist.) The single-file kinds only: the data follow the header.
ImagePtr read_header(const std::string& path) {
  const std::vector<unsigned char> h = read_start(path, 540);
  if (h.size() < 4)
    fail_input(path, 0, "not a NIfTI file: " + std::to_string(h.size()) + " bytes, shorter than any header");
  std::int32_t size = 0;
  std::memcpy(&size, h.data(), 4);
  const bool swap = size != 348 && size != 540;
  auto integer = [&](std::size_t at, int bytes) {
    unsigned char b[8] = {};
    for (int i = 0; i < bytes; ++i) b[i] = h[at + (swap ? bytes - 1 - i : i)];
    std::int64_t v = 0;
    if (bytes == 2) {
      std::int16_t x;
      std::memcpy(&x, b, 2);
      v = x;
    }
    if (bytes == 4) {
      std::int32_t x;
      std::memcpy(&x, b, 4);
      v = x;
    }
    if (bytes == 8) std::memcpy(&v, b, 8);
    return v;
  };
  const std::int64_t sizeof_hdr = integer(0, 4);
  if (sizeof_hdr != 348 && sizeof_hdr != 540)
    fail_input(path, 0,
               "not a NIfTI file: expected sizeof_hdr 348 (NIfTI-1) or 540 (NIfTI-2), got " + std::to_string(size));
  if (h.size() < static_cast<std::size_t>(sizeof_hdr))
    fail_input(path, h.size(),
               "truncated NIfTI header: " + std::to_string(h.size()) + " of " + std::to_string(sizeof_hdr) + " bytes");
  const bool two = sizeof_hdr == 540;
  const std::size_t at = two ? 4 : 344;
  const char* m = reinterpret_cast<const char*>(h.data() + at);
  const char version = two ? '2' : '1';
  if (!(m[0] == 'n' && (m[1] == '+' || m[1] == 'i') && m[2] == version && m[3] == '\0'))
    fail_input(path, at,
               std::string("wrong magic: expected \"n+") + version + "\" for a single-file " +
                   (two ? "NIfTI-2" : "NIfTI-1") + " header");
  if (m[1] == 'i')
    fail_unsupported(path, "a two-file NIfTI header (.hdr with its data in .img); give a single-file .nii or .nii.gz");
  const std::size_t dim_at = two ? 16 : 40, dim_bytes = two ? 8 : 2;
  const std::int64_t ndim = integer(dim_at, int(dim_bytes));
  if (ndim < 1 || ndim > 7)
    fail_input(path, dim_at, "dim[0] (the number of dimensions) is " + std::to_string(ndim) + ", expected 1 to 7");
  for (int a = 1; a <= ndim; ++a) {
    const std::int64_t d = integer(dim_at + a * dim_bytes, int(dim_bytes));
    if (d < 1)
      fail_input(path, dim_at + a * dim_bytes,
                 "dimension " + std::to_string(a) + " of the image is " + std::to_string(d) + ", expected >= 1");
  }
  nifti_image* nim = nullptr;
  if (two) {
    nifti_2_header n2;
    std::memcpy(&n2, h.data(), sizeof n2);
    nim = nifti_convert_n2hdr2nim(n2, path.c_str());
  } else {
    nifti_1_header n1;
    std::memcpy(&n1, h.data(), sizeof n1);
    nim = nifti_convert_n1hdr2nim(n1, path.c_str());
  }
  if (!nim) fail_input(path, std::nullopt, "nifti_clib cannot read the NIfTI header (inconsistent fields)");
  ImagePtr image(nim);
  // The data are in this very file, after the header and its extensions (vox_offset).
  free(nim->fname);
  free(nim->iname);
  nim->fname = nifti_strdup(path.c_str());
  nim->iname = nifti_strdup(path.c_str());
  double vox_offset = 0;
  if (two) {
    vox_offset = double(integer(168, 8));
  } else {
    const std::int32_t bits = static_cast<std::int32_t>(integer(108, 4));
    float f;
    std::memcpy(&f, &bits, 4);
    vox_offset = f;
  }
  const std::size_t header_end = static_cast<std::size_t>(sizeof_hdr) + 4;  // and the extension flags
  if (!std::isfinite(vox_offset) || vox_offset < 0 || vox_offset > 9.0e15)
    fail_input(path, two ? 168 : 108, "vox_offset " + std::to_string(vox_offset) + " is not a byte offset");
  nim->iname_offset = std::max<std::int64_t>(static_cast<std::int64_t>(vox_offset), std::int64_t(header_end));
  return image;
}

template <typename T>
void widen(const void* data, std::size_t n, float* out) {
  const T* p = static_cast<const T*>(data);
  for (std::size_t i = 0; i < n; ++i) out[i] = static_cast<float>(p[i]);
}

// The voxels as float, whatever their type.
std::vector<float> to_float(int datatype, const void* d, std::size_t n, const std::string& path) {
  std::vector<float> v(n);
  const unsigned char* b = static_cast<const unsigned char*>(d);
  switch (datatype) {
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
      for (std::size_t i = 0; i < n; ++i)
        v[i] = static_cast<float>(std::abs(static_cast<const std::complex<double>*>(d)[i]));
      break;
    case DT_RGB24:
      for (std::size_t i = 0; i < n; ++i) v[i] = (float(b[3 * i]) + b[3 * i + 1] + b[3 * i + 2]) / 3.0f;
      break;
    case DT_RGBA32:
      for (std::size_t i = 0; i < n; ++i) v[i] = (float(b[4 * i]) + b[4 * i + 1] + b[4 * i + 2]) / 3.0f;
      break;
    default:
      fail_unsupported(path, std::string("NIfTI data type ") + nifti_datatype_string(datatype) + " (" +
                                 std::to_string(datatype) + ") is not supported");
  }
  return v;
}

}  // namespace

NiftiImage read_nifti_image(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    fail_input(path, std::nullopt, "no such file (expected a NIfTI image)");
  nifti_set_debug_level(0);  // the library would print its own messages; ours name the file and the cause
  ImagePtr nim = read_header(path);
  for (int a = 1; a <= 3; ++a)
    if (nim->dim[a] < 1 || nim->dim[a] > (std::int64_t(1) << 31))
      fail_input(path, std::nullopt,
                 "absurd dimension " + std::to_string(a) + " of the image: " + std::to_string(nim->dim[a]) +
                     " voxels (expected 1 to 2^31)");
  if (nim->nbyper < 1 || nim->nbyper > 32)
    fail_input(path, std::nullopt,
               "bytes per voxel " + std::to_string(nim->nbyper) + " for data type " + std::to_string(nim->datatype));
  // The first volume only (a 4D image's first time point).
  const double voxels = double(nim->dim[1]) * double(nim->dim[2]) * double(nim->dim[3]);
  const double bytes = voxels * nim->nbyper;
  if (nim->iname_offset < 0) fail_input(path, 108, "negative vox_offset " + std::to_string(nim->iname_offset));
  // From the header alone, before anything is inflated: a compressed file's size says nothing of what it
  // claims to hold.
  if (voxels > double(std::int64_t(1) << 30))
    fail_unsupported(path, "the image has " + std::to_string(static_cast<std::uint64_t>(voxels)) +
                               " voxels per volume; at most 2^30 are read");
  // Against the file before reading: a header that claims more than the file holds (truncated, or absurd
  // dimensions) must not make us allocate for it.
  const double wanted = double(nim->iname_offset) + bytes;
  const std::uint64_t have = available_bytes(path, wanted > 1.8e19 ? UINT64_MAX : static_cast<std::uint64_t>(wanted));
  if (double(have) < wanted)
    fail_input(path, have,
               "truncated NIfTI image: the header's " + std::to_string(nim->dim[1]) + "x" +
                   std::to_string(nim->dim[2]) + "x" + std::to_string(nim->dim[3]) + " voxels of " +
                   std::to_string(nim->nbyper) + " bytes at offset " + std::to_string(nim->iname_offset) + " need " +
                   std::to_string(static_cast<std::uint64_t>(wanted)) + " bytes, the file holds " +
                   std::to_string(have));
  // The voxels of the first volume, read here rather than by nifti_image_load, which looks for the data
  // in files beside the one named.
  const std::size_t n = static_cast<std::size_t>(nim->dim[1] * nim->dim[2] * nim->dim[3]);
  std::vector<unsigned char> raw(n * static_cast<std::size_t>(nim->nbyper));
  {
    ZnzCloser z{znzopen(path.c_str(), "rb", 1)};
    if (znz_isnull(z.f) || znzseek(z.f, static_cast<znz_off_t>(nim->iname_offset), SEEK_SET) < 0 ||
        znzread(raw.data(), 1, raw.size(), z.f) != raw.size())
      fail_input(path, static_cast<std::uint64_t>(nim->iname_offset), "cannot read the NIfTI voxel data");
  }
  if (nim->byteorder != nifti_short_order() && nim->swapsize > 1)
    nifti_swap_Nbytes(static_cast<int64_t>(raw.size() / nim->swapsize), nim->swapsize, raw.data());

  NiftiImage v;
  v.path = path;
  v.dims = {nim->dim[1], nim->dim[2], nim->dim[3]};
  v.values = to_float(nim->datatype, raw.data(), n, path);
  raw = {};
  const double slope = nim->scl_slope, inter = nim->scl_inter;
  const bool scaled = slope != 0.0 && std::isfinite(slope) && std::isfinite(inter);
  for (float& x : v.values) {
    if (scaled) x = static_cast<float>(x * slope + inter);
    if (!std::isfinite(x)) x = 0.0f;
  }
  const nifti_dmat44& m = nim->sform_code > 0 ? nim->sto_xyz : nim->qto_xyz;
  const double unit = nim->xyz_units == NIFTI_UNITS_METER ? 1000.0 : nim->xyz_units == NIFTI_UNITS_MICRON ? 0.001 : 1.0;
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 4; ++col) v.voxel_to_ras[4 * row + col] = m.m[row][col] * unit;
  v.voxel_to_ras[15] = 1.0;
  const auto& a = v.voxel_to_ras;
  const double det = a[0] * (a[5] * a[10] - a[6] * a[9]) - a[1] * (a[4] * a[10] - a[6] * a[8]) +
                     a[2] * (a[4] * a[9] - a[5] * a[8]);
  if (!std::isfinite(det) || std::abs(det) < 1e-12 || !std::isfinite(a[3] + a[7] + a[11]))
    fail_input(path, std::nullopt,
               std::string("the ") + (nim->sform_code > 0 ? "sform" : "qform") +
                   " is singular or not finite: no voxel-to-RAS mapping");
  return v;
}

}  // namespace vxl
