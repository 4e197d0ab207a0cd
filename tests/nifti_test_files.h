// Small NIfTI images for the tests: masks and label maps with a chosen affine, written with nifti_clib,
// and the bytes of a NIfTI-1 file built field by field, for the tests that damage them.
#pragma once

#include <array>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include <nifti2_io.h>

namespace vxl::test {

// Writes a 3-D NIfTI-1 image of int16 `values` (x fastest) with `voxel_to_ras` (row-major 3 x 4) as its
// sform; `.nii` or `.nii.gz` by the path's name.
inline void write_nifti_int16(const std::string& path, std::array<std::int64_t, 3> dims,
                              const std::vector<std::int16_t>& values, const std::array<double, 12>& voxel_to_ras) {
  const int64_t d[8] = {3, dims[0], dims[1], dims[2], 1, 1, 1, 1};
  nifti_image* nim = nifti_make_new_nim(d, DT_INT16, 1);
  std::copy(values.begin(), values.end(), static_cast<std::int16_t*>(nim->data));
  nifti_dmat44 m{};
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 4; ++col) m.m[row][col] = voxel_to_ras[4 * row + col];
  m.m[3][3] = 1;
  nim->sform_code = NIFTI_XFORM_SCANNER_ANAT;
  nim->sto_xyz = m;
  nim->qform_code = 0;
  nim->xyz_units = NIFTI_UNITS_MM;
  nim->nifti_type = NIFTI_FTYPE_NIFTI1_1;
  nifti_set_filenames(nim, path.c_str(), 0, 1);
  nifti_image_write(nim);
  nifti_image_free(nim);
}

// The bytes of a single-file NIfTI-1 image: its 348-byte header (little-endian, mm, `datatype` of
// `bitpix` bits, `sform` the row-major 3 x 4 voxel-to-RAS with sform_code 1), 4 zero bytes of extension
// flags, then `data` as given (the header claims `dims` whatever `data` holds).
inline std::string nifti1_bytes(std::array<std::int16_t, 3> dims, std::int16_t datatype, std::int16_t bitpix,
                                const std::string& data,
                                const std::array<float, 12>& sform = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0}) {
  std::string h(352, '\0');
  auto put = [&](std::size_t at, auto v) { std::memcpy(h.data() + at, &v, sizeof v); };
  put(0, std::int32_t{348});
  const std::int16_t dim[8] = {3, dims[0], dims[1], dims[2], 1, 1, 1, 1};
  std::memcpy(h.data() + 40, dim, sizeof dim);
  put(70, datatype);
  put(72, bitpix);
  const float pixdim[8] = {1, 1, 1, 1, 1, 1, 1, 1};
  std::memcpy(h.data() + 76, pixdim, sizeof pixdim);
  put(108, 352.0f);           // vox_offset
  put(112, 1.0f);             // scl_slope
  h[123] = NIFTI_UNITS_MM;    // xyzt_units
  put(254, std::int16_t{1});  // sform_code
  std::memcpy(h.data() + 280, sform.data(), sizeof(float) * 12);
  std::memcpy(h.data() + 344, "n+1", 4);
  return h + data;
}

}  // namespace vxl::test
