// Speed/accuracy trade study. Input: one dataset converted at several voxel sizes and order sets,
// listed in a manifest (written by scripts/trade-study). Two parts:
//
//   sweep    every mode — unsorted, additive, wboit (the baselines), basic, axis, segsort (each voxel's
//            segments sorted on the CPU for the view: the best any order set could reach), and axis on files
//            with other order sets (axis+diag, random:N) — from 6 views (3 axis-aligned, 3 oblique) at each
//            opacity, scored against `exact` from the same view at the same opacity (RMSE, PSNR, mean and
//            max error, SSIM: image_metrics.h), with frame time, the renderer's CPU time per frame, convert
//            time, file size and GPU bytes. `exact` does not depend on the voxelisation (it sorts every
//            fragment), so it is rendered once per (view, opacity) from the reference file; so are the
//            modes whose picture does not depend on it (unsorted: dataset order; additive and wboit:
//            order-independent).
//   flicker  a 72-frame turntable per mode at the reference voxel size: the mean absolute difference
//            between consecutive frames, minus that of `exact` (the paper reports jitter with axis orders
//            while rotating), and how much the error against exact changes between frames; `axis` again
//            with order hysteresis (FramePlan::order_hysteresis) as the remedy. The order-picking modes
//            also on a "wobble": the camera jittering by ±1.5° where many voxels sit at an order boundary.
//
//   levels   `axis` at each coarse level of detail of the reference file (.vxl spec §5.12: about 1/8^d of
//            the streamlines, opacity compensated), scored against `exact` and against full-detail `axis`
//            from the same view and opacity, with frame time and GPU bytes: what a coarse level costs in
//            accuracy for what it saves.
//
// Writes results.csv, results.md, levels.csv, levels.md, flicker.csv, flicker.md and side_<mode>.png (the
// panels of the side-by-side picture) into --out. Prints progress; asserts nothing (timings never gate tests).
//
// Usage: trade_study --manifest FILE --out DIR [--name TEXT] [--size N] [--reference-voxel MM]
//          [--flicker-size N] [--flicker-frames N] [--flicker-opacity A] [--hysteresis M[,M...]]
//          [--no-sweep] [--no-flicker]
// Manifest lines: VOXEL_MM ORDERS PATH CONVERT_SECONDS (whitespace-separated; # starts a comment).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "bench/trade_report.h"
#include "viewer/platform/egl_context.h"
#include "viewer/platform/image_io.h"
#include "viewer/platform/image_metrics.h"
#include "viewer/platform/offscreen_target.h"
#include "viewer/render/renderer.h"

namespace {

using namespace vxl;
using trade::FlickerRow;
using trade::SweepRow;
using Clock = std::chrono::steady_clock;

struct ManifestEntry {
  double voxel_mm = 0;
  std::string orders;
  std::string path;
  double convert_s = 0;
};

struct View {
  const char* name;
  double azimuth, elevation;
  bool oblique;
};
// Axis-aligned views as mrview names them (camera.h), and three oblique ones away from the cube diagonals
// (which would favour axis+diag).
constexpr View kViews[] = {{"superior", 180, 90, false}, {"left", -90, 0, false},      {"anterior", 0, 0, false},
                           {"oblique-a", 30, 25, true},  {"oblique-b", 135, 40, true}, {"oblique-c", 250, -30, true}};
constexpr double kOpacities[] = {0.5, 0.05, 0.01};  // the paper's
constexpr const char* kSideView = "left";           // sagittal, as the paper's comparison figure
constexpr double kSideOpacity = 0.05;
constexpr double kMotionElevation = 20;  // camera elevation of the flicker motions
constexpr int kWobbleFrames = 24;
constexpr double kWobbleAzimuth = 45, kWobbleAmplitude = 1.5;

// A camera path for the flicker measure: azimuth per frame, at kMotionElevation.
struct Motion {
  const char* name;
  int frames;
  std::function<double(int)> azimuth;
  bool all_modes;
};

struct Options {
  std::string manifest, out, name = "dataset";
  int size = 384, flicker_size = 256, flicker_frames = 72;
  double reference_voxel_mm = 10, flicker_opacity = 0.5;
  std::vector<double> hysteresis = {0.1};
  bool sweep = true, flicker = true;
};

struct Frame {
  Image image;
  double ms = 0, cpu_ms = 0;
};

// Everything one rendered mode needs besides the camera.
struct ModeSpec {
  std::string name;
  RenderMode mode;
  float hysteresis = 0;
};

class Study {
 public:
  explicit Study(Options o) : o_(std::move(o)) { read_manifest(); }

