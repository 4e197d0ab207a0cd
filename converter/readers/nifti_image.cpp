#include "converter/readers/nifti_image.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <optional>
#include <vector>

#include <nifti2_io.h>

#include "converter/readers/image_file.h"
#include "converter/readers/voxel_samples.h"
#include "format/base/error.h"

namespace vxl {
namespace {

struct ImageDeleter {
  void operator()(nifti_image* n) const { nifti_image_free(n); }
};
using ImagePtr = std::unique_ptr<nifti_image, ImageDeleter>;

// The file's voxel type, or a refusal naming it (exit 4).
SampleType sample_type(int datatype, const std::string& path) {
  switch (datatype) {
    case DT_UINT8: return SampleType::kUInt8;
    case DT_INT8: return SampleType::kInt8;
    case DT_INT16: return SampleType::kInt16;
    case DT_UINT16: return SampleType::kUInt16;
    case DT_INT32: return SampleType::kInt32;
    case DT_UINT32: return SampleType::kUInt32;
    case DT_INT64: return SampleType::kInt64;
    case DT_UINT64: return SampleType::kUInt64;
    case DT_FLOAT32: return SampleType::kFloat32;
    case DT_FLOAT64: return SampleType::kFloat64;
    case DT_FLOAT128: return SampleType::kFloat128;
    case DT_COMPLEX64: return SampleType::kComplex64;
    case DT_COMPLEX128: return SampleType::kComplex128;
    case DT_RGB24: return SampleType::kRgb24;
    case DT_RGBA32: return SampleType::kRgba32;
    default: break;
  }
  const bool known = datatype == DT_BINARY || datatype == DT_COMPLEX256;
  fail_unsupported(path,
                   std::string("NIfTI datatype ") + std::to_string(datatype) +
                       (known ? std::string(" (") + nifti_datatype_string(datatype) + ")" : std::string()) +
                       " is not supported" +
                       (known ? "; convert the image to UINT8, INT16 or FLOAT32 first" : ": it is no NIfTI datatype"));
}

// The header of exactly `path`, checked before nifti_clib sees it: sizeof_hdr 348 (NIfTI-1, magic "n+1" at
// byte 344) or 540 (NIfTI-2, "n+2" at byte 4), in either byte order, and sane dimensions. (nifti_clib
// alone would take an ANALYZE 7.5 header without magic and turn negative dimensions into 1.) The
// single-file kinds only: the data follow the header. `h` holds the header's bytes on return.
ImagePtr read_header(const std::string& path, GzipBytes& stream, std::vector<unsigned char>& h) {
  const std::uint8_t* start = stream.take(4);
  if (!start)
    fail_input(path, 0, "not a NIfTI file: " + std::to_string(stream.left()) + " bytes, shorter than any header");
  h.assign(start, start + 4);
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
  const std::uint8_t* rest = stream.take(static_cast<std::size_t>(sizeof_hdr) - 4);
  if (!rest)
    fail_input(path, 4 + stream.left(),
               "truncated NIfTI header: " + std::to_string(4 + stream.left()) + " of " + std::to_string(sizeof_hdr) +
                   " bytes");
  h.insert(h.end(), rest, rest + sizeof_hdr - 4);
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
  // The datatype before nifti_clib, which refuses one it does not know with a message of its own.
  (void)sample_type(static_cast<int>(integer(two ? 12 : 70, 2)), path);
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
  // The data are in this very file, after the header and its extensions.
  nim->iname_offset = std::max<std::int64_t>(static_cast<std::int64_t>(vox_offset), std::int64_t(header_end));
  return image;
}

// The header's geometry as MRtrix derives it (image_geometry.h: the sform, else the qform, else centred; the
// units ignored), its voxel-to-RAS mapping checked.
ImageGeometry geometry(const nifti_image& nim, const std::array<std::int64_t, 3>& dims, const std::string& path) {
  NiftiGeometryFields f;
  f.sform_code = nim.sform_code;
  f.qform_code = nim.qform_code;
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 4; ++col) f.srow[std::size_t(row)][std::size_t(col)] = nim.sto_xyz.m[row][col];
  f.quatern_b = nim.quatern_b;
  f.quatern_c = nim.quatern_c;
  f.quatern_d = nim.quatern_d;
  f.qoffset = {nim.qoffset_x, nim.qoffset_y, nim.qoffset_z};
  // pixdim[0]'s sign, which nifti_clib keeps as qfac (-1 when negative, as MRtrix reads it).
  f.pixdim = {nim.qfac, nim.pixdim[1], nim.pixdim[2], nim.pixdim[3]};
  // A damaged sform is refused as stored (MRtrix would replace a non-finite one, with a warning), then what
  // MRtrix makes of the header.
  if (nim.sform_code > 0) {
    std::array<double, 16> stored{};
    for (int row = 0; row < 3; ++row)
      for (int col = 0; col < 4; ++col) stored[std::size_t(4 * row + col)] = nim.sto_xyz.m[row][col];
    stored[15] = 1.0;
    check_voxel_to_ras(path, stored, "the sform");
  }
  const ImageGeometry g = nifti_geometry(f, dims);
  check_voxel_to_ras(path, g.voxel_to_ras(),
                     nim.sform_code > 0   ? "the sform"
                     : nim.qform_code > 0 ? "the qform"
                                          : "pixdim");
  return g;
}

}  // namespace

