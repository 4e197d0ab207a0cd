// voxview's command line as typed, and its checking and precedence: the defaults, then a saved view
// (--camera), then what the command line gives explicitly. No CLI11 here (voxview_cli.h parses), so the rules
// are unit tested on plain structs.
#pragma once

#include <set>
#include <string>
#include <vector>

#include "viewer/app/viewer_options.h"

namespace vxl::app {

struct ViewerArguments {
  // What needs no checking beyond the parser's (files, --render, --turntable, --ortho, --verify, ...).
  ViewerOptions options;
  // What is checked and combined here, as typed; the defaults are the command line's.
  std::string camera_file;  // --camera
  std::string mode = "axis", color = "direction", colormap = "viridis", background = "black";
  std::string partial_pictures = "auto";  // --partial-pictures: auto, always or never (the parser checks which)
  float opacity = kDefaultLineOpacity, line_width = 1.0f;
  std::string fixed_color, scalar, range;
  std::vector<std::string> groups, clips;
  bool lighting = false;
  bool orientation_labels = false, colorbar = false;
  double slab = 0;
  std::string image_range, slices, focus, view;
  std::string size = "1024x1024";
  std::string gpu_memory;           // --gpu-memory SIZE
  std::string memory_limit;         // --memory-limit SIZE
  std::string voxel_size = "10";    // --voxel-size MM|auto
  std::vector<double> drag_region;  // --drag-region DX,DY,DZ
  // With a selection: the focus's opacity (default --opacity) and the context's (0 hides it).
  std::optional<float> focus_opacity;
  float context_opacity = 0.02f;
  // The options given explicitly, by long name ("--mode"): only these override a saved view.
  std::set<std::string> given;
  bool was_given(const char* option) const { return given.count(option) > 0; }
};

// The options voxview runs with. Reads the saved view of `camera_file`, if any. Throws vxl::Error: Usage for
// options that do not parse or do not go together, what read_view throws for a bad view file, and Output for
// an output path (--render and its turntable frames, --save-camera, --stats, --screenshot) that cannot be
// written or that format/base/output_path.h's rule refuses.
ViewerOptions resolve_viewer_options(const ViewerArguments& arguments);

}  // namespace vxl::app
