// Region drag benchmark: what the viewer computes on the CPU each time a region moves, for a 10 mm sphere
// dragged in a straight line through the middle of a .vxl's bounds (left to right, then back to front),
// as voxview recomputes it: the selection (`voxlines select`'s rules) through the whole voxline table and
// through the per-voxel index (VoxelVoxlines: the file's VXIX, or for an older file built once when the first
// region appears, its build time and bytes printed), and through the index with the voxline boxes of the voxels
// the last positions touched (voxline_boxes.h, as the window keeps them; a packed file's), then the focus/context
// groups and the table of one byte per streamline that the window uploads after each change (the per-vertex attributes,
// vertex_attributes.h, are made once, as spans are uploaded: their time for every voxel is printed too). Medians and
// p95 per step.
//
// With --from X,Y,Z the sphere follows the window's scripted drag instead (voxview --include X,Y,Z,R
// --drag-region DX,DY,DZ): --steps positions from X,Y,Z, DX,DY,DZ mm apart (--by; default 2,0,0), each selected
// through the index after the last, as the window's selection worker does; the table walk is left out.
//
// With --boxes-only, only the window's path (through the index and the boxes) is run: for a profiler.
//
// For a file with levels of detail, also the selection among one level's streamlines alone, through that level's own
// voxlines (LevelVoxlines, made once, its time printed): what a window drawing its moving frames at that level needs
// (--level L; by default the coarsest level), checked against the selection through the index at that level.
//
// Usage: drag_bench FILE.vxl [--steps N] [--radius MM] [--from X,Y,Z [--by DX,DY,DZ]] [--level L] [--boxes-only]
#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "converter/selection/streamline_selection.h"
#include "converter/selection/voxline_boxes.h"
#include "format/level_voxlines.h"
#include "format/voxel_voxlines.h"
#include "format/vxl_file.h"
#include "format/vxl_levels.h"
#include "viewer/render/scene_groups.h"
#include "viewer/render/vertex_attributes.h"

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

struct Spread {
  double median = 0, p95 = 0;
};
Spread spread(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return {v[v.size() / 2], v[std::min(v.size() - 1, v.size() * 95 / 100)]};
}

// The sphere's centres: the window's drag (`from`, `by` apart), or the two sweeps through the middle of the bounds.
std::vector<std::array<double, 3>> sphere_centres(const vxl::MetaSection& m,
                                                  const std::optional<std::array<double, 3>>& from,
                                                  const std::array<double, 3>& by, int steps) {
  std::vector<std::array<double, 3>> centres;
  if (from) {
    for (int step = 0; step < steps; ++step)
      centres.push_back({(*from)[0] + step * by[0], (*from)[1] + step * by[1], (*from)[2] + step * by[2]});
    return centres;
  }
  for (int axis : {0, 1})
    for (int step = 0; step < steps; ++step) {
      std::array<double, 3> centre{};
      for (int c = 0; c < 3; ++c) centre[c] = 0.5 * (m.bounds_min[c] + m.bounds_max[c]);
      const double t = double(step) / (steps - 1);
      centre[axis] = m.bounds_min[axis] + t * (m.bounds_max[axis] - m.bounds_min[axis]);
      centres.push_back(centre);
    }
  return centres;
}

constexpr const char* kUsage =
    "usage: drag_bench FILE.vxl [--steps N] [--radius MM] [--from X,Y,Z [--by DX,DY,DZ]] [--level L] [--boxes-only]\n";

struct Arguments {
  int steps = 40;
  double radius = 10;
  std::optional<std::array<double, 3>> from;
  std::array<double, 3> by = {2, 0, 0};
  std::optional<std::uint32_t> level;  // default: the file's coarsest
  bool boxes_only = false;
};