VolumeImage read_nifti_image(const std::string& path, const ImageLimits& limits) {
  nifti_set_debug_level(0);  // the library would print its own messages; ours name the file and the cause
  ImageFile file(path, "a NIfTI");
  GzipBytes& stream = file.bytes();

  std::vector<unsigned char> h;
  const ImagePtr nim = read_header(path, stream, h);
  const std::array<std::int64_t, 3> dims{nim->dim[1], nim->dim[2], nim->dim[3]};
  for (int a = 0; a < 3; ++a)
    if (dims[a] < 1 || dims[a] > (std::int64_t(1) << 31))
      fail_input(path, std::nullopt,
                 "absurd dimension " + std::to_string(a + 1) + " of the image: " + std::to_string(dims[a]) +
                     " voxels (expected 1 to 2^31)");
  const SampleType type = sample_type(nim->datatype, path);
  // From the header alone, before anything is inflated or allocated.
  check_image_size(path, dims, limits);
  const ImageGeometry image_geometry = geometry(*nim, dims, path);
  const std::size_t n = static_cast<std::size_t>(dims[0] * dims[1] * dims[2]);  // the first volume
  const std::size_t size = sample_bytes(type);
  const std::uint64_t start = static_cast<std::uint64_t>(nim->iname_offset);
  const double wanted = double(start) + double(n) * double(size);
  file.check_claim(wanted, "the header's " + std::to_string(dims[0]) + "x" + std::to_string(dims[1]) + "x" +
                               std::to_string(dims[2]) + " voxels of " + std::to_string(size) + " bytes");
  const auto truncated = [&](std::uint64_t at) {
    fail_input(path, at,
               "truncated NIfTI image: the header's " + std::to_string(dims[0]) + "x" + std::to_string(dims[1]) + "x" +
                   std::to_string(dims[2]) + " voxels of " + std::to_string(size) + " bytes at offset " +
                   std::to_string(start) + " need " + std::to_string(static_cast<std::uint64_t>(wanted)) +
                   " bytes, the file holds " + std::to_string(at) + file.offset_note());
  };
  if (!file.gzipped() && wanted > double(file.file_size())) truncated(file.file_size());
  if (!stream.skip(start - h.size())) truncated(stream.offset() + stream.left());

  VolumeImage v;
  v.path = path;
  v.dims = dims;
  v.geometry = image_geometry;
  v.voxel_to_ras = image_geometry.voxel_to_ras();
  const bool swap = nim->byteorder != nifti_short_order();
  const double slope = nim->scl_slope, inter = nim->scl_inter;
  const bool scaled = slope != 0.0 && std::isfinite(slope) && std::isfinite(inter);
  // A block at a time, in the file's type: the destination grows as data arrive, so that a damaged stream
  // is refused having allocated little more than what it held.
  reserve_values(v, path, n);
  const std::size_t block = std::max<std::size_t>(1, (std::size_t(1) << 20) / size);
  while (v.values.size() < n) {
    const std::size_t count = std::min(block, n - v.values.size());
    const std::uint8_t* p = stream.take(count * size);
    if (!p) truncated(stream.offset() + stream.left());
    const std::size_t done = v.values.size();
    v.values.resize(done + count);
    samples_to_float(type, swap, p, count, v.values.data() + done, scaled ? slope : 1.0, scaled ? inter : 0.0);
  }
  // The rest of a gzip stream (a 4D image's other volumes) is inflated and dropped: its CRC, and what
  // follows it, are checked as for any gzip file.
  file.finish();
  return v;
}

}  // namespace vxl
