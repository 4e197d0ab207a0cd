// The Dear ImGui panel of the voxview window: the only file that knows ImGui. It edits a PanelState in
// place, shows read-only PanelStats, and reports one-shot requests (a view preset, a screenshot, a camera
// reset) for the window to carry out.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "viewer/render/render_settings.h"

struct GLFWwindow;

namespace vxl::app {

// What the panel edits.
struct PanelState {
  RenderSettings settings;
  bool orthographic = false;
  bool grid = false;      // voxel-grid overlay
  bool grid_all = false;  // all voxels, not only those the frame draws
  bool panel_in_screenshot = false;
  bool panel_collapsed = false;  // only the title bar shows (H, or its arrow)
  bool exact_when_still = true;  // at rest, go on to the exact picture (rest_refinement.h)
  bool show_regions = true;      // the selection's spheres and boxes drawn as shells (region_shells.h)
  double slab_thickness = 10.0;  // mm, kept while the slab is off (settings.clipping.slab_mm is 0 then)
};

// What the panel only shows.
struct PanelStats {
  std::string title;    // the file shown
  double frame_ms = 0;  // smoothed
  double plan_ms = 0;   // CPU plan of the last frame
  std::uint64_t voxels_drawn = 0, voxels_total = 0;
  std::uint64_t segments_drawn = 0, segments_total = 0;
  std::uint64_t grid_cubes = 0;
  std::string gl_renderer, gl_version;
  std::string detail;            // the level of detail drawn and why, when not full detail (scene_detail.h)
  std::string frame_level;       // the last frame's level when the frame budget chose a coarser one
  double frame_budget_ms = 0;    // --frame-budget (0: none)
  std::string refinement;        // what the refinement at rest is doing (rest_refinement.h), "" when done
  bool exact_available = true;   // GL >= 4.3
  float max_line_width = 16.0f;  // the driver's wide-line limit
  std::string error;             // shown in red until the next one replaces it
  std::string status;            // e.g. where the last screenshot went
  double bounds_min[3] = {0, 0, 0}, bounds_max[3] = {0, 0, 0};  // scene bounds, for the clip-plane sliders
  std::vector<std::string> value_sets;                          // what --color scalar can show
  std::vector<std::pair<std::string, std::uint64_t>> groups;    // name, streamlines
  std::array<float, 2> scalar_range = {0, 1};                   // the range in use
  bool has_image = false;                                       // --image: the slice controls are shown
  std::array<float, 2> image_range = {0, 1};                    // the slices' grey range in use
  double focus[3] = {0, 0, 0};                                  // the focus point (camera target), RAS mm
  // The selection's regions (region_editor.h) and what they select.
  struct Region {
    std::string role, argument;  // "include", "exclude", "ends in"; as `voxlines select` takes it
    std::uint64_t streamlines = 0;
    bool sphere = false, active = false;
    double radius = 0;
  };
  std::vector<Region> regions;
  std::string selection;  // "N of M streamlines selected", "" without regions
};

struct PanelRequests {
  std::optional<std::array<double, 2>> view;  // azimuth, elevation
  bool reset_camera = false;
  bool screenshot = false;
  bool save_view = false;                      // write the view (camera and settings) for --camera
  double move_focus = 0;                       // mm along the view direction (moves the slab)
  std::optional<std::array<double, 3>> focus;  // a new focus point (moves the slices), RAS mm
  // Selection: add a sphere at the focus, make a region active, edit or remove the active one, save.
  bool add_region = false, remove_region = false, toggle_region = false, save_selection = false;
  std::optional<std::size_t> activate_region;
  std::optional<double> region_radius;
};

class UiPanel {
 public:
  // Installs ImGui's GLFW callbacks after the window's own ones, which it chains to.
  explicit UiPanel(GLFWwindow* window);
  ~UiPanel();
  UiPanel(const UiPanel&) = delete;
  UiPanel& operator=(const UiPanel&) = delete;

  // Starts an ImGui frame and lays out the panel. Call render() later in the same frame.
  PanelRequests build(PanelState& state, const PanelStats& stats);
  // Draws the panel into the bound (default) framebuffer.
  void render();

  // Whether a click or wheel at window point (x, y) belongs to the panel. Decided on the panel's last
  // rectangle rather than ImGui's hover state, which is only as fresh as the last frame (slow frames on a
  // software renderer would hand clicks on the scene to the panel).
  bool takes_mouse_at(double x, double y) const;
  // Whether the panel takes typed keys (a text field is being edited).
  bool wants_keyboard() const;

 private:
  float x0_ = 0, y0_ = 0, x1_ = 0, y1_ = 0;  // the panel window, window units
  bool popup_open_ = false;                  // a combo or colour picker may reach beyond the panel
  bool collapsed_ = false;                   // as the panel last was: a change in PanelState is the H key's
};

}  // namespace vxl::app
