#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "converter/cli/commands.h"
#include "converter/share/share_folder.h"

namespace vxl::cli {
namespace {

// Where the built web viewer is: $VOXLINES_WEB_VIEWER, else the build tree's (a build with VOXLINES_WEB),
// else beside an installed voxlines (PREFIX/share/voxlines/web).
std::string default_web_viewer_dir() {
  if (const char* env = std::getenv("VOXLINES_WEB_VIEWER"); env != nullptr && *env != '\0') return env;
#ifdef VOXLINES_WEB_VIEWER_DIR
  if (std::filesystem::is_directory(VOXLINES_WEB_VIEWER_DIR)) return VOXLINES_WEB_VIEWER_DIR;
#endif
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::string("share/voxlines/web") : (exe.parent_path().parent_path() / "share/voxlines/web").string();
}

}  // namespace

void add_share_command(CLI::App& app) {
  struct Options {
    std::string input, output;
    ShareSettings settings;
  };
  auto opt = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "share",
      "Make a folder that shows a tractogram in any web browser, with the same sorted transparency as voxview:\n"
      "the web viewer, the tractogram (a .vxl, or a .vxlz, which the page unpacks) and a README for the recipient.\n"
      "Serve it with any static web server (python3 -m http.server in the folder) and open index.html");
  cmd->add_option("input", opt->input, ".vxl file or .vxlz package")->required();
  cmd->add_option("output", opt->output, "the folder to make (must not exist; appears only when complete)")->required();
  cmd->add_option("--title", opt->settings.title, "title the page shows (default: the input's name)");
  cmd->add_option("--web-viewer", opt->settings.web_viewer_dir,
                  "the built web viewer's folder (default: $VOXLINES_WEB_VIEWER, this build's, or "
                  "PREFIX/share/voxlines/web)");
  cmd->add_flag("--unpack", opt->settings.unpack,
                "a .vxlz: write it unpacked, as a .vxl (about 8 times larger to host; the page then fetches a large\n"
                "one by ranges and shows its first picture before the rest is in, where it fetches a .vxlz whole)");
  cmd->add_option(
         "--level", opt->settings.level,
         "share only the streamlines of this level of detail, as a .vxl (1: about an eighth, 2: a 64th...,\n"
         "spread over the whole tractogram): a smaller file to host. Without it, a .vxl larger than a browser\n"
         "holds (3.75 GiB) is drawn from the coarser levels that fit, fetched by ranges")
      ->type_name("N");
  add_threads_option(cmd, opt->settings.threads,
                     "worker threads for unpacking a .vxlz (--unpack, --level; 0: all cores)");
  cmd->callback([opt] {
    if (opt->settings.web_viewer_dir.empty()) opt->settings.web_viewer_dir = default_web_viewer_dir();
    const ShareSummary s = share_folder(opt->input, opt->output, opt->settings);
    const std::string how = opt->settings.level ? ", level " + std::to_string(*opt->settings.level) + " of the input"
                            : s.unpacked        ? ", unpacked from the .vxlz"
                            : s.package         ? ", unpacked by the page"
                                                : "";
    std::printf("%s: %llu streamlines in %s (%.1f MiB%s); serve the folder and open index.html\n", opt->output.c_str(),
                (unsigned long long)s.streamlines, s.data_file.c_str(), double(s.data_bytes) / (1 << 20), how.c_str());
    if (s.image_level)
      std::printf(
          "larger than a browser holds: the page draws %s, fetched by ranges: serve it with a server that answers "
          "Range requests (most do; python3 -m http.server does not)\n",
          *s.image_level == 0 ? "it without its streamline tables (no unsorted mode, no colouring by value or group)"
                              : ("level " + std::to_string(*s.image_level) + " and coarser (about 1/" +
                                 std::to_string(1ull << (3 * *s.image_level)) + " of the streamlines)")
                                    .c_str());
  });
}

}  // namespace vxl::cli
