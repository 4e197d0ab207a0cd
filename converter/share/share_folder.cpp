#include "converter/share/share_folder.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <system_error>

#include <unistd.h>

#include <nlohmann/json.hpp>

#include "converter/package/unpack.h"
#include "converter/selection/selection_output.h"
#include "converter/selection/streamline_selection.h"
#include "format/base/error.h"
#include "format/base/memory_size.h"
#include "format/vxl_file.h"
#include "format/vxl_layout.h"
#include "format/vxl_level_image.h"
#include "format/vxl_levels.h"
#include "format/vxlz_layout.h"
#include "format/vxlz_package.h"

namespace vxl {
namespace {

namespace fs = std::filesystem;

[[noreturn]] void fail_output(const std::string& path, const std::string& what) {
  throw Error(ErrorKind::Output, path, std::nullopt, what);
}

void copy_file(const std::string& from, const fs::path& to) {
  std::error_code ec;
  fs::copy_file(from, to, ec);
  if (ec) fail_output(to.string(), "cannot copy the tractogram: " + ec.message());
}

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  if (!out.flush()) fail_output(path.string(), "cannot write it");
}

std::string readme(const std::string& title, const std::string& data_file, std::optional<std::uint32_t> image_level) {
  const std::string drawn =
      !image_level        ? std::string()
      : *image_level == 0 ? "all of it but the streamline tables (no unsorted mode, no colouring by value or group)"
                          : "its level of detail " + std::to_string(*image_level) + " (about 1/" +
                                std::to_string(1ull << (3 * *image_level)) +
                                " of the streamlines,\nspread over the whole) and the coarser ones";
  const std::string large = image_level ? "The tractogram is larger than a browser holds: the page draws " + drawn +
                                              ", fetching only their bytes by HTTP Range requests.\n\n"
                                        : std::string();
  // Python's server sends whole files: the page then reads the tractogram whole, which it cannot for a larger one.
  const std::string serve =
      image_level
          ? "Serve this folder with a static web server that answers HTTP Range requests (nginx, Apache and most\n"
            "hosting do; python3 -m http.server does not) and open index.html.\n\n"
          : "Serve this folder with any static web server and open index.html, for example:\n\n"
            "    python3 -m http.server 8000     (in this folder), then open http://localhost:8000/\n\n";
  return "# " + title +
         "\n\n"
         "A tractogram to look at in a web browser, with correctly ordered transparency (Voxlines).\n\n" +
         serve +
         "Opening index.html straight from the disk does not work: browsers do not let a page read files\n"
         "beside it. The folder can be put as it is on institutional web space or GitHub Pages.\n\n"
         "In the page: drag to turn, right-drag (or shift-drag) to pan, the wheel to zoom. \"Copy link to\n"
         "this view\" puts the view in the address, so that whoever opens the link sees what you saw.\n"
         "A large tractogram is drawn in less detail where it would not fit the GPU: index.html?gpu=2G (or\n"
         "512M...) says how much GPU memory the page may take.\n\n" +
         large + "The data is " + data_file +
         " (the .vxl format, or a .vxlz package of it); the Voxlines tools (voxlines, voxview) read it\n"
         "and export it back to TCK, TRK, TRX or VTK (a .vxlz after `voxlines unpack`).\n";
}

// A package's .vxl of `bytes` for the page, which unpacks it whole in WebAssembly's memory: refused where that is
// too small, naming --unpack (a .vxl larger than the page holds is drawn from its coarser levels) and the level of
// detail that would fit. The .vxl has `levels` levels; each holds about an eighth of the next finer one's
// streamlines, and its file shrinks alike.
void check_package_fits_the_page(const std::string& in_path, std::uint64_t bytes, std::uint32_t levels,
                                 const ShareSettings& settings) {
  if (bytes <= settings.max_data_bytes) return;
  auto size_at = [&](std::uint32_t level) { return double(bytes) / std::pow(8.0, level); };
  std::uint32_t level = 1;
  while (level < levels && size_at(level) > 0.9 * double(settings.max_data_bytes)) ++level;
  const std::string alone = level < levels ? ", or a coarser level of detail alone: --level " + std::to_string(level) +
                                                 " keeps about 1/" + std::to_string(1ull << (3 * level)) +
                                                 " of the streamlines, spread over the whole tractogram (some " +
                                                 format_memory_size(std::uint64_t(size_at(level))) + ")"
                                           : std::string();
  throw Error(ErrorKind::Unsupported, in_path, std::nullopt,
              "the .vxl to share is " + format_memory_size(bytes) + ", more than the web viewer holds (" +
                  format_memory_size(settings.max_data_bytes) +
                  " in a browser's WebAssembly memory) to unpack a package: share it unpacked (--unpack: the page "
                  "then draws the coarser levels of detail that fit, fetched by ranges)" +
                  alone);
}

// The level of detail the page draws `file` from (a level image, vxl_level_image.h) where the file is larger than it
// holds; nullopt where it holds the file. Refused where not even the coarsest level's image fits.
std::optional<std::uint32_t> page_image_level(const std::string& in_path, const VxlFile& file,
                                              const ShareSettings& settings) {
  if (file.bytes().size() <= settings.max_data_bytes) return std::nullopt;
  if (const auto image = level_image_size(file, settings.max_data_bytes)) return image->level;
  throw Error(ErrorKind::Unsupported, in_path, std::nullopt,
              "the .vxl to share is " + format_memory_size(file.bytes().size()) + "; the web viewer holds at most " +
                  format_memory_size(settings.max_data_bytes) +
                  " (a browser's WebAssembly memory) and draws a larger file from its coarser levels of detail, but "
                  "not even its coarsest level (" +
                  std::to_string(file.level_count() - 1) +
                  ") fits: share a part of it (voxlines select IN.vxl OUT.vxl --include ROI ...)");
}

// The streamlines of `level` of `file` (those of depth >= level, spec §6.5), written to `out_path` as a .vxl; their
// count. Not a selection's criteria: those would also apply the length limits tckedit takes from the source header.
std::uint64_t write_level(const VxlFile& file, const std::string& out_path, std::uint32_t level) {
  check_level(file.path(), level, file.level_count());
  std::vector<std::uint64_t> kept;
  for (std::uint64_t s = 0; s < file.meta().streamline_count; ++s)
    if (streamline_depth(s, file.level_count()) >= level) kept.push_back(s);
  write_selection(file, StreamlineSubset(file.meta().streamline_count, kept), out_path, {},
                  {"voxlines_selection: level " + std::to_string(level)});
  return kept.size();
}

// The folder's content, written into `staging`.
ShareSummary fill_folder(const std::string& in_path, const fs::path& staging, const ShareSettings& settings) {
  ShareSummary summary;
  for (const char* name : kWebViewerFiles) {
    std::error_code ec;
    fs::copy_file(fs::path(settings.web_viewer_dir) / name, staging / name, ec);
    if (ec)
      fail_output((staging / name).string(), "cannot copy the web viewer's " + std::string(name) + ": " + ec.message());
  }
  fs::path data = fs::path(in_path).filename();
  const bool package = starts_as_vxlz(in_path);
  if (!package) {
    // Opened first, so that a damaged file is refused here rather than in the recipient's browser.
    const VxlFile file = VxlFile::open(in_path);
    if (settings.unpack)
      throw Error(ErrorKind::Usage, in_path, std::nullopt,
                  "--unpack unpacks a .vxlz package; this is a .vxl, shared as it is (leave --unpack out)");
    data.replace_extension(".vxl");
    if (settings.level) {
      summary.streamlines = write_level(file, (staging / data).string(), *settings.level);
      summary.image_level = page_image_level(in_path, VxlFile::open((staging / data).string()), settings);
    } else {
      summary.streamlines = file.meta().streamline_count;
      summary.image_level = page_image_level(in_path, file, settings);
      copy_file(in_path, staging / data);
    }
  } else if (settings.unpack || settings.level) {
    const VxlzFile package_file = VxlzFile::open(in_path);
    UnpackSettings unpack;
    unpack.threads = settings.threads;
    if (settings.level) check_level(in_path, *settings.level, package_levels(package_file));  // those unpacked
    data.replace_extension(".vxl");
    // Not a .vxl's name: the shared file's is the input's with .vxl, whatever the input was called.
    const fs::path unpacked = settings.level ? staging / "unpacked.tmp" : staging / data;
    summary.streamlines = unpack_vxlz(package_file, unpacked.string(), unpack).streamlines;
    summary.unpacked = true;
    if (settings.level) {
      const VxlFile file = VxlFile::open(unpacked.string());
      summary.streamlines = write_level(file, (staging / data).string(), *settings.level);
      std::error_code ec;
      fs::remove(unpacked, ec);  // without --level it is the shared file, in the staging folder
    }
    summary.image_level = page_image_level(in_path, VxlFile::open((staging / data).string()), settings);
  } else {
    // A package's checksums cover every byte of it. The page unpacks it in its own memory, as large as the .vxl
    // (UnpackSettings' defaults): a .vxl larger than the page holds is refused here, not after the recipient has
    // fetched the package.
    const VxlzFile package_file = VxlzFile::open(in_path);
    summary.streamlines = package_file.meta().streamline_count;
    const UnpackSettings as_the_page;
    check_package_fits_the_page(in_path, unpacked_vxl_bytes(package_file, as_the_page), package_levels(package_file),
                                settings);
    summary.package = true;
    data.replace_extension(".vxlz");
    copy_file(in_path, staging / data);
  }
  summary.data_file = data.string();
  summary.data_bytes = fs::file_size(staging / data);
  const std::string title = settings.title.empty() ? fs::path(in_path).stem().string() : settings.title;
  write_text(
      staging / "share.json",
      nlohmann::json{{"file", summary.data_file}, {"title", title}, {"voxlines", VOXLINES_VERSION}}.dump(2) + "\n");
  write_text(staging / "README.txt", readme(title, summary.data_file, summary.image_level));
  return summary;
}

}  // namespace

