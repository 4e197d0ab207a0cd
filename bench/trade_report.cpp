#include "bench/trade_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <stdexcept>

namespace vxl::trade {

namespace {

// Display order of the modes: the reference, the baselines, then ours from cheapest to richest, and last
// segsort, the bound the order sets are measured against.
int mode_rank(const std::string& mode) {
  static const char* const order[] = {"exact", "unsorted", "additive", "wboit", "basic", "axis", "axis+diag"};
  for (int i = 0; i < int(std::size(order)); ++i)
    if (mode == order[i]) return i;
  if (mode == "segsort") return int(std::size(order)) + 1;
  return int(std::size(order));  // random:N and anything else, after them
}

FILE* open_out(const std::string& path) {
  FILE* f = std::fopen(path.c_str(), "w");
  if (!f) throw std::runtime_error("cannot write " + path);
  return f;
}

double mean_of(const std::vector<const SweepRow*>& rows, const std::function<double(const SweepRow&)>& get) {
  double sum = 0;
  for (const SweepRow* r : rows) sum += get(*r);
  return rows.empty() ? 0 : sum / double(rows.size());
}

const double kMiB = 1048576.0;

}  // namespace

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

void write_sweep_csv(const std::string& path, const std::vector<SweepRow>& rows) {
  FILE* f = open_out(path);
  std::fprintf(f,
               "mode,orders,voxel_mm,voxel_dependent,view,oblique,opacity,rmse,psnr_db,mean_abs,max_abs,ssim,frame_ms,"
               "cpu_ms,convert_s,file_bytes,gpu_bytes\n");
  for (const SweepRow& r : rows)
    std::fprintf(f, "%s,%s,%g,%d,%s,%d,%g,%.5f,%.4f,%.5f,%.3f,%.6f,%.2f,%.4f,%.3f,%llu,%llu\n", r.mode.c_str(),
                 r.orders.c_str(), r.voxel_mm, r.voxel_dependent ? 1 : 0, r.view.c_str(), r.oblique ? 1 : 0, r.opacity,
                 r.score.rmse, r.score.psnr, r.score.mean_abs, r.score.max_abs, r.score.ssim, r.frame_ms, r.cpu_ms,
                 r.convert_s, (unsigned long long)r.file_bytes, (unsigned long long)r.gpu_bytes);
  std::fclose(f);
}

void write_sweep_markdown(const std::string& path, const std::string& heading, const std::vector<SweepRow>& rows,
                          double reference_voxel_mm) {
  // Groups: (mode, voxel size); modes that do not depend on the voxel size form one group.
  using Key = std::pair<int, std::pair<std::string, double>>;
  std::map<Key, std::vector<const SweepRow*>> groups;
  for (const SweepRow& r : rows)
    groups[{mode_rank(r.mode), {r.mode, r.voxel_dependent ? r.voxel_mm : 0.0}}].push_back(&r);

  FILE* f = open_out(path);
  std::fprintf(f, "%s\n\n", heading.c_str());
  std::fprintf(f,
               "Errors against `exact` (same view, same opacity) in 8-bit levels over R, G, B, averaged over all views "
               "and opacities; frame and CPU times are medians. \"any\": the mode draws the same picture at every "
               "voxel size (dataset order or order-independent), measured once.\n\n");
  std::fprintf(
      f,
      "| mode | voxel mm | RMSE | PSNR dB | SSIM | mean abs | max abs | frame ms | CPU ms | convert s | file MiB "
      "| GPU MiB |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const auto& [key, g] : groups) {
    const SweepRow& first = *g.front();
    std::vector<double> frame, cpu;
    double max_abs = 0;
    for (const SweepRow* r : g) {
      frame.push_back(r->frame_ms);
      cpu.push_back(r->cpu_ms);
      max_abs = std::max(max_abs, r->score.max_abs);
    }
    char voxel[32];
    std::snprintf(voxel, sizeof voxel, first.voxel_dependent ? "%g" : "any", first.voxel_mm);
    if (first.mode == "exact") {
      std::fprintf(f, "| exact | any | reference | | | | | %.0f | %.3f | | | |\n", median(frame), median(cpu));
      continue;
    }
    std::fprintf(f, "| %s | %s | %.2f | %.1f | %.4f | %.2f | %.0f | %.0f | %.3f | %.1f | %.1f | %.1f |\n",
                 first.mode.c_str(), voxel, mean_of(g, [](const SweepRow& r) { return r.score.rmse; }),
                 mean_of(g, [](const SweepRow& r) { return r.score.psnr; }),
                 mean_of(g, [](const SweepRow& r) { return r.score.ssim; }),
                 mean_of(g, [](const SweepRow& r) { return r.score.mean_abs; }), max_abs, median(frame), median(cpu),
                 first.convert_s, first.file_bytes / kMiB, first.gpu_bytes / kMiB);
  }

  // At the reference voxel size: by opacity, and axis-aligned against oblique views.
  std::map<std::pair<int, std::string>, std::vector<const SweepRow*>> at_reference;
  std::vector<double> opacities;
  for (const SweepRow& r : rows) {
    if (r.mode == "exact" || (r.voxel_dependent && r.voxel_mm != reference_voxel_mm)) continue;
    at_reference[{mode_rank(r.mode), r.mode}].push_back(&r);
    if (std::find(opacities.begin(), opacities.end(), r.opacity) == opacities.end()) opacities.push_back(r.opacity);
  }
  std::sort(opacities.rbegin(), opacities.rend());
  std::fprintf(f, "\n**By opacity** at %g mm (RMSE / SSIM, mean over views):\n\n| mode |", reference_voxel_mm);
  for (double o : opacities) std::fprintf(f, " opacity %g |", o);
  std::fprintf(f, "\n|---|");
  for (std::size_t i = 0; i < opacities.size(); ++i) std::fprintf(f, "---:|");
  std::fprintf(f, "\n");
  for (const auto& [key, g] : at_reference) {
    std::fprintf(f, "| %s |", key.second.c_str());
    for (double o : opacities) {
      std::vector<const SweepRow*> sel;
      for (const SweepRow* r : g)
        if (r->opacity == o) sel.push_back(r);
      std::fprintf(f, " %.2f / %.4f |", mean_of(sel, [](const SweepRow& r) { return r.score.rmse; }),
                   mean_of(sel, [](const SweepRow& r) { return r.score.ssim; }));
    }
    std::fprintf(f, "\n");
  }
  std::fprintf(
      f,
      "\n**By view** at %g mm (RMSE / SSIM, mean over opacities):\n\n| mode | axis-aligned views | oblique views "
      "|\n|---|---:|---:|\n",
      reference_voxel_mm);
  for (const auto& [key, g] : at_reference) {
    std::vector<const SweepRow*> aligned, oblique;
    for (const SweepRow* r : g) (r->oblique ? oblique : aligned).push_back(r);
    auto rmse = [](const SweepRow& r) { return r.score.rmse; };
    auto ssim = [](const SweepRow& r) { return r.score.ssim; };
    std::fprintf(f, "| %s | %.2f / %.4f | %.2f / %.4f |\n", key.second.c_str(), mean_of(aligned, rmse),
                 mean_of(aligned, ssim), mean_of(oblique, rmse), mean_of(oblique, ssim));
  }
  std::fclose(f);
}

void write_flicker(const std::string& csv_path, const std::string& md_path, const std::string& heading,
                   const std::vector<FlickerRow>& rows) {
  FILE* c = open_out(csv_path);
  std::fprintf(c, "motion,mode,flicker,flicker_minus_exact,error_change,rmse_mean,ssim_mean\n");
  for (const FlickerRow& r : rows)
    std::fprintf(c, "%s,%s,%.5f,%.5f,%.5f,%.5f,%.6f\n", r.motion.c_str(), r.mode.c_str(), r.flicker, r.flicker_excess,
                 r.error_change, r.rmse, r.ssim);
  std::fclose(c);
  FILE* m = open_out(md_path);
  std::fprintf(m, "%s\n\n", heading.c_str());
  std::fprintf(m,
               "Flicker: mean absolute difference between consecutive frames (R, G, B, 8-bit levels). Error change: "
               "mean |(frame i+1 − exact i+1) − (frame i − exact i)|, the part of the flicker that exact does not "
               "have. RMSE and SSIM against exact: means over the frames.\n\n"
               "| motion | mode | flicker | flicker − exact | error change | RMSE vs exact | SSIM vs exact |\n"
               "|---|---|---:|---:|---:|---:|---:|\n");
  for (const FlickerRow& r : rows)
    std::fprintf(m, "| %s | %s | %.3f | %+.3f | %.3f | %.2f | %.4f |\n", r.motion.c_str(), r.mode.c_str(), r.flicker,
                 r.flicker_excess, r.error_change, r.rmse, r.ssim);
  std::fclose(m);
}

}  // namespace vxl::trade
