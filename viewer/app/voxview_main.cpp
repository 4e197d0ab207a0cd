// `voxview`: look into a tractogram with correct-looking transparency, in a window or headless.
// Parse the command line (voxview_cli.h), resolve it into options (viewer_arguments.h), run; errors become
// exit codes.
#include <cstdio>
#include <exception>

#include <CLI/CLI.hpp>

#include "converter/command_line_typos.h"
#include "format/base/error.h"
#include "viewer/app/headless_render.h"
#include "viewer/app/viewer_arguments.h"
#include "viewer/app/voxview_cli.h"
#include "viewer/app/window_app.h"

int main(int argc, char** argv) {
  using namespace vxl;
  app::ViewerArguments arguments;
  CLI::App cli{app::voxview_description(VOXLINES_VERSION)};
  cli.set_version_flag("--version", VOXLINES_VERSION);
  app::declare_voxview_options(cli, arguments);
  try {
    app::parse_voxview_command_line(cli, arguments, argc, argv);
    const app::ViewerOptions options = app::resolve_viewer_options(arguments);
    return options.render_png ? app::run_headless(options) : app::run_window(options);
  } catch (const CLI::ParseError& e) {
    if (const std::string typo = typo_message(cli, argc, argv); !typo.empty() && e.get_exit_code() != 0) {
      std::fprintf(stderr, "voxview: error: %s\n", typo.c_str());
      return static_cast<int>(ErrorKind::Usage);
    }
    int code = cli.exit(e);
    return code == 0 ? 0 : static_cast<int>(ErrorKind::Usage);
  } catch (const Error& e) {
    std::fprintf(stderr, "voxview: error: %s\n", e.what());
    return static_cast<int>(e.kind());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "voxview: error: %s\n", e.what());
    return kExitInternalError;
  }
}
