#include "converter/share/share_folder.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <system_error>

#include <unistd.h>

#include <nlohmann/json.hpp>

#include "converter/package/unpack.h"
#include "format/base/error.h"
#include "format/vxl_file.h"
#include "format/vxl_layout.h"
#include "format/vxlz_layout.h"
#include "format/vxlz_package.h"

namespace vxl {
namespace {

namespace fs = std::filesystem;

[[noreturn]] void fail_output(const std::string& path, const std::string& what) {
  throw Error(ErrorKind::Output, path, std::nullopt, what);
}

// The first eight bytes of `path`, to tell a .vxl from a .vxlz whatever its name.
std::array<std::uint8_t, 8> magic_of(const std::string& path) {
  std::array<std::uint8_t, 8> magic{};
  std::ifstream in(path, std::ios::binary);
  if (!in) fail_input(path, std::nullopt, "cannot open it");
  in.read(reinterpret_cast<char*>(magic.data()), magic.size());
  return magic;
}

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  if (!out.flush()) fail_output(path.string(), "cannot write it");
}

std::string readme(const std::string& title, const std::string& data_file) {
  return "# " + title +
         "\n\n"
         "A tractogram to look at in a web browser, with correctly ordered transparency (Voxlines).\n\n"
         "Serve this folder with any static web server and open index.html, for example:\n\n"
         "    python3 -m http.server 8000     (in this folder), then open http://localhost:8000/\n\n"
         "Opening index.html straight from the disk does not work: browsers do not let a page read files\n"
         "beside it. The folder can be put as it is on institutional web space or GitHub Pages.\n\n"
         "In the page: drag to turn, right-drag (or shift-drag) to pan, the wheel to zoom. \"Copy link to\n"
         "this view\" puts the view in the address, so that whoever opens the link sees what you saw.\n"
         "A large tractogram is drawn in less detail where it would not fit the GPU: index.html?gpu=2G (or\n"
         "512M...) says how much GPU memory the page may take.\n\n"
         "The data is " +
         data_file +
         " (the .vxl format, or a .vxlz package of it); the Voxlines tools (voxlines, voxview) read it\n"
         "and export it back to TCK or TRX.\n";
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
  const auto magic = magic_of(in_path);
  fs::path data = fs::path(in_path).filename();
  const bool package = std::equal(kVxlzMagic.begin(), kVxlzMagic.end(), magic.begin());
  if (package && settings.unpack) {
    data.replace_extension(".vxl");
    UnpackSettings unpack;
    unpack.threads = settings.threads;
    summary.streamlines = unpack_vxlz(in_path, (staging / data).string(), unpack).streamlines;
    summary.unpacked = true;
  } else {
    // Opened first, so that a damaged file is refused here rather than in the recipient's browser (a package's
    // checksums cover every byte of it).
    summary.streamlines =
        package ? VxlzFile::open(in_path).meta().streamline_count : VxlFile::open(in_path).meta().streamline_count;
    summary.package = package;
    const char* suffix = package ? ".vxlz" : ".vxl";
    if (data.extension() != suffix) data.replace_extension(suffix);
    std::error_code ec;
    fs::copy_file(in_path, staging / data, ec);
    if (ec) fail_output((staging / data).string(), "cannot copy the tractogram: " + ec.message());
  }
  summary.data_file = data.string();
  summary.data_bytes = fs::file_size(staging / data);
  const std::string title = settings.title.empty() ? fs::path(in_path).stem().string() : settings.title;
  write_text(
      staging / "share.json",
      nlohmann::json{{"file", summary.data_file}, {"title", title}, {"voxlines", VOXLINES_VERSION}}.dump(2) + "\n");
  write_text(staging / "README.txt", readme(title, summary.data_file));
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