// The options after the file; nullopt (said on stderr) for one it does not know.
std::optional<Arguments> parse_arguments(int argc, char** argv) {
  Arguments a;
  auto triple = [](const char* text) {
    std::array<double, 3> v{};
    if (std::sscanf(text, "%lf,%lf,%lf", &v[0], &v[1], &v[2]) != 3) throw std::invalid_argument(text);
    return v;
  };
  for (int i = 2; i < argc; ++i) {
    const std::string option = argv[i];
    if (option == "--steps" && i + 1 < argc)
      a.steps = std::max(2, std::stoi(argv[++i]));
    else if (option == "--radius" && i + 1 < argc)
      a.radius = std::stod(argv[++i]);
    else if (option == "--from" && i + 1 < argc)
      a.from = triple(argv[++i]);
    else if (option == "--by" && i + 1 < argc)
      a.by = triple(argv[++i]);
    else if (option == "--level" && i + 1 < argc)
      a.level = static_cast<std::uint32_t>(std::stoul(argv[++i]));
    else if (option == "--boxes-only")
      a.boxes_only = true;
    else {
      std::fprintf(stderr, "drag_bench: unknown argument %s\n%s", option.c_str(), kUsage);
      return std::nullopt;
    }
  }
  return a;
}

// The file's voxel index (its VXIX, or built), its figures printed; nullopt when the file has too many voxlines.
std::optional<vxl::VoxelVoxlines> open_index(const vxl::VxlFile& file) {
  const vxl::MetaSection& m = file.meta();
  const auto t0 = Clock::now();
  std::optional<vxl::VoxelVoxlines> index = vxl::VoxelVoxlines::of_file(file);
  const double build_ms = ms_since(t0);
  if (!index) return index;
  std::printf("file %s: %llu streamlines, %llu voxlines, %zu voxels\n", file.path().c_str(),
              static_cast<unsigned long long>(m.streamline_count),
              static_cast<unsigned long long>(file.voxlines().size()), file.voxels().size());
  if (index->from_file())
    std::printf("index: the file's VXIX, mapped in %.3f ms (nothing built)\n", build_ms);
  else
    std::printf("index build (a file without VXIX): %.0f ms, %.1f MB (4 bytes a voxline, 8 a voxel)\n", build_ms,
                index->bytes() / 1e6);
  return index;
}

// The per-vertex words of every voxel at full detail, timed: what uploading the whole scene makes once.
void time_attributes(const vxl::VxlFile& file, const vxl::VoxelVoxlines& index) {
  const auto t0 = Clock::now();
  std::vector<std::uint32_t> words;
  for (std::size_t v = 0; v < file.voxels().size(); ++v) {
    words.resize(2 * std::size_t(file.voxels()[v].vertex_count));
    vxl::voxel_attributes(file, v, {{}, 0, &index}, file.voxels()[v].vertex_count, words.data());
  }
  std::printf("per-vertex attributes of every voxel, once (one thread): %.0f ms\n", ms_since(t0));
}

