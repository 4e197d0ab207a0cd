#include "viewer/app/focus_copy.h"

#include <atomic>
#include <filesystem>
#include <string>
#include <system_error>

#include <unistd.h>

#include "converter/export/streamline_subset.h"
#include "converter/selection/selection_output.h"
#include "format/base/output_path.h"

namespace vxl::app {

namespace {

// A name of this process's own in the temporary directory.
std::filesystem::path temporary_vxl() {
  static std::atomic<unsigned> counter{0};
  return temporary_folder() /
         ("voxview-focus-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + ".vxl");
}

}  // namespace

FocusCopy::FocusCopy(std::span<const VxlFile* const> files, const std::vector<std::vector<std::uint64_t>>& kept) {
  copies_.reserve(files.size());
  for (std::size_t i = 0; i < files.size(); ++i) {
    if (kept[i].empty()) continue;
    const std::filesystem::path path = temporary_vxl();
    try {
      write_selection(*files[i], StreamlineSubset(files[i]->meta().streamline_count, kept[i]), path.string(), {}, {});
      copies_.push_back(VxlFile::open(path.string()));
    } catch (...) {
      std::error_code ignored;
      std::filesystem::remove(path, ignored);
      throw;
    }
    std::error_code ignored;
    std::filesystem::remove(path, ignored);  // mapped: the copy lives on in memory
  }
  for (const VxlFile& f : copies_) pointers_.push_back(&f);
}

}  // namespace vxl::app
