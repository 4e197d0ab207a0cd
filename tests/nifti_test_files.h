// Small NIfTI images written with nifti_clib for the tests: masks and label maps with a chosen affine.
#pragma once

#include <array>
#include <cstdint>
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

}  // namespace vxl::test