// One level's own voxlines, for the selection among its streamlines alone, timed.
vxl::LevelVoxlines make_level_voxlines(const vxl::VxlFile& file, std::uint32_t level) {
  vxl::check_level(file.path(), level, file.level_count());
  const auto t0 = Clock::now();
  vxl::LevelVoxlines lists(file, level);
  std::printf("level %u's own voxlines, made once (one thread): %.0f ms\n", level, ms_since(t0));
  return lists;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h") {
    std::fprintf(argc < 2 ? stderr : stdout, "%s", kUsage);
    return argc < 2 ? 2 : 0;
  }
  std::optional<Arguments> parsed;
  try {
    parsed = parse_arguments(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "drag_bench: bad number %s\n%s", e.what(), kUsage);
    return 2;
  }
  if (!parsed) return 2;
  const auto [steps, radius, from, by, level_asked, boxes_only] = *parsed;
  try {
    const vxl::VxlFile file = vxl::VxlFile::open(argv[1]);
    const vxl::MetaSection& m = file.meta();
    const std::optional<vxl::VoxelVoxlines> index = open_index(file);
    if (!index) {
      std::fprintf(stderr, "drag_bench: %s has too many voxlines for the index\n", argv[1]);
      return 1;
    }
    if (!boxes_only) time_attributes(file, *index);
    const std::uint32_t levels = file.level_count();
    const std::uint32_t level = level_asked.value_or(levels - 1);
    std::optional<vxl::LevelVoxlines> level_voxlines;
    if (!boxes_only && level > 0) level_voxlines = make_level_voxlines(file, level);

    auto t0 = Clock::now();
    const std::vector<std::array<double, 3>> centres = sphere_centres(m, from, by, steps);
    std::vector<double> scan_ms, indexed_ms, boxed_ms, level_ms, groups_ms;
    vxl::VoxlineBoxes boxes(file);  // the window's selection worker keeps one per file
    std::uint64_t selected_total = 0;
    const std::vector<const vxl::VxlFile*> files = {&file};
    for (const std::array<double, 3>& centre : centres) {
      vxl::SelectionCriteria c;
      c.include.push_back(vxl::parse_region(std::to_string(centre[0]) + "," + std::to_string(centre[1]) + "," +
                                            std::to_string(centre[2]) + "," + std::to_string(radius)));
      std::optional<vxl::SelectionResult> scan;
      if (!from && !boxes_only) {
        t0 = Clock::now();
        scan = vxl::select_streamlines(file, c, nullptr, vxl::SelectionPath::ScanTable);
        scan_ms.push_back(ms_since(t0));
      }
      std::optional<vxl::SelectionResult> indexed;
      if (!boxes_only) {
        t0 = Clock::now();
        indexed = vxl::select_streamlines(file, c, &*index);
        indexed_ms.push_back(ms_since(t0));
      }
      t0 = Clock::now();
      vxl::SelectionResult boxed = vxl::select_streamlines(file, c, &*index, vxl::SelectionPath::Fastest, &boxes);
      boxed_ms.push_back(ms_since(t0));
      if (indexed && boxed.streamlines != indexed->streamlines) {
        std::fprintf(stderr, "drag_bench: the boxes and the index disagree at (%g, %g, %g)\n", centre[0], centre[1],
                     centre[2]);
        return 1;
      }
      if (scan && indexed->streamlines != scan->streamlines) {
        std::fprintf(stderr, "drag_bench: the index and the scan disagree at (%g, %g, %g)\n", centre[0], centre[1],
                     centre[2]);
        return 1;
      }
      if (level_voxlines) {
        vxl::SelectionCriteria at_level = c;
        at_level.level = level;
        t0 = Clock::now();
        const vxl::SelectionResult own =
            vxl::select_streamlines(file, at_level, &*index, vxl::SelectionPath::Fastest, nullptr, &*level_voxlines);
        level_ms.push_back(ms_since(t0));
        std::vector<std::uint64_t> expected = boxed.streamlines;
        std::erase_if(expected, [&](std::uint64_t st) { return vxl::streamline_depth(st, levels) < level; });
        if (own.streamlines != expected) {
          std::fprintf(stderr, "drag_bench: level %u's voxlines and the index disagree at (%g, %g, %g)\n", level,
                       centre[0], centre[1], centre[2]);
          return 1;
        }
      }
      selected_total += boxed.streamlines.size();
      // What the window does with a new selection: the groups, then one byte per streamline.
      t0 = Clock::now();
      const vxl::SceneGroups groups = vxl::SceneGroups::selection(files, {std::move(boxed.streamlines)});
      std::vector<std::uint8_t> table(m.streamline_count);
      groups.write_table(0, table, 256);
      groups_ms.push_back(ms_since(t0));
    }
    auto row = [](const char* what, const std::vector<double>& v) {
      if (v.empty()) return;
      const Spread s = spread(v);
      std::printf("| %s | %.1f | %.1f |\n", what, s.median, s.p95);
    };
    std::printf("%zu positions of a %g mm sphere, %.0f streamlines selected on average\n\n", centres.size(), radius,
                double(selected_total) / double(centres.size()));
    std::printf("| per position | median ms | p95 ms |\n|---|---:|---:|\n");
    row("select, scanning the voxline table", scan_ms);
    row("select, through the per-voxel index", indexed_ms);
    row("select, through the index and the voxline boxes kept from the last position", boxed_ms);
    const std::string at_level =
        "select among level " + std::to_string(level) + "'s streamlines, through its own voxlines";
    row(at_level.c_str(), level_ms);
    row("focus/context groups and the byte per streamline (before upload)", groups_ms);
    // The first position alone: the window's first selection, with nothing boxed yet (it reads its voxels without
    // boxes).
    if (!indexed_ms.empty())
      std::printf("\nfirst position: through the index %.1f ms, with the boxes (nothing boxed yet) %.1f ms\n",
                  indexed_ms.front(), boxed_ms.front());
    else
      std::printf("\nfirst position, with the boxes (nothing boxed yet): %.1f ms\n", boxed_ms.front());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "drag_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