  void run() {
    std::filesystem::create_directories(o_.out);
    std::printf("GL: %s %s\n", context_.version_string().c_str(), context_.renderer().c_str());
    if (o_.sweep) sweep();
    if (o_.flicker) flicker();
  }

 private:
  void read_manifest() {
    std::ifstream in(o_.manifest);
    if (!in) throw std::runtime_error("cannot read manifest " + o_.manifest);
    for (std::string line; std::getline(in, line);) {
      if (line.empty() || line[0] == '#') continue;
      std::istringstream ss(line);
      ManifestEntry e;
      if (!(ss >> e.voxel_mm >> e.orders >> e.path >> e.convert_s))
        throw std::runtime_error("bad manifest line: " + line);
      entries_.push_back(e);
    }
    // The reference file (axis orders at the reference voxel size) goes first: exact is rendered from it.
    auto is_reference = [&](const ManifestEntry& e) {
      return e.orders == "axis" && e.voxel_mm == o_.reference_voxel_mm;
    };
    auto ref = std::find_if(entries_.begin(), entries_.end(), is_reference);
    if (ref == entries_.end()) throw std::runtime_error("the manifest has no axis file at the reference voxel size");
    std::rotate(entries_.begin(), ref, ref + 1);
  }

  Frame render(Renderer& r, const Camera& cam, const ModeSpec& m, double opacity, int size) {
    if (!target_ || target_->width() != size) target_ = std::make_unique<OffscreenTarget>(size, size);
    RenderSettings s;
    s.mode = m.mode;
    s.opacity = static_cast<float>(opacity);
    s.order_hysteresis = m.hysteresis;
    target_->bind();
    glFinish();
    auto t0 = Clock::now();
    r.draw(cam, s, size, size, target_->framebuffer());
    glFinish();
    Frame f;
    f.ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    f.cpu_ms = r.stats().plan_ms;
    f.image = {size, size, target_->read_rgba()};
    return f;
  }

  Camera camera(const Renderer& r, double azimuth, double elevation) const {
    Camera c;
    c.azimuth_deg = azimuth;
    c.elevation_deg = elevation;
    c.frame(r.bounds_min(), r.bounds_max(), 1.0);
    return c;
  }

  // The modes drawn from one file: ours on every file, the voxel-independent ones from the reference only.
  // segsort (the bound for any order set at this voxel size) also from the reference only: its CPU sort
  // costs about as much as drawing the frame, and the study must stay within its half hour.
  std::vector<ModeSpec> sweep_modes(const ManifestEntry& e, bool reference) const {
    if (e.orders != "axis") return {{e.orders, RenderMode::Axis}};
    std::vector<ModeSpec> modes = {{"basic", RenderMode::Basic}, {"axis", RenderMode::Axis}};
    if (reference) {
      modes.insert(
          modes.begin(),
          {{"unsorted", RenderMode::Unsorted}, {"additive", RenderMode::Additive}, {"wboit", RenderMode::Wboit}});
      modes.push_back({"segsort", RenderMode::Segsort});
    }
    return modes;
  }

