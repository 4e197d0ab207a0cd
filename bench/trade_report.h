// The records of the speed/accuracy study (bench/trade_study.cpp) and how they are written out: one CSV
// row per rendered image, markdown tables that aggregate them, and the flicker summary.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "viewer/platform/image_metrics.h"

namespace vxl::trade {

// One rendered image, scored against `exact` from the same view at the same opacity.
struct SweepRow {
  std::string mode;             // exact, unsorted, additive, wboit, basic, axis, segsort, axis+diag, random:N
  std::string orders;           // order set of the file it was drawn from
  double voxel_mm = 0;          // voxel size of that file
  bool voxel_dependent = true;  // false: the mode draws the same picture at every voxel size
  std::string view;
  bool oblique = false;
  double opacity = 0;
  ImageScore score;
  double frame_ms = 0;   // draw, glFinish-bounded
  double cpu_ms = 0;     // the renderer's CPU work of the frame (cull, voxel sort, order pick; segsort's segment sort)
  double convert_s = 0;  // `voxlines convert` wall time of the file
  std::uint64_t file_bytes = 0, gpu_bytes = 0;
};

// One mode over one camera motion.
struct FlickerRow {
  std::string motion;  // turntable or wobble
  std::string mode;
  double flicker = 0;         // mean |frame i+1 - frame i| over R, G, B, in levels
  double flicker_excess = 0;  // flicker minus that of exact
  double error_change = 0;    // mean error_change (image_metrics.h) between consecutive frames
  double rmse = 0, ssim = 0;  // means over the turntable's frames, against exact
};

void write_sweep_csv(const std::string& path, const std::vector<SweepRow>& rows);

// Tables: every mode at every voxel size (averaged over views and opacities), then per opacity and per
// view kind at `reference_voxel_mm`. `heading` opens the file.
void write_sweep_markdown(const std::string& path, const std::string& heading, const std::vector<SweepRow>& rows,
                          double reference_voxel_mm);

void write_flicker(const std::string& csv_path, const std::string& md_path, const std::string& heading,
                   const std::vector<FlickerRow>& rows);

double median(std::vector<double> values);

}  // namespace vxl::trade
