// Viewer benchmark. First the cost of a process start (`voxview --help`), then for each scene (.vxl, with its
// source TCK):
//   * time from process start to the first frame read back: `voxview FILE --render` as a child process,
//     for the .vxl and for the source TCK (converted first);
//   * per-frame CPU work (cull + voxel sort + order pick + command building), median over a 72-view
//     turntable, at the file's voxel size;
//   * frame time per mode (glFinish-bounded) and the renderer's CPU time of the frame (FrameStats::plan_ms:
//     for segsort it includes the segment sort), medians of a few frames over the turntable; for exact, also
//     with the lists composited on the GPU and on the CPU (exact_resolve.h), whichever the mode chooses.
// Prints numbers; asserts nothing.
//
// Usage: render_bench --scene FILE.vxl[:SOURCE.tck] ... [--size N] [--frames N] [--modes a,b,...]
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "bench/child_process.h"
#include "viewer/platform/egl_context.h"
#include "viewer/platform/offscreen_target.h"
#include "viewer/render/exact_renderer.h"
#include "viewer/render/frame_plan.h"
#include "viewer/render/renderer.h"

namespace {

using Clock = std::chrono::steady_clock;

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// Wall time of a child process, from fork to exit; -1 when it failed.
double run_child_seconds(const std::vector<std::string>& args) {
  vxl::bench::ChildRun r = vxl::bench::run_child(args, true);
  return r.exit_code == 0 ? r.seconds : -1;
}

vxl::Camera turntable_camera(const vxl::Renderer& r, int step, int steps) {
  vxl::Camera c;
  c.azimuth_deg = 360.0 * step / steps;
  c.elevation_deg = 20;
  c.frame(r.bounds_min(), r.bounds_max(), 1.0);
  return c;
}

}  // namespace

struct BenchOptions {
  std::vector<std::string> scenes;
  int size = 1024, frames = 5;
  std::vector<vxl::RenderMode> modes;
};

// The command line; nullopt (after a message) when it is not one.
std::optional<BenchOptions> parse_options(int argc, char** argv) {
  BenchOptions o;
  std::string every_mode;  // render_settings.h's table, the default of --modes
  for (const std::string& name : vxl::render_mode_names()) every_mode += (every_mode.empty() ? "" : ",") + name;
  std::string modes_arg = every_mode;
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    if (a == "--scene" && i + 1 < argc)
      o.scenes.push_back(argv[++i]);
    else if (a == "--size" && i + 1 < argc)
      o.size = std::stoi(argv[++i]);
    else if (a == "--frames" && i + 1 < argc)
      o.frames = std::stoi(argv[++i]);
    else if (a == "--modes" && i + 1 < argc)
      modes_arg = argv[++i];
    else {
      std::fprintf(stderr,
                   "usage: render_bench --scene FILE.vxl[:SOURCE.tck]... [--size N] [--frames N] [--modes a,b]\n");
      return std::nullopt;
    }
  }
  std::stringstream ss(modes_arg);
  for (std::string m; std::getline(ss, m, ',');) {
    const auto mode = vxl::parse_render_mode(m);
    if (!mode) {
      std::fprintf(stderr, "render_bench: unknown mode '%s' (modes: %s)\n", m.c_str(), every_mode.c_str());
      return std::nullopt;
    }
    o.modes.push_back(*mode);
  }
  return o;
}

// CPU work per frame over a turntable.
void print_plan_times(vxl::Renderer& renderer) {
  vxl::FramePlan plan;
  for (auto [order, name] : {std::pair{vxl::PlanOrder::Nearest, "axis (sort + nearest order)"},
                             std::pair{vxl::PlanOrder::Block, "basic (sort only)"}}) {
    std::vector<double> ms;
    for (int step = 0; step < 72; ++step) {
      vxl::Camera cam = turntable_camera(renderer, step, 72);
      auto t0 = Clock::now();
      renderer.plan(cam, 1.0, order, plan);
      ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    }
    std::printf("  CPU per frame, %-28s median %.3f ms, max %.3f ms (%llu voxels drawn at the last view)\n", name,
                median(ms), *std::max_element(ms.begin(), ms.end()), (unsigned long long)plan.voxels_drawn);
  }
}

