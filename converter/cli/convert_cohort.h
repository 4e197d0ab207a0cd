// The cohort form of `voxlines convert`: IN... --output-dir DIR [--jobs N] writes DIR/<stem>.vxl for each
// input, N files at a time. A file that fails is reported (naming it) and the others go on.
#pragma once

#include <string>
#include <vector>

#include "converter/convert/convert.h"

namespace vxl::cli {

struct CohortOptions {
  std::vector<std::string> inputs;
  std::string output_dir;
  unsigned jobs = 1;
  ConvertSettings settings;      // threads: in all (0: all cores), shared among the jobs; memory_limit: per file
  std::vector<std::string> tsf;  // only with a single input
  bool verbose = false;
};

// Exit code when files failed with more than one kind of error (one kind: that kind's code).
inline constexpr int kCohortMixedFailures = 6;

// The output name of an input: its file name without its source suffix (readers/source_formats.h; any
// case; another extension: the last one), plus ".vxl". Throws vxl::Error (Usage) when nothing is left.
std::string cohort_output_name(const std::string& input);

// Worker threads for each file when `jobs` files are converted at once out of `threads` in all.
unsigned threads_per_job(unsigned threads, unsigned jobs);

// Checks everything that can be checked before any work (distinct output names, DIR usable; DIR is created
// when missing), then converts. Returns the exit code: 0 when every file was converted, else the failures'
// error kind when they share one, else kCohortMixedFailures. Throws vxl::Error for what is refused up front.
int run_cohort(const CohortOptions& options);

}  // namespace vxl::cli