ShareSummary share_folder(const std::string& in_path, const std::string& out_dir, const ShareSettings& settings) {
  for (const char* name : kWebViewerFiles)
    if (!fs::is_regular_file(fs::path(settings.web_viewer_dir) / name))
      throw Error(ErrorKind::Unsupported, settings.web_viewer_dir, std::nullopt,
                  "no web viewer here (" + std::string(name) +
                      " is missing): this voxlines was built without it (CMake option VOXLINES_WEB, which needs "
                      "Emscripten)");
  const fs::path out(out_dir);
  if (fs::exists(fs::symlink_status(out))) fail_output(out_dir, "exists already: name a new folder");
  const fs::path parent = out.parent_path().empty() ? fs::path(".") : out.parent_path();
  if (!fs::is_directory(parent)) fail_output(out_dir, "its parent folder does not exist");
  const fs::path staging = parent / ("." + out.filename().string() + ".part-" + std::to_string(::getpid()));
  std::error_code ec;
  if (!fs::create_directory(staging, ec) || ec)
    fail_output(staging.string(), "cannot make the folder: " + (ec ? ec.message() : std::string("it exists")));
  try {
    ShareSummary summary = fill_folder(in_path, staging, settings);
    fs::rename(staging, out, ec);
    if (ec) fail_output(out_dir, "cannot move the finished folder into place: " + ec.message());
    return summary;
  } catch (...) {
    fs::remove_all(staging, ec);
    throw;
  }
}

}  // namespace vxl
