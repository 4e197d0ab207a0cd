#include <cstdio>

#include <nlohmann/json.hpp>

#include "converter/cli/commands.h"
#include "converter/export/streamline_outputs.h"
#include "converter/selection/selection_output.h"
#include "converter/selection/streamline_selection.h"
#include "format/base/error.h"

namespace vxl::cli {
namespace {

// The criteria as MRtrix would record them in a TCK header (one line each), so that a selection says how
// it was made.
std::vector<std::string> criteria_lines(const std::vector<std::string>& include, const std::vector<std::string>& ends,
                                        const std::vector<std::string>& exclude, const SelectionCriteria& c) {
  std::vector<std::string> out;
  for (const std::string& r : include) out.push_back("roi: include " + r);
  for (const std::string& r : ends) out.push_back("roi: ends_in " + r);
  for (const std::string& r : exclude) out.push_back("roi: exclude " + r);
  if (c.min_length) out.push_back("min_dist: " + std::to_string(*c.min_length));
  if (c.max_length) out.push_back("max_dist: " + std::to_string(*c.max_length));
  if (c.invert) out.push_back("voxlines_selection: inverted");
  if (c.level) out.push_back("voxlines_selection: level " + std::to_string(*c.level));
  return out;
}

struct SelectOptions {
  std::string input, output;
  std::vector<std::string> include, exclude, ends_in;
  std::optional<double> min_length, max_length;
  std::optional<std::uint32_t> level;
  bool invert = false, count = false, json = false, verbose = false;
  TckExportSettings tck;
};

// The criteria the options give. The region limit is checked before any image is read, and each image is read once
// however often it is named.
SelectionCriteria criteria_of(const SelectOptions& opt) {
  std::vector<std::string> texts = opt.include;
  texts.insert(texts.end(), opt.exclude.begin(), opt.exclude.end());
  texts.insert(texts.end(), opt.ends_in.begin(), opt.ends_in.end());
  if (texts.size() > kMaxRegions)
    throw Error(ErrorKind::Usage, "--include/--exclude/--ends-in", std::nullopt,
                "at most " + std::to_string(kMaxRegions) + " regions in one selection (" +
                    std::to_string(texts.size()) + " given)");
  std::vector<Region> regions = parse_regions(texts);
  SelectionCriteria criteria;
  auto take = [&](std::vector<Region>& into, std::size_t first, std::size_t count) {
    into.assign(std::make_move_iterator(regions.begin() + first),
                std::make_move_iterator(regions.begin() + first + count));
  };
  take(criteria.include, 0, opt.include.size());
  take(criteria.exclude, opt.include.size(), opt.exclude.size());
  take(criteria.ends_in, opt.include.size() + opt.exclude.size(), opt.ends_in.size());
  criteria.min_length = opt.min_length;
  criteria.max_length = opt.max_length;
  criteria.invert = opt.invert;
  criteria.level = opt.level;
  return criteria;
}

}  // namespace

void add_select_command(CLI::App& app) {
  auto opt = std::make_shared<SelectOptions>();
  CLI::App* cmd = app.add_subcommand(
      "select",
      "Select streamlines by regions and length (virtual dissection), with MRtrix tckedit's rules:\n"
      "  voxlines select IN.vxl " +
          streamline_output_usage(false) +
          " --include ROI [--include ROI]... "
          "[--exclude ROI]...\n"
          "  voxlines select IN.vxl --include ROI --count [--json]\n"
          "A streamline is kept when every --include region holds one of its points, every --ends-in region its first\n"
          "or last point, no --exclude region any of its points, and its length is within the limits. ROI: X,Y,Z,R (a\n"
          "sphere, RAS mm; a point at distance <= R is inside), box:X0,Y0,Z0,X1,Y1,Z1, FILE.nii[.gz] or FILE.mif[.gz]\n"
          "(its non-zero voxels: the voxel nearest to the point) or FILE.nii[.gz]:LABEL, FILE.mif[.gz]:LABEL (one "
          "label of a parcellation).\n"
          "Points are those the .vxl stores: bit for bit the source's with --positions float32; with packed positions\n"
          "(the default) within the bound `voxlines info` prints, so a streamline whose deciding point lies that "
          "close\n"
          "to a region's surface may be decided differently from tckedit on the source. Length limits are tckedit's:\n"
          "its float32 sum, the limits widened by the source header's step_size (a tenth of it, or half of it over\n"
          "downsample_factor); to the bit with float32 positions, within a few float32 roundings with packed ones.");
  cmd->add_option("input", opt->input, ".vxl file")->required();
  cmd->add_option("output", opt->output,
                  "the selected streamlines, in source order, as " + streamline_output_help(false) +
                      "; written atomically, valid when empty. Not needed with --count");
  cmd->add_option("--include", opt->include, "a region every kept streamline passes through (repeatable)")
      ->type_name("ROI");
  cmd->add_option("--exclude", opt->exclude, "a region no kept streamline touches (repeatable)")->type_name("ROI");
  cmd->add_option("--ends-in", opt->ends_in,
                  "a region holding the first or the last point of every kept streamline (repeatable; tckedit's "
                  "-include with -ends_only)")
      ->type_name("ROI");
  cmd->add_option("--min-length", opt->min_length,
                  "keep streamlines at least this long (mm; the sum of the segments, as tckedit measures it)")
      ->type_name("MM");
  cmd->add_option("--max-length", opt->max_length, "keep streamlines at most this long (mm)")->type_name("MM");
  cmd->add_flag("--invert", opt->invert, "keep exactly the streamlines the criteria reject (tckedit's -inverse)");
  cmd->add_option(
         "--level", opt->level,
         "of those, keep only the streamlines of this level of detail (1: about an eighth, 2: a 64th...,\n"
         "spread over the whole tractogram, as voxview draws it coarser): a smaller tractogram alike everywhere")
      ->type_name("N");
  CLI::Option* const count =
      cmd->add_flag("--count", opt->count, "print only the number of selected streamlines (no output file)");
  cmd->add_flag("--json", opt->json, "print the result as JSON");
  // With --count nothing is written: what would shape the output is refused rather than ignored.
  cmd->add_option("--tsf", opt->tck.tsf_path, "with a .tck output: also write one per-point value set as a TSF")
      ->excludes(count);
  cmd->add_option("--value", opt->tck.value, "the per-point value set for --tsf (default: the first)")->excludes(count);
  cmd->add_flag("--verbose", opt->verbose, "say what the query touched");
  cmd->callback([opt] {
    if (opt->count == !opt->output.empty())
      throw Error(ErrorKind::Usage, opt->input, std::nullopt,
                  opt->count ? "--count prints the count: give no output file" : "give an output file, or --count");
    if (!opt->output.empty() && !is_selection_output(opt->output))
      throw Error(ErrorKind::Usage, opt->output, std::nullopt,
                  "a selection is written to " + streamline_output_suffixes(false));
    for (const std::optional<double>& limit : {opt->min_length, opt->max_length})
      if (limit && !(std::isfinite(*limit) && *limit >= 0))
        throw Error(ErrorKind::Usage, "--min-length/--max-length", std::nullopt,
                    "a length limit is a finite, non-negative number of mm");
    const SelectionCriteria criteria = criteria_of(*opt);

    const VxlFile file = VxlFile::open(opt->input);
    const SelectionResult result = select_streamlines(file, criteria);
    file.release_resident_pages();  // what the query read; the writer maps again what it needs
    const std::uint64_t total = file.meta().streamline_count;
    std::vector<std::string> warnings;
    if (!opt->count) {
      const StreamlineSubset subset(total, result.streamlines);
      warnings = write_selection(file, subset, opt->output, opt->tck,
                                 criteria_lines(opt->include, opt->ends_in, opt->exclude, criteria));
    }
    for (const std::string& w : warnings) std::fprintf(stderr, "voxlines: warning: %s\n", w.c_str());
    const std::uint64_t kept = result.streamlines.size();
    if (opt->json) {
      nlohmann::json j = {{"selected", kept},
                          {"streamlines", total},
                          {"voxels_touched", result.voxels_touched},
                          {"voxels", file.meta().voxel_count},
                          {"points_tested", result.points_tested},
                          {"lengths_read", result.lengths_read},
                          {"streamlines_measured", result.streamlines_measured},
                          {"bytes_read", result.bytes_read},
                          {"file_bytes", file.bytes().size()}};
      if (!opt->output.empty()) j["output"] = opt->output;
      std::printf("%s\n", j.dump(2).c_str());
    } else if (opt->count) {
      std::printf("%llu\n", (unsigned long long)kept);
    } else {
      std::printf("%s: %llu of %llu streamlines selected\n", opt->output.c_str(), (unsigned long long)kept,
                  (unsigned long long)total);
    }
    if (opt->verbose && !opt->json)
      std::fprintf(stderr,
                   "select: %u of %u voxels touched, %llu points tested, %llu lengths read, %llu streamlines measured, "
                   "%llu of %llu bytes read\n",
                   result.voxels_touched, file.meta().voxel_count, (unsigned long long)result.points_tested,
                   (unsigned long long)result.lengths_read, (unsigned long long)result.streamlines_measured,
                   (unsigned long long)result.bytes_read, (unsigned long long)file.bytes().size());
  });
}

}  // namespace vxl::cli