  void sweep() {
    std::vector<SweepRow> rows;
    std::map<std::pair<int, int>, Image> exact;      // (view, opacity) -> image
    std::map<std::pair<int, int>, Image> full_axis;  // the same, `axis` at full detail, reference file
    for (std::size_t n = 0; n < entries_.size(); ++n) {
      const ManifestEntry& e = entries_[n];
      const bool reference = n == 0;
      VxlFile file = VxlFile::open(e.path);
      Renderer r(file);
      const std::uint64_t scene_bytes = r.gpu_bytes();
      std::vector<ModeSpec> modes = sweep_modes(e, reference);
      if (reference) modes.insert(modes.begin(), ModeSpec{"exact", RenderMode::Exact});
      for (const ModeSpec& m : modes) {
        r.prepare(m.mode);  // a one-time upload is not a frame
        for (std::size_t v = 0; v < std::size(kViews); ++v)
          for (std::size_t o = 0; o < std::size(kOpacities); ++o) {
            const View& view = kViews[v];
            Frame f = render(r, camera(r, view.azimuth, view.elevation), m, kOpacities[o], o_.size);
            if (m.mode == RenderMode::Exact) exact[{int(v), int(o)}] = f.image;
            if (reference && m.mode == RenderMode::Axis) full_axis[{int(v), int(o)}] = f.image;
            SweepRow row;
            row.mode = m.name;
            row.orders = e.orders;
            row.voxel_mm = e.voxel_mm;
            row.voxel_dependent = !reference || m.mode == RenderMode::Basic || m.mode == RenderMode::Axis ||
                                  m.mode == RenderMode::Segsort;
            row.view = view.name;
            row.oblique = view.oblique;
            row.opacity = kOpacities[o];
            row.score = score_image(f.image, exact.at({int(v), int(o)}));
            row.frame_ms = f.ms;
            row.cpu_ms = f.cpu_ms;
            row.convert_s = e.convert_s;
            row.file_bytes = file.bytes().size();
            row.gpu_bytes =
                m.mode == RenderMode::Unsorted || m.mode == RenderMode::Segsort ? r.gpu_bytes() : scene_bytes;
            rows.push_back(row);
            if (reference && view.name == std::string(kSideView) && kOpacities[o] == kSideOpacity)
              write_png(o_.out + "/side_" + m.name + ".png", f.image);
          }
        const SweepRow& last = rows.back();
        std::printf("%-10s %5g mm %-9s RMSE %6.2f SSIM %.4f  %7.0f ms/frame\n", m.name.c_str(), e.voxel_mm,
                    e.orders.c_str(), last.score.rmse, last.score.ssim, last.frame_ms);
        std::fflush(stdout);
      }
      if (reference) levels(file, exact, full_axis);
    }
    trade::write_sweep_csv(o_.out + "/results.csv", rows);
    char heading[256];
    std::snprintf(heading, sizeof heading, "### %s: speed vs accuracy (%dx%d, %s)", o_.name.c_str(), o_.size, o_.size,
                  context_.renderer().c_str());
    trade::write_sweep_markdown(o_.out + "/results.md", heading, rows, o_.reference_voxel_mm);
  }

  // `axis` at every coarse level of the reference file, against exact and against full detail.
  void levels(const VxlFile& file, const std::map<std::pair<int, int>, Image>& exact,
              const std::map<std::pair<int, int>, Image>& full_axis) {
    std::ofstream csv(o_.out + "/levels.csv");
    csv << "level,view,opacity,rmse_vs_exact,ssim_vs_exact,rmse_vs_full,ssim_vs_full,frame_ms,gpu_bytes,segments\n";
    std::ofstream md(o_.out + "/levels.md");
    md << "### " << o_.name << ": levels of detail (`axis`, " << o_.size << "x" << o_.size
       << ", mean over views and opacities; frame time the median)\n\n"
       << "| level | streamlines | segments drawn | GPU MiB | RMSE vs exact | SSIM vs exact | RMSE vs full detail | "
          "SSIM vs full detail | frame ms |\n|---|---|---|---|---|---|---|---|---|\n";
    for (std::uint32_t level = 0; level < file.level_count(); ++level) {
      Renderer r(file, 0, level);
      const ModeSpec axis{"axis", RenderMode::Axis};
      double rmse_exact = 0, ssim_exact = 0, rmse_full = 0, ssim_full = 0;
      std::vector<double> ms;
      std::uint64_t segments = 0;
      for (std::size_t v = 0; v < std::size(kViews); ++v)
        for (std::size_t o = 0; o < std::size(kOpacities); ++o) {
          const View& view = kViews[v];
          Frame f = render(r, camera(r, view.azimuth, view.elevation), axis, kOpacities[o], o_.size);
          const ImageScore to_exact = score_image(f.image, exact.at({int(v), int(o)}));
          const ImageScore to_full = score_image(f.image, full_axis.at({int(v), int(o)}));
          rmse_exact += to_exact.rmse, ssim_exact += to_exact.ssim;
          rmse_full += to_full.rmse, ssim_full += to_full.ssim;
          ms.push_back(f.ms);
          segments = std::max<std::uint64_t>(segments, r.stats().segments_drawn);
          csv << level << ',' << view.name << ',' << kOpacities[o] << ',' << to_exact.rmse << ',' << to_exact.ssim
              << ',' << to_full.rmse << ',' << to_full.ssim << ',' << f.ms << ',' << r.gpu_bytes() << ','
              << r.stats().segments_drawn << '\n';
        }
      const double n = double(ms.size());
      std::sort(ms.begin(), ms.end());
      char line[320];
      std::snprintf(line, sizeof line, "| %u | 1/%.0f | %llu | %.1f | %.2f | %.4f | %.2f | %.4f | %.0f |\n", level,
                    std::pow(double(kLevelRatio), double(level)), (unsigned long long)segments,
                    double(r.gpu_bytes()) / (1 << 20), rmse_exact / n, ssim_exact / n, rmse_full / n, ssim_full / n,
                    ms[ms.size() / 2]);
      md << line;
      std::printf("level %u    RMSE %6.2f vs exact, %6.2f vs full detail  %7.0f ms/frame  %.1f MiB\n", level,
                  rmse_exact / n, rmse_full / n, ms[ms.size() / 2], double(r.gpu_bytes()) / (1 << 20));
      std::fflush(stdout);
    }
  }

