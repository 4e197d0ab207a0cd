// Saved views (`voxview --camera FILE.json`, `--save-camera FILE.json`, the window's V key): everything
// that decides a picture apart from the data — the camera, the render settings (mode, opacity, colour mode,
// colour map, range, group colours, line width, background, lighting, orientation labels, colour bar, slab and
// clip planes) and the image size — as a small JSON file, so that a view found in the window can be rendered
// again headless, identically, for a figure.
//
//   {
//     "voxview_view": 1,
//     "size": [1024, 768],
//     "camera": {"target": [x, y, z], "distance": 300, "azimuth_deg": -35, "elevation_deg": 25,
//                "fov_y_deg": 30, "orthographic": false, "ortho_height": 200},
//     "settings": {"mode": "axis", "opacity": 0.3, "color": "direction", "fixed_color": [1, 0.85, 0.3],
//                  "colormap": "viridis", "scalar": "", "range": null,
//                  "groups": [{"name": "ARC_L", "color": "#e41a1c", "opacity": 1}],
//                  "line_width": 1, "background": "black", "lighting": false, "orientation_labels": false,
//                  "colorbar": false, "order_hysteresis": 0,
//                  "slab_mm": 0, "clip": [{"plane": "-x,10", "enabled": true}]},
//     "selection": {"include": ["-9,-23,-30,6"], "exclude": [], "ends_in": [], "show_regions": true}
//   }
//
// "background" takes what --background takes (a name, "#RRGGBB" or "R,G,B"; background_color.h).
// "selection" (the regions of voxview --include, --exclude, --ends-in and of the window) is written only
// when there are regions; "show_regions": whether their shells were drawn (the window's B, --show-regions).
//
// Numbers are written with enough digits to read back the same double or float. On reading, a missing key
// keeps its default (a hand-written file may give only what it changes) and unknown keys are ignored (a
// newer voxview's file still opens); a key of the wrong type or value is an error naming the file and the
// key.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "viewer/render/camera.h"
#include "viewer/render/render_settings.h"

namespace vxl::app {

struct SavedView {
  Camera camera;
  RenderSettings settings;
  std::optional<std::array<int, 2>> size;  // width, height
  bool has_camera = true;                  // false: the file has no "camera", and the view is framed as without one
  std::vector<std::string> include, exclude, ends_in;  // the selection's regions, as voxlines select takes them
  std::optional<bool> show_regions;                    // their shells drawn; none: not said (older files)
};

// A slab thickness that draws something: 0 (no slab), or within ViewLimits; and the range in words.
bool slab_is_drawable(double mm);
std::string slab_range_text();

// Throws vxl::Error: Input (naming the file and key) for malformed content or a camera beyond ViewLimits,
// Input when unreadable.
SavedView read_view(const std::string& path, const SavedView& defaults = {});
// Atomic (the file appears complete or not at all); throws vxl::Error (Output) naming the path.
void write_view(const std::string& path, const SavedView& view);

// The JSON text of a view, and its inverse (for tests and the two functions above; `path` names errors).
std::string view_json(const SavedView& view);
SavedView parse_view_json(const std::string& text, const std::string& path, const SavedView& defaults = {});

}  // namespace vxl::app
