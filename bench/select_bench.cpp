// Selection benchmark: `voxlines select` on a .vxl against MRtrix `tckedit` on its TCK, for spheres of 5, 10
// and 20 mm at three places — the densest voxel (a bundle's core), the top of the brain (cortex) and outside
// the bounds (empty space) — one exclude, every streamline (a box around them all), and length limits alone.
// Each query: the selected count of both, the wall time of both (medians, warm page cache), their ratio, the
// peak resident memory of both (select's includes the pages of the .vxl it maps), and the bytes of the file
// `select` reads (its tables and the vertices it tests) against the TCK's size (tckedit reads all of it).
// tckedit is run only when it is installed; nothing else needs it.
//
// Usage: select_bench FILE.tck FILE.vxl [--rounds N] [--tckedit-rounds N] [--voxlines PATH]
// (--voxlines: the program to time, by default the build's; a copy keeps a long run apart from rebuilds)
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "bench/child_process.h"
#include "format/vxl_file.h"

namespace {

using vxl::bench::run_child;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

std::string sphere(const std::array<double, 3>& c, double r) {
  char s[128];
  std::snprintf(s, sizeof s, "%.3f,%.3f,%.3f,%g", c[0], c[1], c[2], r);
  return s;
}

// The `count:` of a TCK header (tckedit writes the true count there when it finishes).
long long tck_count(const std::string& path) {
  std::ifstream in(path);
  for (std::string line; std::getline(in, line) && line != "END";)
    if (line.rfind("count:", 0) == 0) return std::stoll(line.substr(6));
  return -1;
}

std::string find_tckedit() {
  for (const char* dir : {"/usr/bin", "/usr/local/bin"})
    if (std::filesystem::exists(std::string(dir) + "/tckedit")) return std::string(dir) + "/tckedit";
  return "";
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: select_bench FILE.tck FILE.vxl [--rounds N] [--tckedit-rounds N] [--voxlines PATH]\n");
    return 2;
  }
  const std::string tck = argv[1], vxl_path = argv[2];
  int rounds = 5, tckedit_rounds = 3;
  std::string cli = VOXLINES_CLI;
  for (int i = 3; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--rounds") rounds = std::stoi(argv[i + 1]);
    if (a == "--tckedit-rounds") tckedit_rounds = std::stoi(argv[i + 1]);
    if (a == "--voxlines") cli = argv[i + 1];
  }
  const vxl::VxlFile file = vxl::VxlFile::open(vxl_path);
  const auto voxels = file.voxels();
  // The places: the centre of the voxel holding the most vertices, the top of the voxel reaching highest,
  // and 30 mm beyond the bounds.
  std::size_t densest = 0, top = 0;
  for (std::size_t i = 0; i < voxels.size(); ++i) {
    if (voxels[i].vertex_count > voxels[densest].vertex_count) densest = i;
    if (voxels[i].tight_max[2] > voxels[top].tight_max[2]) top = i;
  }
  auto centre = [&](std::size_t i) {
    std::array<double, 3> c;
    for (int k = 0; k < 3; ++k) c[k] = (double(voxels[i].tight_min[k]) + voxels[i].tight_max[k]) / 2;
    return c;
  };
  std::array<double, 3> cortex = centre(top);
  cortex[2] = voxels[top].tight_max[2] - 5;
  const auto& m = file.meta();
  const std::array<double, 3> empty{m.bounds_max[0] + 30, m.bounds_max[1] + 30, m.bounds_max[2] + 30};
  struct Query {
    std::string name;
    std::vector<std::string> ours, theirs;
  };
  std::vector<Query> queries;
  for (const auto& [name, c] :
       {std::pair{"dense", centre(densest)}, std::pair{"cortex", cortex}, std::pair{"empty", empty}})
    for (double r : {5.0, 10.0, 20.0})
      queries.push_back({std::string(name) + " " + std::to_string(int(r)) + " mm",
                         {"--include", sphere(c, r)},
                         {"-include", sphere(c, r)}});
  const std::array<double, 3> beside{centre(densest)[0] + 6, centre(densest)[1], centre(densest)[2]};
  queries.push_back({"dense 10 mm, exclude 4 mm",
                     {"--include", sphere(centre(densest), 10), "--exclude", sphere(beside, 4)},
                     {"-include", sphere(centre(densest), 10), "-exclude", sphere(beside, 4)}});