  // The frames of one camera motion. (Their timings are not kept: the script runs the flicker part beside
  // the sweep, at low priority.)
  std::vector<Image> frames_of(Renderer& r, const ModeSpec& m, const Motion& motion) {
    std::vector<Image> frames;
    for (int i = 0; i < motion.frames; ++i)
      frames.push_back(
          render(r, camera(r, motion.azimuth(i), kMotionElevation), m, o_.flicker_opacity, o_.flicker_size).image);
    return frames;
  }

  FlickerRow flicker_row(const Motion& motion, const std::string& name, const std::vector<Image>& frames,
                         const std::vector<Image>& exact) {
    FlickerRow row;
    row.motion = motion.name;
    row.mode = name;
    for (std::size_t i = 0; i + 1 < frames.size(); ++i) {
      row.flicker += mean_abs_difference(frames[i], frames[i + 1]) / double(frames.size() - 1);
      row.error_change += error_change(frames[i], exact[i], frames[i + 1], exact[i + 1]) / double(frames.size() - 1);
    }
    for (std::size_t i = 0; i < frames.size(); ++i) {
      ImageScore s = score_image(frames[i], exact[i]);
      row.rmse += s.rmse / double(frames.size());
      row.ssim += s.ssim / double(frames.size());
    }
    std::printf("%-9s %-24s flicker %.3f  error change %.3f  RMSE %.2f\n", motion.name, name.c_str(), row.flicker,
                row.error_change, row.rmse);
    std::fflush(stdout);
    return row;
  }

