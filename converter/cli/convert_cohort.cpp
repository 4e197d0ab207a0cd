#include "converter/cli/convert_cohort.h"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <new>
#include <set>

#include <unistd.h>

#include "converter/cli/convert_file.h"
#include "converter/cli/progress_bar.h"
#include "converter/readers/source_formats.h"
#include "format/base/error.h"
#include "format/base/parallel.h"

namespace vxl::cli {
namespace {

namespace fs = std::filesystem;

constexpr int kInternalError = 70;  // main()'s code for an exception that is not a vxl::Error

// DIR is created when missing (a cluster job's first file should not need a separate mkdir); an existing
// path must be a directory this process can write into, so that a typo fails before any file is read.
void prepare_output_dir(const std::string& dir) {
  if (dir.empty()) throw Error(ErrorKind::Usage, dir, std::nullopt, "--output-dir needs a directory name");
  std::error_code ec;
  if (!fs::exists(dir, ec)) {
    fs::create_directories(dir, ec);
    if (ec) throw Error(ErrorKind::Output, dir, std::nullopt, "cannot create the output directory: " + ec.message());
  } else if (!fs::is_directory(dir, ec)) {
    throw Error(ErrorKind::Output, dir, std::nullopt, "--output-dir is not a directory");
  }
  if (::access(dir.c_str(), W_OK | X_OK) != 0)
    throw Error(ErrorKind::Output, dir, std::nullopt,
                std::string("cannot write into the output directory: ") + std::strerror(errno));
}

// The message of a failed file, naming the input even when the error is about another file (its output,
// a TSF file).
std::string failure_message(const std::string& input, const std::string& what, const std::string& about) {
  return about == input ? what : input + ": " + what;
}

}  // namespace

std::string cohort_output_name(const std::string& input) {
  std::string path = input;
  while (path.size() > 1 && path.back() == '/') path.pop_back();  // a TRX directory given as "x.trx/"
  std::string name = fs::path(path).filename().string();
  if (const SourceMatch match = source_format_of(name); match.format && name.size() > match.suffix.size())
    name.resize(name.size() - match.suffix.size());
  else
    name = fs::path(name).stem().string();
  if (name.empty() || name == "." || name == "..")
    throw Error(ErrorKind::Usage, input, std::nullopt,
                "has no file name to name its output after (--output-dir writes DIR/NAME.vxl)");
  return name + ".vxl";
}

unsigned threads_per_job(unsigned threads, unsigned jobs) {
  return std::max(1u, resolve_threads(threads) / std::max(1u, jobs));
}

int run_cohort(const CohortOptions& o) {
  const std::size_t n = o.inputs.size();
  if (!o.tsf.empty() && n > 1)
    throw Error(
        ErrorKind::Usage, o.inputs[1], std::nullopt,
        "--tsf values belong to one tractogram: give a single input with --tsf, or convert the others without it");

  // Distinct output names first: a refused command line must not create DIR or start any file.
  std::vector<std::string> outputs(n);
  std::map<std::string, std::size_t> first_with_name;
  for (std::size_t i = 0; i < n; ++i) {
    const std::string name = cohort_output_name(o.inputs[i]);
    outputs[i] = (fs::path(o.output_dir) / name).string();
    auto [it, fresh] = first_with_name.emplace(name, i);
    if (!fresh)
      throw Error(ErrorKind::Usage, o.inputs[i], std::nullopt,
                  "would be written to " + outputs[i] + ", like " + o.inputs[it->second] +
                      ": two inputs with the same name (without extension); rename one or convert them into "
                      "different --output-dir");
  }
  prepare_output_dir(o.output_dir);

  const unsigned jobs = static_cast<unsigned>(std::min<std::size_t>(std::max(1u, o.jobs), n));
  const bool terminal = ProgressBar::stderr_is_terminal();
  std::mutex io;
  std::vector<int> failed_code(n, 0);  // per input: 0 converted, else the exit code of its error
  auto print = [&io](std::FILE* to, const std::string& text) {
    std::lock_guard lock(io);
    std::fputs(text.c_str(), to);
    std::fflush(to);
  };

  // Every item catches its own errors: parallel_for would stop handing out files at the first one.
  parallel_for(n, jobs, [&](std::uint64_t i, unsigned) {
    const std::string& in = o.inputs[i];
    const std::string tag = "[" + std::to_string(i + 1) + "/" + std::to_string(n) + "]";
    ConvertSettings settings = o.settings;
    settings.threads = threads_per_job(o.settings.threads, jobs);
    // One file at a time: its bar. Several: a bar per file would overwrite the others' lines, so a line
    // when each starts; the report or the error says when it ends.
    std::unique_ptr<ProgressBar> bar;
    if (jobs == 1) {
      bar = std::make_unique<ProgressBar>(tag + " " + fs::path(in).filename().string());
      settings.progress = [&bar](const char* stage, double f) { bar->update(stage, f); };
      bar->update("reading", 0.0);
    } else {
      settings.progress = nullptr;
      if (terminal) print(stderr, tag + " " + in + " -> " + outputs[i] + "\n");
    }
    auto say = [&](std::FILE* to, const std::string& text) {
      if (bar) bar->done();
      print(to, text);
    };
    try {
      const std::string report = convert_file(
          in, outputs[i], o.tsf, settings, o.verbose,
          [&](const std::string& w) { say(stderr, "voxlines: warning: " + in + ": " + w + "\n"); }, jobs);
      say(stdout, report);
    } catch (const Error& e) {
      failed_code[i] = static_cast<int>(e.kind());
      say(stderr, "voxlines: error: " + failure_message(in, e.what(), e.file()) + "\n");
    } catch (const std::bad_alloc&) {
      failed_code[i] = static_cast<int>(ErrorKind::Unsupported);
      say(stderr, "voxlines: error: " + in + ": out of memory\n");
    } catch (const std::exception& e) {
      failed_code[i] = kInternalError;
      say(stderr, "voxlines: internal error: " + in + ": " + e.what() + "\n");
    }
  });

  std::set<int> codes;
  std::string failed_names;
  for (std::size_t i = 0; i < n; ++i)
    if (failed_code[i] != 0) {
      codes.insert(failed_code[i]);
      failed_names += (failed_names.empty() ? "" : ", ") + o.inputs[i];
    }
  const std::size_t failed = std::count_if(failed_code.begin(), failed_code.end(), [](int c) { return c != 0; });
  const std::string which = failed ? " (" + failed_names + ")" : "";
  std::printf("%zu converted, %zu failed%s\n", n - failed, failed, which.c_str());
  if (codes.empty()) return 0;
  return codes.size() == 1 ? *codes.begin() : kCohortMixedFailures;
}

}  // namespace vxl::cli
