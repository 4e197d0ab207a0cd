// The deliberate outcome of every file in ../shared/data/real, shared by the converter and viewer tests.
#pragma once

#include <cctype>
#include <map>
#include <string>

namespace vxl::test {

enum class Outcome { RoundTrip, BadInput, Unsupported };

const std::map<std::string, Outcome>& expected_outcomes() {
  static const std::map<std::string, Outcome> m = {
      // TCK
      {"TractographyFormat__example.tck", Outcome::RoundTrip},
      {"TractographyFormat__stroke.tck", Outcome::RoundTrip},
      {"mrtrix3__tmp.tck", Outcome::RoundTrip},  // 50000 one-point streamlines
      {"nibabel__empty.tck", Outcome::RoundTrip},
      {"nibabel__matlab_nan.tck", Outcome::RoundTrip},  // stale count: warned, data trusted
      {"nibabel__multiline_header_field.tck", Outcome::RoundTrip},
      {"nibabel__no_header_end.tck", Outcome::BadInput},
      {"nibabel__no_header_end_eof.tck", Outcome::BadInput},
      {"nibabel__no_magic_number.tck", Outcome::BadInput},
      {"nibabel__simple.tck", Outcome::RoundTrip},
      {"nibabel__simple_big_endian.tck", Outcome::RoundTrip},
      {"nibabel__standard.tck", Outcome::RoundTrip},
      {"niivue__tract.SLF1_R.tck", Outcome::RoundTrip},
      {"scilpy__disco_centerlines_resampled.tck", Outcome::RoundTrip},
      {"test_data__SIFT_phantom__tracks.tck", Outcome::RoundTrip},
      {"test_data__tckgen__tensor_det.tck", Outcome::RoundTrip},
      {"test_data__tckresample__endpoints.tck", Outcome::RoundTrip},
      {"test_data__tracks.tck", Outcome::RoundTrip},
      {"trx-javascript__gs.tck", Outcome::RoundTrip},
      // TRK
      {"TractographyFormat__example.trk", Outcome::RoundTrip},
      {"TractographyFormat__stroke.trk", Outcome::RoundTrip},
      {"dipy__EuDX_small_25.trk", Outcome::RoundTrip},
      {"dipy__fbc34ca__tracks300.trk", Outcome::RoundTrip},
      {"dipy__tracks300.trk", Outcome::RoundTrip},
      {"nibabel__complex.trk", Outcome::RoundTrip},
      {"nibabel__complex_big_endian.trk", Outcome::RoundTrip},
      {"nibabel__empty.trk", Outcome::RoundTrip},
      {"nibabel__simple.trk", Outcome::RoundTrip},
      {"nibabel__standard.LPS.trk", Outcome::RoundTrip},
      {"nibabel__standard.trk", Outcome::RoundTrip},
      {"niivue__C_PHP.trk.gz", Outcome::RoundTrip},
      {"niivue__colby.trk", Outcome::RoundTrip},  // all-zero vox_to_ras: warned
      {"niivue__stroke.trk.gz", Outcome::RoundTrip},
      {"niivue__tract.IFOF_R.trk", Outcome::RoundTrip},
      {"scilpy__reconstruction_metrics.trk", Outcome::RoundTrip},
      {"scilpy__tracking.trk", Outcome::RoundTrip},
      {"trx-javascript__gs.trk", Outcome::RoundTrip},
      // TRX
      {"niivue__colby.trx", Outcome::RoundTrip},
      {"niivue__dps.trx", Outcome::RoundTrip},
      {"niivue__dpsv.trx", Outcome::RoundTrip},
      {"niivue__sub-01_ses-01_dwi_space-RASMM_model-probCSD_algo-AFQ_tractography.trx", Outcome::RoundTrip},
      {"niivue__tests__dpsv.trx", Outcome::RoundTrip},
      {"trx-javascript__gs.trx", Outcome::RoundTrip},
      {"trx-python__small.trx", Outcome::RoundTrip},
      {"trx-python__small_compressed.trx", Outcome::RoundTrip},
      {"trx-python__small_fldr.trx", Outcome::RoundTrip},  // directory form
      // VTK (legacy) and VTP (XML)
      {"SlicerDMRI__cluster_00750.vtp", Outcome::RoundTrip},
      {"SlicerDMRI__fiber_vtk.vtk", Outcome::RoundTrip},
      {"SlicerDMRI__tractography.vtk", Outcome::RoundTrip},
      {"SlicerDMRI__tractography.vtp", Outcome::RoundTrip},
      {"TractographyFormat__example.vtk", Outcome::RoundTrip},
      {"TractographyFormat__example.vtp", Outcome::RoundTrip},
      {"TractographyFormat__stroke.vtk", Outcome::RoundTrip},
      {"niivue__tract.FAT_R.vtk", Outcome::RoundTrip},
      {"surf-ice__helix.vtk", Outcome::RoundTrip},
      {"test_data__tckconvert__empty.vtk", Outcome::RoundTrip},  // POINTS 0, no title line
      {"test_data__tckconvert__out0.vtk", Outcome::RoundTrip},
      {"test_data__tckconvert__tracks-binary.vtk", Outcome::RoundTrip},
      {"tract_querier__CG_L.vtk", Outcome::RoundTrip},
      {"trx-javascript__gs.vtk", Outcome::RoundTrip},
      {"ukftractography__1T_fiber.vtk", Outcome::RoundTrip},
      {"ukftractography__seeds_tc.vtk", Outcome::RoundTrip},
      {"ukftractography__ukf__seeds_tc.vtk", Outcome::RoundTrip},
      {"whitematteranalysis__brain_0001.vtk", Outcome::RoundTrip},
      {"whitematteranalysis__clusters_brain_0001.vtp", Outcome::RoundTrip},
      // Not streamline files we read: a VTK surface mesh (POLYGONS), TSF (scalars), the index.
      {"niivue__issue1298.vtk", Outcome::Unsupported},  // POLYGONS, no LINES
      {"SOURCES.md", Outcome::Unsupported},
      {"niivue__mni152.SLF1_R.tsf", Outcome::Unsupported},
      {"test_data__afd.tsf", Outcome::Unsupported},
      {"test_data__tcksample__out.tsf", Outcome::Unsupported},
  };
  return m;
}

// A fixture file name as a GoogleTest parameter name (letters, digits, underscores).
inline std::string fixture_test_name(const std::string& file) {
  std::string s = file;
  for (char& c : s)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return s;
}

}  // namespace vxl::test