  // Every mode on the turntable; on the wobble only the modes that pick stored orders (the others draw
  // the same order from every view).
  void flicker() {
    const Motion motions[] = {
        {"turntable", o_.flicker_frames, [&](int i) { return 360.0 * i / o_.flicker_frames; }, true},
        {"wobble", kWobbleFrames, [](int i) { return kWobbleAzimuth + (i % 2 ? kWobbleAmplitude : -kWobbleAmplitude); },
         false},
    };
    std::vector<FlickerRow> rows;
    for (const Motion& motion : motions) {
      std::vector<Image> exact;  // exact is always the first mode drawn
      double exact_flicker = 0;
      for (const ManifestEntry& e : entries_) {
        if (e.voxel_mm != o_.reference_voxel_mm) continue;
        VxlFile file = VxlFile::open(e.path);
        std::vector<ModeSpec> modes = sweep_modes(e, e.orders == "axis");
        if (e.orders == "axis") modes.insert(modes.begin(), ModeSpec{"exact", RenderMode::Exact});
        if (e.orders == "axis")  // the remedy, for the axis orders whose jitter the paper reports
          for (double h : o_.hysteresis) {
            char name[64];
            std::snprintf(name, sizeof name, "axis + hysteresis %g", h);
            modes.push_back({name, RenderMode::Axis, static_cast<float>(h)});
          }
        for (const ModeSpec& m : modes) {
          if (!motion.all_modes && m.mode != RenderMode::Axis && m.mode != RenderMode::Exact) continue;
          if (m.mode == RenderMode::Segsort) continue;  // 72 CPU sorts a turntable: kept to the sweep's 18 frames
          Renderer r(file);                             // fresh: no order memory from an earlier run
          std::vector<Image> frames = frames_of(r, m, motion);
          if (m.mode == RenderMode::Exact) exact = frames;
          FlickerRow row = flicker_row(motion, m.name, frames, exact);
          if (m.mode == RenderMode::Exact) exact_flicker = row.flicker;
          row.flicker_excess = row.flicker - exact_flicker;
          rows.push_back(row);
        }
      }
    }
    char heading[320];
    std::snprintf(heading, sizeof heading,
                  "### %s: flicker (%g mm voxels, opacity %g, %dx%d; elevation %g°)\n\n"
                  "turntable: %d frames, azimuth 0° to 355° in equal steps. wobble: %d frames alternating between "
                  "azimuth %g° and %g° (a hand's jitter at a view where many voxels are near the boundary between "
                  "the X and Y orders).",
                  o_.name.c_str(), o_.reference_voxel_mm, o_.flicker_opacity, o_.flicker_size, o_.flicker_size,
                  kMotionElevation, o_.flicker_frames, kWobbleFrames, kWobbleAzimuth - kWobbleAmplitude,
                  kWobbleAzimuth + kWobbleAmplitude);
    trade::write_flicker(o_.out + "/flicker.csv", o_.out + "/flicker.md", heading, rows);
  }

  Options o_;
  std::vector<ManifestEntry> entries_;
  HeadlessGlContext context_;
  std::unique_ptr<OffscreenTarget> target_;
};

std::vector<double> parse_list(const std::string& s) {
  std::vector<double> out;
  std::stringstream ss(s);
  for (std::string item; std::getline(ss, item, ',');) out.push_back(std::stod(item));
  return out;
}

constexpr const char* kUsage =
    "usage: trade_study --manifest FILE --out DIR [--name TEXT] [--size N] [--reference-voxel MM] "
    "[--flicker-size N] [--flicker-frames N] [--flicker-opacity A] [--hysteresis M,...] [--no-sweep] "
    "[--no-flicker]\n";

}  // namespace

int main(int argc, char** argv) {
  Options o;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      if (a == "--help" || a == "-h") {
        std::printf(
            "Speed vs accuracy study: every transparency mode (exact, unsorted, additive, wboit, basic, axis, "
            "segsort, and axis on other order sets) scored against exact over 6 views x 3 opacities; writes "
            "results.csv/.md, levels.csv/.md, flicker.csv/.md into --out.\n%sManifest lines: VOXEL_MM ORDERS "
            "PATH CONVERT_SECONDS\n",
            kUsage);
        return 0;
      }
      auto value = [&]() -> std::string {
        if (i + 1 >= argc) throw std::invalid_argument(a + " needs a value");
        return argv[++i];
      };
      if (a == "--manifest")
        o.manifest = value();
      else if (a == "--out")
        o.out = value();
      else if (a == "--name")
        o.name = value();
      else if (a == "--size")
        o.size = std::stoi(value());
      else if (a == "--reference-voxel")
        o.reference_voxel_mm = std::stod(value());
      else if (a == "--flicker-size")
        o.flicker_size = std::stoi(value());
      else if (a == "--flicker-frames")
        o.flicker_frames = std::stoi(value());
      else if (a == "--flicker-opacity")
        o.flicker_opacity = std::stod(value());
      else if (a == "--hysteresis")
        o.hysteresis = parse_list(value());
      else if (a == "--no-sweep")
        o.sweep = false;
      else if (a == "--no-flicker")
        o.flicker = false;
      else
        throw std::invalid_argument("unknown argument " + a);
    }
    if (o.manifest.empty() || o.out.empty() || o.size < 16 || o.flicker_size < 16 || o.flicker_frames < 2)
      throw std::invalid_argument("--manifest and --out are required; sizes >= 16, frames >= 2");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "trade_study: %s\n%s", e.what(), kUsage);
    return 2;
  }
  try {
    Study(o).run();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "trade_study: %s\n", e.what());
    return 1;
  }
  return 0;
}