  queries.push_back({"everything (a box holding all)",
                     {"--include", "box:-100000,-100000,-100000,100000,100000,100000"},
                     {"-include", "0,0,0,200000"}});
  queries.push_back({"length 60-120 mm only",
                     {"--min-length", "60", "--max-length", "120"},
                     {"-minlength", "60", "-maxlength", "120"}});
  const std::string tckedit = find_tckedit();
  const auto tck_bytes = std::filesystem::file_size(tck);
  const std::string out = (std::filesystem::temp_directory_path() / "select_bench_out.tck").string();
  std::printf("file: %s (%llu streamlines, %llu bytes; TCK %llu bytes)\n", vxl_path.c_str(),
              (unsigned long long)m.streamline_count, (unsigned long long)file.bytes().size(),
              (unsigned long long)tck_bytes);
  std::printf("tckedit: %s\n", tckedit.empty() ? "not installed (its columns are empty)" : tckedit.c_str());
  std::printf("%-31s %9s %9s %10s %10s %7s %9s %9s %14s\n", "query", "selected", "tckedit", "select s", "tckedit s",
              "ratio", "select MB", "tckedit MB", "select bytes");
  for (const Query& q : queries) {
    // The count and bytes from --json, then the timed runs writing the TCK.
    std::vector<std::string> count_args = {cli, "select", vxl_path, "--count", "--json"};
    count_args.insert(count_args.end(), q.ours.begin(), q.ours.end());
    const std::string json_path = out + ".json";
    std::string command;
    for (const std::string& a : count_args) command += "'" + a + "' ";
    if (std::system((command + "> '" + json_path + "'").c_str()) != 0) {
      std::fprintf(stderr, "select failed: %s\n", command.c_str());
      return 1;
    }
    std::ifstream json_in(json_path);
    const nlohmann::json j = nlohmann::json::parse(json_in);
    std::vector<std::string> args = {cli, "select", vxl_path, out};
    args.insert(args.end(), q.ours.begin(), q.ours.end());
    // A run that fails must not pass for a fast one.
    long peak_kib = 0;
    auto timed = [&](const std::vector<std::string>& command) {
      const vxl::bench::ChildRun run = run_child(command, true);
      if (run.exit_code != 0) {
        std::fprintf(stderr, "failed (exit %d): %s ...\n", run.exit_code, command[0].c_str());
        std::exit(1);
      }
      peak_kib = std::max(peak_kib, run.peak_rss_kib);
      return run.seconds;
    };
    timed(args);  // warm
    std::vector<double> ours;
    for (int r = 0; r < rounds; ++r) ours.push_back(timed(args));
    const long our_peak_kib = peak_kib;
    peak_kib = 0;
    double theirs = -1;
    long long their_count = -1;
    if (!tckedit.empty()) {
      std::vector<std::string> t = {tckedit, "-quiet", "-force", "-nthreads", "0", tck, out};
      t.insert(t.end(), q.theirs.begin(), q.theirs.end());
      std::vector<double> times;
      for (int r = 0; r < tckedit_rounds; ++r) times.push_back(timed(t));
      theirs = median(times);
      their_count = tck_count(out);
    }
    const double ours_s = median(ours);
    std::printf("%-31s %9llu %9lld %10.3f %10.3f %7.1f %9.0f %9.0f %14llu\n", q.name.c_str(),
                (unsigned long long)j["selected"].get<std::uint64_t>(), their_count, ours_s, theirs,
                theirs > 0 ? theirs / ours_s : 0.0, our_peak_kib / 1024.0, theirs > 0 ? peak_kib / 1024.0 : 0.0,
                (unsigned long long)j["bytes_read"].get<std::uint64_t>());
  }
  std::filesystem::remove(out);
  std::filesystem::remove(out + ".json");
  return 0;
}