int run(int argc, char** argv) {
  const std::optional<BenchOptions> options = parse_options(argc, argv);
  if (!options) return 2;
  const std::vector<std::string>& scenes = options->scenes;
  const std::vector<vxl::RenderMode>& modes = options->modes;
  const int size = options->size, frames = options->frames;

  // What every start of the viewer costs before it does anything: loading the program and its libraries.
  std::vector<double> help;
  for (int r = 0; r < 5; ++r) help.push_back(run_child_seconds({VOXVIEW_CLI, "--help"}));
  std::printf("process start: voxview --help median %.3f s (min %.3f) over 5 runs\n", median(help),
              *std::min_element(help.begin(), help.end()));

  vxl::HeadlessGlContext context;
  std::printf("GL: %s %s; image %dx%d\n", context.version_string().c_str(), context.renderer().c_str(), size, size);
  for (const std::string& spec : scenes) {
    std::string vxl_path = spec.substr(0, spec.find(':'));
    std::string source = spec.find(':') == std::string::npos ? "" : spec.substr(spec.find(':') + 1);
    std::string sz = std::to_string(size) + "x" + std::to_string(size);
    std::string png = "/tmp/render_bench_" + std::to_string(getpid()) + ".png";
    std::vector<double> first_vxl, first_src;
    for (int r = 0; r < 3; ++r) {
      first_vxl.push_back(run_child_seconds({VOXVIEW_CLI, vxl_path, "--render", png, "--size", sz}));
      if (!source.empty()) first_src.push_back(run_child_seconds({VOXVIEW_CLI, source, "--render", png, "--size", sz}));
    }
    std::remove(png.c_str());

    vxl::VxlFile file = vxl::VxlFile::open(vxl_path);
    auto t_upload = Clock::now();
    vxl::Renderer renderer(file);
    double upload_s = std::chrono::duration<double>(Clock::now() - t_upload).count();
    std::printf(
        "\nscene %s: %llu streamlines, %llu segments, %u voxels of %g mm, GPU %.0f MiB, upload %.3f s (%.2f GB/s)\n",
        vxl_path.c_str(), (unsigned long long)file.meta().streamline_count,
        (unsigned long long)file.meta().segment_count, file.meta().voxel_count, file.meta().voxel_size,
        renderer.gpu_bytes() / 1048576.0, upload_s, renderer.gpu_bytes() / 1e9 / upload_s);
    std::printf("  first frame read back (process start -> PNG written): .vxl %.3f s", median(first_vxl));
    if (!source.empty())
      std::printf(", source %.3f s (ratio %.1fx)", median(first_src), median(first_src) / median(first_vxl));
    std::printf("\n");

    print_plan_times(renderer);

    vxl::OffscreenTarget target(size, size);
    double unsorted_ms = 0;
    // The median time of `frames` frames over the turntable (after a warm-up), each drawn by draw(camera) and
    // bounded by glFinish; with `cpu`, the renderer's CPU time of each frame too.
    auto timed_frames = [&](auto&& draw, std::vector<double>* cpu = nullptr) {
      std::vector<double> ms;
      for (int f = 0; f <= frames; ++f) {
        vxl::Camera cam = turntable_camera(renderer, f, frames + 1);
        target.bind();
        glFinish();
        auto t0 = Clock::now();
        draw(cam);
        glFinish();
        if (f > 0) {  // the first is a warm-up
          ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
          if (cpu) cpu->push_back(renderer.stats().plan_ms);
        }
      }
      return median(ms);
    };
    for (vxl::RenderMode mode : modes) {
      vxl::RenderSettings s;
      s.mode = mode;
      s.opacity = 0.05f;
      std::vector<double> cpu_ms;
      renderer.prepare(mode);
      const double m = timed_frames(
          [&](const vxl::Camera& cam) { renderer.draw(cam, s, size, size, target.framebuffer()); }, &cpu_ms);
      if (mode == vxl::RenderMode::Unsorted) unsorted_ms = m;
      std::printf("  frame time %-9s median %9.1f ms, CPU %8.2f ms", vxl::render_mode_name(mode), m, median(cpu_ms));
      if (unsorted_ms > 0) std::printf("  (%.2fx unsorted)", m / unsorted_ms);
      std::printf("\n");
      std::fflush(stdout);
      if (mode == vxl::RenderMode::Exact) {
        // The exact frame with its lists composited each way (exact_resolve.h), whichever the mode chose here.
        for (auto [resolve, name] :
             {std::pair{vxl::ExactResolve::Gpu, "GPU"}, std::pair{vxl::ExactResolve::Cpu, "CPU"}}) {
          vxl::ExactRenderer exact(renderer, 0, resolve);
          const double resolved =
              timed_frames([&](const vxl::Camera& cam) { exact.draw(cam, s, size, size, target.framebuffer()); });
          std::printf("  frame time exact, lists composited on the %s%s: median %9.1f ms\n", name,
                      exact.resolve() == resolve ? "" : " (refused: the driver disagrees, on the CPU)", resolved);
          std::fflush(stdout);
        }
      }
    }
  }
  return 0;
}

// A file that cannot be read is reported, not left to std::terminate.
int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: error: %s\n", "render_bench", e.what());
    return 1;
  }
}
