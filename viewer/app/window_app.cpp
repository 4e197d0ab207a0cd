#include "viewer/app/window_app.h"
#include "viewer/platform/gl_driver_pinning.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include <epoxy/gl.h>
#define GLFW_INCLUDE_NONE  // epoxy provides the GL declarations
#include <GLFW/glfw3.h>

#include "converter/selection/selection_output.h"
#include "viewer/app/camera_controller.h"
#include "viewer/app/camera_file.h"
#include "viewer/app/frame_budget.h"
#include "viewer/app/frame_log.h"
#include "viewer/app/frame_pacing.h"
#include "viewer/app/headless_render.h"
#include "viewer/app/key_bindings.h"
#include "viewer/app/picture_annotations.h"
#include "viewer/app/picture_scheduler.h"
#include "viewer/app/process_clock.h"
#include "viewer/app/region_drag.h"
#include "viewer/app/region_editor.h"
#include "viewer/app/rest_refinement.h"
#include "viewer/app/scene_detail.h"
#include "viewer/app/scene_selection.h"
#include "viewer/app/scene_source.h"
#include "viewer/app/selection_worker.h"
#include "viewer/app/ui_panel.h"
#include "viewer/app/viewer_session.h"
#include "viewer/app/window_size.h"
#include "viewer/platform/image_io.h"
#include "viewer/platform/offscreen_target.h"
#include "viewer/render/background_color.h"
#include "viewer/render/grid_overlay.h"
#include "viewer/render/renderer.h"
#include "viewer/render/scene_framing.h"

namespace vxl::app {

namespace {

const char* const kHeadlessHint = "use --render OUT.png for headless rendering";

std::string g_glfw_error;  // GLFW reports errors through a callback; kept for the exception's message
void remember_glfw_error(int, const char* text) { g_glfw_error = text ? text : "unknown GLFW error"; }

// glfwInit / glfwTerminate. Without an X server glfwInit fails, which is the common case (ssh, CI).
struct GlfwLibrary {
  GlfwLibrary() {
    glfwSetErrorCallback(remember_glfw_error);
    if (!glfwInit())
      throw std::runtime_error("cannot open a window (no display?): " + g_glfw_error + "; " + kHeadlessHint);
  }
  ~GlfwLibrary() { glfwTerminate(); }
  GlfwLibrary(const GlfwLibrary&) = delete;
  GlfwLibrary& operator=(const GlfwLibrary&) = delete;
};

struct WindowDeleter {
  void operator()(GLFWwindow* w) const { glfwDestroyWindow(w); }
};
using WindowPtr = std::unique_ptr<GLFWwindow, WindowDeleter>;

WindowPtr open_window(const ViewerOptions& o) {
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  // Not forward-compatible: that would forbid line widths above 1.
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_FALSE);
  glfwWindowHint(GLFW_DEPTH_BITS, 24);  // the opaque mode depth-tests in the default framebuffer
  std::string title = "voxview -";
  for (const std::string& in : o.inputs) title += " " + std::filesystem::path(in).filename().string();
  // The default size is for a large screen: on a smaller one (a 1280x800 laptop) it is scaled down to fit.
  // A size given by --size or a saved view is kept.
  std::array<int, 2> size{o.width, o.height};
  if (!o.size_given) {
    int x = 0, y = 0, area_w = 0, area_h = 0;
    if (GLFWmonitor* monitor = glfwGetPrimaryMonitor()) glfwGetMonitorWorkarea(monitor, &x, &y, &area_w, &area_h);
    size = fit_to_work_area(o.width, o.height, area_w, area_h);
  }
  GLFWwindow* w = glfwCreateWindow(size[0], size[1], title.c_str(), nullptr, nullptr);
  if (!w) throw std::runtime_error("cannot open an OpenGL 3.3 core window: " + g_glfw_error + "; " + kHeadlessHint);
  glfwMakeContextCurrent(w);
  glfwSwapInterval(1);
  pin_dri_drivers();  // see gl_driver_pinning.h: Mesa's GLX path loads the same driver
  return WindowPtr(w);
}

// The mode after `m` in render_modes(), skipping those that need OpenGL 4.3 where the context has less.
RenderMode next_mode(RenderMode m, bool gl43) {
  const std::span<const RenderModeInfo> modes = render_modes();
  std::size_t i = static_cast<std::size_t>(
      std::find_if(modes.begin(), modes.end(), [m](const RenderModeInfo& info) { return info.mode == m; }) -
      modes.begin());
  do i = (i + 1) % modes.size();
  while (modes[i].needs_gl43 && !gl43);
  return modes[i].mode;
}

// The default framebuffer's back buffer as RGBA8 rows top to bottom (GL counts rows from the bottom).
Image read_back_buffer(int width, int height) {
  Image img;
  img.width = width;
  img.height = height;
  img.rgba.resize(static_cast<std::size_t>(width) * height * 4);
  std::vector<std::uint8_t> rows(img.rgba.size());
  glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
  glReadBuffer(GL_BACK);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, rows.data());
  const std::size_t stride = static_cast<std::size_t>(width) * 4;
  for (int y = 0; y < height; ++y)
    std::copy_n(rows.data() + (height - 1 - y) * stride, stride, img.rgba.data() + y * stride);
  // A window's picture is opaque whatever the framebuffer kept in alpha (it may have no alpha at all).
  for (std::size_t i = 3; i < img.rgba.size(); i += 4) img.rgba[i] = 255;
  return img;
}

// voxview-YYYYMMDD-HHMMSS.png (or .json, ...) in the current directory, with a suffix when taken twice in
// a second.
std::filesystem::path stamped_name(const std::string& prefix, const std::string& extension) {
  std::time_t now = std::time(nullptr);
  std::tm local{};
  localtime_r(&now, &local);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y%m%d-%H%M%S", &local);
  std::filesystem::path p = std::filesystem::current_path() / (prefix + stamp + extension);
  for (int n = 2; std::filesystem::exists(p); ++n)
    p = std::filesystem::current_path() / (prefix + stamp + "-" + std::to_string(n) + extension);
  return p;
}

// Whether two cameras show the same view (what the frame budget calls "not moving").
bool same_view(const Camera& a, const Camera& b) {
  return a.target == b.target && a.distance == b.distance && a.azimuth_deg == b.azimuth_deg &&
         a.elevation_deg == b.elevation_deg && a.fov_y_deg == b.fov_y_deg && a.orthographic == b.orthographic &&
         a.ortho_height == b.ortho_height;
}

// What a picture on screen depends on: when none of it changes, the window refines the picture instead of
// drawing it again.
struct PictureKey {
  Camera camera;
  RenderSettings settings;
  int width = 0, height = 0;
  bool grid = false, grid_all = false;
  std::uint64_t selection = 0;  // the selection the picture was drawn with (its generation; the regions' shells
                                // are in the settings)
};
bool same_picture(const PictureKey& a, const PictureKey& b) {
  return same_view(a.camera, b.camera) && a.settings == b.settings && a.width == b.width && a.height == b.height &&
         a.grid == b.grid && a.grid_all == b.grid_all && a.selection == b.selection;
}

// One open window on one scene: GL objects, camera, panel, input. Callbacks reach it through the GLFW
// user pointer.
class ViewerWindow {
 public:
  // `session`: the scene, its level of detail already chosen (ViewerSession::choose_detail); its renderers
  // go with the window, before the GL context. `start`: when voxview started, for --stats.
  // `regions`: the selection's regions (region_editor.h), edited in the window.
  ViewerWindow(const ViewerOptions& o, std::unique_ptr<ViewerSession> session, RegionEditor regions, GLFWwindow* window,
               std::chrono::steady_clock::time_point start, StartupTimes startup);
  int run();

 private:
  static ViewerWindow& of(GLFWwindow* w) { return *static_cast<ViewerWindow*>(glfwGetWindowUserPointer(w)); }
  void on_mouse_button(int button, int action, int mods);
  void on_cursor(double x, double y);
  void begin_region_drag(double x, double y);
  void on_scroll(double steps);
  void on_key(int key, int action, int mods);
  void on_char(unsigned codepoint);
  // Carries out a key's action (key_bindings.h); `shift` makes a move 10 times larger.
  void perform(KeyAction action, bool shift);
  void toggle_slices();
  void toggle_clip_plane(std::size_t i);
  void move_focus_along(int axis, double mm);
  // Asks for a new selection when the regions changed and takes the newest finished one into the picture
  // (selection_worker.h); with `wait`, the one the regions ask for now.
  void update_selection(bool wait);
  // Hands the focus and context to every renderer (without a selection: the files' own groups again).
  void apply_selection(std::optional<SceneSelection> selection);
  // Writes the selected streamlines of every file to a stamped .tck (a key or the panel).
  void save_selection();

  Camera home_camera(double aspect, bool orthographic) const;
  void reset_camera(double aspect);
  double aspect() const;
  void set_error(const std::string& message);
  // Draws the scene whole at `level` of detail into scene_target_; returns the frame's time in ms.
  double draw_scene(int width, int height, std::uint32_t level);
  // Draws the next piece of the refinement at rest (rest_refinement.h) into refine_target_; once the stage's
  // picture is complete it becomes scene_target_'s and `completes` is set. Returns the piece's time in ms.
  double refine(int width, int height, std::uint32_t level, bool& completes);
  // The grid overlay and the annotations (picture_annotations.h) over scene_target_'s picture, when they are on.
  void draw_overlays(const Renderer& renderer, int width, int height);
  // The panel's figures of a complete picture drawn by `renderer`.
  void show_frame_figures(const Renderer& renderer, std::uint32_t level);
  // scene_target_ into the window's back buffer.
  void present(int width, int height) const;
  double seconds_since_start() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }
  // The renderer of the scene's level, or of a coarser one (made on first use, for the frame budget).
  Renderer& renderer_at(std::uint32_t level);
  void save_screenshot(const std::string& path, int width, int height);
  // Writes the current view (camera, settings, size) to --save-camera's path or a stamped name.
  void save_view(int width, int height);

  const ViewerOptions& options_;
  GLFWwindow* window_;
  std::unique_ptr<ViewerSession> session_;  // the files, the image, the level of detail, the renderers
  const std::vector<const VxlFile*>& files_;
  RegionEditor regions_;
  std::optional<SceneSelection> selection_;          // the newest finished; the regions may have moved since
  std::optional<std::uint64_t> selection_revision_;  // the regions' revision last asked for
  std::optional<std::uint64_t> cleared_revision_;    // all regions removed at this revision: older selections are stale
  std::uint64_t selection_generation_ = 0;           // counts the selections taken into the picture
  SelectionWorker selection_worker_;
  std::vector<double> selection_ms_;  // each selection's run time, for --stats
  const SceneDetail& detail_;         // the level of detail drawn at rest, and the span size
  std::uint32_t first_level_ = 0;
  std::chrono::steady_clock::time_point start_;
  std::vector<FrameRecord> frames_;            // for --stats
  StartupTimes startup_;                       // for --stats
  std::optional<PictureKey> drawn_;            // what the picture on screen shows (none before the first)
  std::optional<PictureScheduler> scheduler_;  // what each frame draws (made once the GL version is known)
  std::optional<GridOverlay> grid_;
  std::optional<PictureAnnotations> annotations_;  // made when first wanted
  // The scene is drawn here and blitted to the window: it blends in float like headless rendering, so
  // faint layers add up beyond 8-bit rounding and the window shows what --render writes.
  std::optional<OffscreenTarget> scene_target_;
  std::optional<OffscreenTarget> refine_target_;  // the refinement's picture until it is complete
  CameraController controller_;
  std::vector<glm::dvec3> framing_points_;  // what the home view fills the window with (scene_framing.h)
  std::unique_ptr<UiPanel> panel_;          // created after our callbacks, which ImGui then chains to
  PanelState state_;
  PanelStats stats_;
  int drag_button_ = -1;
  bool dragging_region_ = false;   // Ctrl + left drag: the active sphere follows the cursor
  glm::dvec2 region_cursor_{0.0};  // the cursor at the drag's last move
  bool screenshot_requested_ = false;
  bool save_view_requested_ = false;
  RenderMode drawn_mode_ =
      RenderMode::Axis;          // the mode of the last frame, to clear a mode's error once another is chosen
  unsigned events_ = 0;          // input events seen, to keep drawing while something happens
  SliceSettings hidden_slices_;  // which slices I brings back
};

ViewerWindow::ViewerWindow(const ViewerOptions& o, std::unique_ptr<ViewerSession> session, RegionEditor regions,
                           GLFWwindow* window, std::chrono::steady_clock::time_point start, StartupTimes startup)
    : options_(o),
      window_(window),
      session_(std::move(session)),
      files_(session_->files()),
      regions_(std::move(regions)),
      selection_worker_(files_, session_->indexes()),
      detail_(session_->detail()),
      start_(start),
      startup_(startup),
      controller_(Camera{}, 1.0) {
  if (o.saved_show_regions) state_.show_regions = *o.saved_show_regions;  // as the saved view had them
  stats_.detail = describe_scene_detail(detail_, session_->levels_in_files());
  if (!stats_.detail.empty()) std::fprintf(stderr, "voxview: %s\n", stats_.detail.c_str());
  std::vector<std::uint64_t> segments(SceneLayout::coarsest_level(files_) + 1, 0);
  for (const VxlFile* f : files_)
    for (std::size_t i = 0; i < f->voxels().size(); ++i)
      for (std::uint32_t d = 0; d < segments.size(); ++d) segments[d] += f->level(i, d).segment_count;
  first_level_ = first_picture_level(segments, detail_.level);
  // The command line's selection first: its groups are those the options name.
  update_selection(true);
  // Scene-wide facts (bounds, groups, value sets, voxel cubes) are the same at every level.
  Renderer& first = renderer_at(first_level_);
  grid_.emplace(first);
  controller_ = CameraController(Camera{}, std::max(1.0, glm::length(first.scene_max() - first.scene_min()) * 0.5));
  stats_.has_image = session_->image() != nullptr;
  check_color_options(o.inputs_name(), first, o.settings, o.from_view_file);
  GLint major = 0, minor = 0;
  glGetIntegerv(GL_MAJOR_VERSION, &major);
  glGetIntegerv(GL_MINOR_VERSION, &minor);
  GLfloat widths[2] = {1, 1};
  glGetFloatv(GL_ALIASED_LINE_WIDTH_RANGE, widths);

  state_.settings = o.settings;
  drawn_mode_ = o.settings.mode;
  state_.orthographic = o.orthographic;
  stats_.title = std::filesystem::path(o.inputs.front()).filename().string();
  if (files_.size() > 1) stats_.title += " + " + std::to_string(files_.size() - 1) + " more";
  for (const VxlFile* f : files_) {
    stats_.voxels_total += f->meta().voxel_count;
    stats_.segments_total += f->meta().segment_count;
  }
  stats_.gl_renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  stats_.gl_version = std::to_string(major) + "." + std::to_string(minor);
  stats_.exact_available = major * 10 + minor >= 43;
  scheduler_.emplace(FrameBudget(o.frame_budget_ms, detail_.level, SceneLayout::coarsest_level(files_)),
                     RestRefinement(stats_.exact_available, o.exact_when_still), detail_.level, detail_.forced,
                     first_level_);
  state_.exact_when_still = o.exact_when_still;
  stats_.frame_budget_ms = o.frame_budget_ms;
  stats_.max_line_width = std::clamp(widths[1], 1.0f, 16.0f);
  stats_.value_sets = first.value_set_names();
  for (int c = 0; c < 3; ++c) {
    stats_.bounds_min[c] = first.bounds_min()[c];
    stats_.bounds_max[c] = first.bounds_max()[c];
  }
  if (o.settings.clipping.slab_mm > 0) state_.slab_thickness = o.settings.clipping.slab_mm;

  framing_points_ = framing_points(first.layout());
  controller_.set_home(home_camera(aspect(), o.orthographic));
  controller_.reset();

  glfwSetWindowUserPointer(window_, this);
  glfwSetMouseButtonCallback(window_, [](GLFWwindow* w, int b, int a, int m) { of(w).on_mouse_button(b, a, m); });
  glfwSetCursorPosCallback(window_, [](GLFWwindow* w, double x, double y) { of(w).on_cursor(x, y); });
  // Some systems turn Shift + wheel into a horizontal scroll: take whichever axis moved.
  glfwSetScrollCallback(window_, [](GLFWwindow* w, double dx, double dy) { of(w).on_scroll(dy != 0 ? dy : dx); });
  glfwSetKeyCallback(window_, [](GLFWwindow* w, int k, int, int a, int m) { of(w).on_key(k, a, m); });
  glfwSetCharCallback(window_, [](GLFWwindow* w, unsigned c) { of(w).on_char(c); });
  glfwSetFramebufferSizeCallback(window_, [](GLFWwindow* w, int, int) { of(w).events_++; });
  glfwSetWindowRefreshCallback(window_, [](GLFWwindow* w) { of(w).events_++; });
  panel_ = std::make_unique<UiPanel>(window_);
  startup_.viewer_ready_s = seconds_since_start();
}

double ViewerWindow::aspect() const {
  int w = 0, h = 0;
  glfwGetFramebufferSize(window_, &w, &h);
  return h > 0 && w > 0 ? double(w) / h : 1.0;
}

Camera ViewerWindow::home_camera(double aspect, bool orthographic) const {
  ViewerOptions o = options_;
  o.orthographic = orthographic;
  return initial_camera(framing_points_, o, aspect);
}

void ViewerWindow::reset_camera(double aspect) {
  // Re-frames for the current window shape; keeps the projection the user chose.
  controller_.set_home(home_camera(aspect, controller_.camera().orthographic));
  controller_.reset();
}

void ViewerWindow::set_error(const std::string& message) {
  if (stats_.error != message) std::fprintf(stderr, "voxview: %s\n", message.c_str());
  stats_.error = message;
}

void ViewerWindow::on_mouse_button(int button, int action, int mods) {
  events_++;
  if (action == GLFW_RELEASE) {
    if (button == drag_button_) {
      controller_.end_drag();
      drag_button_ = -1;
      dragging_region_ = false;
    }
    return;
  }
  // A drag that starts on the panel belongs to the panel; one that started on the scene keeps going over it.
  double x = 0, y = 0;
  glfwGetCursorPos(window_, &x, &y);
  if (drag_button_ != -1 || panel_->takes_mouse_at(x, y)) return;
  if (button == GLFW_MOUSE_BUTTON_LEFT && (mods & GLFW_MOD_CONTROL)) {
    begin_region_drag(x, y);
    return;
  }
  DragMode mode = DragMode::None;
  if (button == GLFW_MOUSE_BUTTON_LEFT) mode = (mods & GLFW_MOD_SHIFT) ? DragMode::Pan : DragMode::Orbit;
  if (button == GLFW_MOUSE_BUTTON_RIGHT || button == GLFW_MOUSE_BUTTON_MIDDLE) mode = DragMode::Pan;
  if (mode == DragMode::None) return;
  controller_.begin_drag(mode, x, y);
  drag_button_ = button;
}

void ViewerWindow::on_cursor(double x, double y) {
  events_++;
  if (dragging_region_) {
    int w = 0, h = 0;
    glfwGetWindowSize(window_, &w, &h);
    const std::optional<std::size_t> active = regions_.active();
    if (active && regions_.regions()[*active].centre) {
      const std::array<double, 3>& c = *regions_.regions()[*active].centre;
      const glm::dvec3 move =
          drag_in_view_plane(controller_.camera(), {c[0], c[1], c[2]}, region_cursor_, {x, y}, w, h);
      regions_.move_active_by({move.x, move.y, move.z});  // the selection follows (update_selection)
    }
    region_cursor_ = {x, y};
    return;
  }
  if (controller_.dragging() != DragMode::None) controller_.drag_to(x, y);
}

// Ctrl + left press: the sphere under the cursor becomes the active one (else the active one stays) and
// follows the cursor until the button is released.
void ViewerWindow::begin_region_drag(double x, double y) {
  std::vector<RegionShape> spheres;
  std::vector<std::size_t> index;  // the region of each sphere
  for (std::size_t i = 0; i < regions_.regions().size(); ++i) {
    const EditorRegion& r = regions_.regions()[i];
    if (!r.centre) continue;
    RegionShape s;
    s.centre = {(*r.centre)[0], (*r.centre)[1], (*r.centre)[2]};
    s.radius = r.radius;
    spheres.push_back(s);
    index.push_back(i);
  }
  int w = 0, h = 0;
  glfwGetWindowSize(window_, &w, &h);
  if (const auto hit = pick_sphere(pick_ray(controller_.camera(), x, y, w, h), spheres)) regions_.activate(index[*hit]);
  const std::optional<std::size_t> active = regions_.active();
  if (!active || !regions_.regions()[*active].centre) return;
  dragging_region_ = true;
  region_cursor_ = {x, y};
  drag_button_ = GLFW_MOUSE_BUTTON_LEFT;
}

void ViewerWindow::on_scroll(double steps) {
  events_++;
  double x = 0, y = 0;
  glfwGetCursorPos(window_, &x, &y);
  if (panel_->takes_mouse_at(x, y)) return;
  // Ctrl + wheel moves the slab through the scene (as in mrview), Shift + wheel changes the active region's
  // radius (Ctrl + wheel is taken by the slab); the plain wheel zooms.
  auto held = [&](int left, int right) {
    return glfwGetKey(window_, left) == GLFW_PRESS || glfwGetKey(window_, right) == GLFW_PRESS;
  };
  if (held(GLFW_KEY_LEFT_CONTROL, GLFW_KEY_RIGHT_CONTROL))
    controller_.move_focus(-steps);
  else if (held(GLFW_KEY_LEFT_SHIFT, GLFW_KEY_RIGHT_SHIFT) && !regions_.empty())
    regions_.scale_radius(std::pow(RegionEditor::kRadiusStep, steps));
  else
    controller_.zoom(steps);
}

// Clip plane i on or off; a missing one is added through the focus point, on axis i, keeping the + side.
void ViewerWindow::toggle_clip_plane(std::size_t i) {
  std::vector<AxisClip>& planes = state_.settings.clipping.planes;
  if (i < planes.size()) {
    planes[i].enabled = !planes[i].enabled;
    return;
  }
  if (planes.size() >= Clipping::kMaxPlanes) return;
  AxisClip p;
  p.axis = static_cast<int>(i);
  p.position = controller_.camera().target[p.axis];
  planes.push_back(p);
}

// Moves the focus point (where the slices cross) along a RAS axis; the view follows it.
void ViewerWindow::move_focus_along(int axis, double mm) {
  Camera c = controller_.camera();
  c.target[axis] += mm;
  controller_.set_camera(c);
  std::array<double, 3> offset{0, 0, 0};
  offset[axis] = mm;
  regions_.move_active_by(offset);  // the active sphere moves with the focus (a dragged one from where it is)
}

void ViewerWindow::update_selection(bool wait) {
  // The panel's list, every frame: which region is active changes without a new selection.
  stats_.regions.clear();
  for (std::size_t i = 0; i < regions_.regions().size(); ++i) {
    const EditorRegion& r = regions_.regions()[i];
    stats_.regions.push_back(
        {r.role_name(), r.argument(), r.streamlines, r.centre.has_value(), regions_.active() == i, r.radius});
  }
  if (selection_revision_ != regions_.revision()) {
    selection_revision_ = regions_.revision();
    if (regions_.empty()) {
      cleared_revision_ = regions_.revision();
      if (selection_) apply_selection(std::nullopt);
    } else {
      try {
        selection_worker_.request(regions_.revision(), regions_.criteria());
      } catch (const std::exception& e) {  // a region that does not parse: said, and no selection
        set_error(e.what());
        if (selection_) apply_selection(std::nullopt);
      }
    }
  }
  std::optional<SelectionWorker::Done> done = selection_worker_.poll(wait);
  if (!done || (cleared_revision_ && done->revision <= *cleared_revision_)) return;
  if (!done->error.empty()) {
    set_error(done->error);
    apply_selection(std::nullopt);
    return;
  }
  selection_ms_.push_back(done->ms);
  // Counts only for the regions they were computed with: the list may have changed since.
  if (done->revision == regions_.revision()) regions_.set_counts(done->selection->streamlines_per_region);
  stats_.selection = std::to_string(done->selection->selected) + " of " + std::to_string(done->selection->total) +
                     " streamlines selected (" + std::to_string(int(done->ms + 0.5)) + " ms)";
  RenderSettings& s = state_.settings;
  // Regions added in the window to a scene started without: the context faint, as --context-opacity's default.
  if (s.find_style(SceneGroups::kContext) == nullptr)
    s.style_of(SceneGroups::kContext).opacity = std::min(1.0f, 0.02f / s.opacity);
  apply_selection(std::move(done->selection));
}

void ViewerWindow::apply_selection(std::optional<SceneSelection> selection) {
  selection_ = std::move(selection);
  if (!selection_) stats_.selection.clear();
  ++selection_generation_;
  session_->set_groups(selection_ ? std::optional<SceneGroups>(selection_->groups) : std::nullopt);
  const SceneGroups groups = selection_ ? selection_->groups : SceneGroups(files_);
  stats_.groups.clear();
  for (const SceneGroup& g : groups.groups()) stats_.groups.emplace_back(g.name, g.streamlines);
  for (std::size_t i = 0; i < stats_.regions.size(); ++i)
    stats_.regions[i].streamlines = regions_.regions()[i].streamlines;
}

void ViewerWindow::save_selection() {
  if (!selection_) {
    set_error("no selection to save: add a region first (G)");
    return;
  }
  for (std::size_t i = 0; i < files_.size(); ++i) {
    const std::string path =
        stamped_name("voxview-selection-", files_.size() > 1 ? "-" + std::to_string(i) + ".tck" : ".tck").string();
    try {
      write_selection(*files_[i], StreamlineSubset(files_[i]->meta().streamline_count, selection_->kept[i]), path, {},
                      {});
      stats_.status = "selection saved to " + path;
      std::printf("voxview: %zu streamlines saved to %s\n", selection_->kept[i].size(), path.c_str());
      std::fflush(stdout);
    } catch (const std::exception& e) {
      set_error(e.what());
    }
  }
}

void ViewerWindow::on_key(int key, int action, int mods) {
  events_++;
  if ((action != GLFW_PRESS && action != GLFW_REPEAT) || panel_->wants_keyboard()) return;
  const bool shift = mods & GLFW_MOD_SHIFT;
  if (const auto a = action_for_key(key, shift, action == GLFW_REPEAT)) perform(*a, shift);
}

void ViewerWindow::on_char(unsigned c) {
  events_++;
  if (panel_->wants_keyboard()) return;
  if (const auto a = action_for_char(c)) perform(*a, false);
}

// I hides the slices shown, and brings back those it hid (or the default ones).
void ViewerWindow::toggle_slices() {
  SliceSettings& slices = state_.settings.slices;
  if (slices.any()) {
    hidden_slices_ = slices;
    slices.axial = slices.coronal = slices.sagittal = slices.view_plane = false;
  } else {
    const auto range = slices.range;  // the grey range may have changed in the panel meanwhile
    slices = hidden_slices_.any() ? hidden_slices_ : SliceSettings{};
    slices.range = range;
  }
}

void ViewerWindow::perform(KeyAction action, bool shift) {
  RenderSettings& s = state_.settings;
  const double step = shift ? 10.0 : 1.0;
  auto view = [&](const char* name) {
    const auto v = parse_view(name);
    controller_.set_view((*v)[0], (*v)[1]);
  };
  auto slab_thickness = [&](double factor) {
    state_.slab_thickness = std::clamp(state_.slab_thickness * factor, 0.1, 1000.0);
    if (s.clipping.slab_mm > 0) s.clipping.slab_mm = state_.slab_thickness;
  };
  switch (action) {
    case KeyAction::ViewAxial: view("axial"); break;
    case KeyAction::ViewSagittal: view("sagittal"); break;
    case KeyAction::ViewCoronal: view("coronal"); break;
    case KeyAction::ViewInferior: view("inferior"); break;
    case KeyAction::ViewRight: view("right"); break;
    case KeyAction::ViewPosterior: view("posterior"); break;
    case KeyAction::ToggleOrthographic: controller_.set_orthographic(!controller_.camera().orthographic); break;
    case KeyAction::NextMode: s.mode = next_mode(s.mode, stats_.exact_available); break;
    case KeyAction::OpacityUp: s.opacity = std::clamp(s.opacity * 1.5f, 0.001f, 1.0f); break;
    case KeyAction::OpacityDown: s.opacity = std::clamp(s.opacity / 1.5f, 0.001f, 1.0f); break;
    case KeyAction::ToggleLighting: s.lighting = !s.lighting; break;
    case KeyAction::ToggleExactWhenStill: state_.exact_when_still = !state_.exact_when_still; break;
    case KeyAction::Screenshot: screenshot_requested_ = true; break;
    case KeyAction::ResetCamera: reset_camera(aspect()); break;
    case KeyAction::SaveView: save_view_requested_ = true; break;
    case KeyAction::ToggleSlab: s.clipping.slab_mm = s.clipping.slab_mm > 0 ? 0.0 : state_.slab_thickness; break;
    case KeyAction::SlabThinner: slab_thickness(0.8); break;
    case KeyAction::SlabThicker: slab_thickness(1.25); break;
    case KeyAction::SlabNearer: controller_.move_focus(-step); break;
    case KeyAction::SlabFarther: controller_.move_focus(step); break;
    case KeyAction::ToggleClip1: toggle_clip_plane(0); break;
    case KeyAction::ToggleClip2: toggle_clip_plane(1); break;
    case KeyAction::ToggleClip3: toggle_clip_plane(2); break;
    case KeyAction::FocusSuperior: move_focus_along(2, step); break;
    case KeyAction::FocusInferior: move_focus_along(2, -step); break;
    case KeyAction::FocusRight: move_focus_along(0, step); break;
    case KeyAction::FocusLeft: move_focus_along(0, -step); break;
    case KeyAction::FocusAnterior: move_focus_along(1, step); break;
    case KeyAction::FocusPosterior: move_focus_along(1, -step); break;
    case KeyAction::ToggleSlices: toggle_slices(); break;
    case KeyAction::AddRegion: {
      const glm::dvec3 f = controller_.camera().target;
      regions_.add_sphere({f.x, f.y, f.z});
      break;
    }
    case KeyAction::RemoveRegion: regions_.remove_active(); break;
    case KeyAction::NextRegion: regions_.activate_next(); break;
    case KeyAction::ToggleRegionRole: regions_.toggle_role(); break;
    case KeyAction::ToggleRegionShells: state_.show_regions = !state_.show_regions; break;
    case KeyAction::RegionSmaller: regions_.scale_radius(1 / RegionEditor::kRadiusStep); break;
    case KeyAction::RegionLarger: regions_.scale_radius(RegionEditor::kRadiusStep); break;
    case KeyAction::SaveSelection: save_selection(); break;
    case KeyAction::TogglePanel: state_.panel_collapsed = !state_.panel_collapsed; break;
    case KeyAction::Quit: glfwSetWindowShouldClose(window_, GLFW_TRUE); break;
  }
}

Renderer& ViewerWindow::renderer_at(std::uint32_t level) {
  // The first picture's level is uploaded whole at once; the others span by span as frames need them
  // (the refinement at rest spreads its level's upload over frames).
  return session_->renderer_at(level, level == first_level_);
}

double ViewerWindow::draw_scene(int width, int height, std::uint32_t level) {
  Renderer& renderer = renderer_at(level);
  RenderSettings& s = state_.settings;
  if (s.mode != drawn_mode_) stats_.error.clear();  // a new choice of mode gets a fresh start
  if (render_mode_info(s.mode).needs_gl43 && !stats_.exact_available) {
    set_error(std::string("the ") + render_mode_name(s.mode) + " mode needs OpenGL 4.3; this context is " +
              stats_.gl_version + ": showing axis");
    s.mode = RenderMode::Axis;
  }
  const auto t0 = std::chrono::steady_clock::now();
  const Camera& camera = controller_.camera();
  if (!scene_target_) scene_target_.emplace(width, height);
  if (scene_target_->width() != width || scene_target_->height() != height) scene_target_->resize(width, height);
  scheduler_->abandon_pieces();  // a whole picture abandons the refinement's pieces
  const GLuint target = scene_target_->framebuffer();
  try {
    renderer.draw(camera, s, width, height, target);
  } catch (const std::exception& e) {
    // A mode that cannot run here (e.g. exact out of node memory): say so and keep showing something.
    set_error(std::string(render_mode_name(s.mode)) + ": " + e.what() + ": showing axis");
    s.mode = RenderMode::Axis;
    renderer.draw(camera, s, width, height, target);
  }
  drawn_mode_ = s.mode;
  draw_overlays(renderer, width, height);
  glFinish();  // the frame time should include the GPU's work, not only its submission
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  stats_.frame_ms = stats_.frame_ms == 0 ? ms : 0.9 * stats_.frame_ms + 0.1 * ms;
  show_frame_figures(renderer, level);
  return ms;
}

void ViewerWindow::draw_overlays(const Renderer& renderer, int width, int height) {
  scene_target_->bind();
  const RenderSettings& s = state_.settings;
  if (state_.grid) {
    const glm::vec4 colour =
        background_is_light(s.background()) ? glm::vec4(0.1f, 0.1f, 0.1f, 0.25f) : glm::vec4(0.8f, 0.8f, 0.8f, 0.25f);
    grid_->draw(renderer, controller_.camera(), double(width) / height,
                state_.grid_all ? GridOverlay::Scope::All : GridOverlay::Scope::Drawn, colour, s.clipping);
    stats_.grid_cubes = grid_->cubes_drawn();
  }
  // Over the grid too: the letters and the colour bar stay readable.
  if (PictureAnnotations::wanted(s)) {
    if (!annotations_) annotations_.emplace();
    annotations_->draw(controller_.camera(), s, renderer, width, height);
  }
}

void ViewerWindow::show_frame_figures(const Renderer& renderer, std::uint32_t level) {
  const RenderSettings& s = state_.settings;
  const FrameStats& f = renderer.stats();
  stats_.scalar_range = renderer.scalar_range(s);
  stats_.image_range = renderer.slice_range(s);
  for (int a = 0; a < 3; ++a) stats_.focus[a] = controller_.camera().target[a];
  stats_.plan_ms = f.plan_ms;
  stats_.voxels_drawn = f.voxels_drawn;
  stats_.segments_drawn = f.segments_drawn;
  stats_.frame_level = level > detail_.level ? "level " + std::to_string(level) + " while the camera moves"
                       : level < detail_.level
                           ? "level " + std::to_string(level) + ": the visible part fits the GPU memory budget"
                           : "";
}

void ViewerWindow::present(int width, int height) const {
  glBindFramebuffer(GL_READ_FRAMEBUFFER, scene_target_->framebuffer());
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
  glBlitFramebuffer(0, 0, width, height, 0, 0, width, height, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

double ViewerWindow::refine(int width, int height, std::uint32_t level, bool& completes) {
  const auto t0 = std::chrono::steady_clock::now();
  Renderer& renderer = renderer_at(level);
  if (!refine_target_) refine_target_.emplace(width, height);
  if (refine_target_->width() != width || refine_target_->height() != height) refine_target_->resize(width, height);
  RestRefinement& rest = scheduler_->rest();
  const bool exact_stage = rest.stage() == RestStage::Exact;
  completes = false;
  try {
    // Each piece fits the frame budget, so that input waits no longer at rest than while moving.
    const double piece_ms =
        options_.frame_budget_ms > 0 ? options_.frame_budget_ms : std::numeric_limits<double>::infinity();
    if (!scheduler_->pieces_begun()) {
      // The level's spans this view needs come first, a piece's time at a time (the nearest first).
      if (!renderer.upload_for(controller_.camera(), double(width) / height, state_.settings.clipping, piece_ms)) {
        stats_.refinement = "uploading the scene's level";
        glFinish();
        return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      }
      RenderSettings s = state_.settings;
      s.mode = rest.stage_mode();
      renderer.begin_pieces(controller_.camera(), s, width, height, refine_target_->framebuffer());
      scheduler_->begin_pieces();
    }
    completes = renderer.draw_piece(piece_ms);
  } catch (const std::exception& e) {
    // Exact out of node memory, say: keep the picture on screen and stop refining it.
    set_error(std::string(exact_stage ? "exact when still" : render_mode_name(rest.stage_mode())) + ": " + e.what() +
              (exact_stage ? ": turned off" : ": showing axis"));
    if (exact_stage) {
      state_.exact_when_still = false;
      scheduler_->set_exact_when_still(false);
    } else {
      state_.settings.mode = RenderMode::Axis;  // as draw_scene does: the picture is drawn again in axis
    }
    scheduler_->abandon_pieces();
    stats_.refinement = rest.describe(0);
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  }
  if (completes) {
    std::swap(scene_target_, refine_target_);
    draw_overlays(renderer, width, height);
    show_frame_figures(renderer, level);
  }
  scheduler_->piece_drawn(completes);
  stats_.refinement = rest.describe(completes ? 0 : renderer.pieces_progress());
  glFinish();
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

void ViewerWindow::save_screenshot(const std::string& path, int width, int height) {
  const Image picture = read_back_buffer(width, height);
  write_picture(path, picture.width, picture.height, picture.rgba);
  stats_.status = "saved " + path;
  std::printf("voxview: screenshot %dx%d saved to %s\n", width, height, path.c_str());
  std::fflush(stdout);
}

void ViewerWindow::save_view(int width, int height) {
  const std::string path = options_.save_camera.value_or(stamped_name("voxview-view-", ".json").string());
  try {
    SavedView view{controller_.camera(), state_.settings, std::array<int, 2>{width, height}, true, {}, {}, {},
                   state_.show_regions};
    // Without regions the focus and context groups are gone: a view naming them would not replay.
    if (regions_.empty())
      std::erase_if(view.settings.group_styles, [](const GroupStyle& g) {
        return g.name == SceneGroups::kSelected || g.name == SceneGroups::kContext;
      });
    for (const EditorRegion& r : regions_.regions())
      (r.role == EditorRegion::Role::Include   ? view.include
       : r.role == EditorRegion::Role::Exclude ? view.exclude
                                               : view.ends_in)
          .push_back(r.argument());
    write_view(path, view);
    stats_.status = "view saved to " + path;
    std::printf("voxview: view saved to %s (replay: voxview FILE --camera '%s' --render OUT.png)\n", path.c_str(),
                path.c_str());
    std::fflush(stdout);
  } catch (const std::exception& e) {
    set_error(e.what());
  }
}

int ViewerWindow::run() {
  const bool automated = options_.frames.has_value();
  FramePacing pacing;
  for (long frame = 1;; ++frame) {
    const unsigned seen = events_;
    if (automated || !pacing.may_wait()) {
      glfwPollEvents();
    } else {
      glfwWaitEvents();  // nothing moves by itself: sleep until the user does something
    }
    pacing.frame_started(events_ != seen);
    // A script's frames are done after --frames; with --until-refined it then waits, at rest, for the
    // refinement to finish.
    const bool frames_done = automated && frame >= *options_.frames;
    const bool refined = drawn_ && scheduler_->rest().stage() == RestStage::Done;
    const bool closing = glfwWindowShouldClose(window_) || (frames_done && (!options_.until_refined || refined));

    // Render at the framebuffer's size (HiDPI), take input in window units.
    int fb_w = 0, fb_h = 0, win_h = 0;
    glfwGetFramebufferSize(window_, &fb_w, &fb_h);
    glfwGetWindowSize(window_, nullptr, &win_h);
    if (fb_w <= 0 || fb_h <= 0) {  // minimised
      if (closing) break;
      continue;
    }
    controller_.set_window_height(win_h);

    state_.orthographic = controller_.camera().orthographic;
    const PanelRequests requests = panel_->build(state_, stats_);
    controller_.set_orthographic(state_.orthographic);
    if (requests.view) controller_.set_view((*requests.view)[0], (*requests.view)[1]);
    if (requests.reset_camera) reset_camera(double(fb_w) / fb_h);
    if (requests.move_focus != 0) controller_.move_focus(requests.move_focus);
    if (requests.focus)
      for (int a = 0; a < 3; ++a) move_focus_along(a, (*requests.focus)[a] - controller_.camera().target[a]);
    if (requests.add_region) perform(KeyAction::AddRegion, false);
    if (requests.activate_region) regions_.activate(*requests.activate_region);
    if (requests.region_radius) regions_.set_radius(*requests.region_radius);
    if (requests.toggle_region) regions_.toggle_role();
    if (requests.remove_region) regions_.remove_active();
    if (requests.save_selection) save_selection();
    screenshot_requested_ |= requests.screenshot;
    save_view_requested_ |= requests.save_view;
    scheduler_->set_exact_when_still(state_.exact_when_still);
    if (options_.orbit_deg && !frames_done)
      controller_.set_view(controller_.camera().azimuth_deg + *options_.orbit_deg, controller_.camera().elevation_deg);

    // A changed picture is drawn whole: the first at a coarse level (at once); while the camera moves or a
    // setting changes, at the finest level that fits the frame budget; a script's last frame at the scene's
    // level. An unchanged one is refined at rest, a piece a frame (rest_refinement.h).
    const Camera& camera = controller_.camera();
    // A scripted drag moves the active region every frame, as a mouse would.
    const bool dragging = options_.drag_region_mm && !frames_done && regions_.active();
    if (dragging) regions_.move_active_by(*options_.drag_region_mm);
    // A script's window (--frames) waits for each selection, so that what it draws does not depend on timing;
    // a scripted drag does not, as a user's drag does not.
    update_selection(automated && !options_.drag_region_mm);
    state_.settings.regions = state_.show_regions ? regions_.shapes() : std::vector<RegionShape>{};
    const PictureKey key{camera, state_.settings, fb_w, fb_h, state_.grid, state_.grid_all, selection_generation_};
    const bool moving = drawn_ && !closing && (!same_view(drawn_->camera, camera) || dragging);
    const bool changed = !drawn_ || !same_picture(*drawn_, key);
    const bool scripted_last = closing && frames_done && !options_.until_refined;
    bool drawn_now = false;  // the picture (and so what the panel should say) changed after the panel was built
    const PictureTask task = scheduler_->next(changed, scripted_last, closing, [&] {
      return session_->level_for_view(camera, double(fb_w) / fb_h, state_.settings.clipping);
    });
    if (task.stage_skipped) stats_.refinement = scheduler_->rest().describe(0);
    if (task.work == PictureWork::Whole) {
      const double ms = draw_scene(fb_w, fb_h, task.level);
      scheduler_->drawn_whole(state_.settings.mode, task.level, ms);
      stats_.refinement = scheduler_->rest().describe(0);
      drawn_ = key;
      frames_.push_back({task.level, moving, ms, seconds_since_start()});
      drawn_now = true;
    } else if (task.work == PictureWork::Piece) {
      bool completes = false;
      const double ms = refine(fb_w, fb_h, task.level, completes);
      frames_.push_back({task.level, false, ms, seconds_since_start(), task.frame_work, completes});
      drawn_now = true;
    }
    pacing.frame_ended(scheduler_->rest().stage() != RestStage::Done, drawn_now);
    present(fb_w, fb_h);
    // Screenshots show the scene alone unless the user asked for the panel too; automated ones never do.
    if (closing && options_.screenshot) save_screenshot(*options_.screenshot, fb_w, fb_h);
    // The view of the frame just drawn; scripts get it on quitting after --frames.
    if (save_view_requested_ || (closing && automated && options_.save_camera)) save_view(fb_w, fb_h);
    save_view_requested_ = false;
    if (screenshot_requested_ && !state_.panel_in_screenshot) {
      try {
        save_screenshot(stamped_name("voxview-", ".png").string(), fb_w, fb_h);
      } catch (const std::exception& e) {
        set_error(e.what());
      }
    }
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glViewport(0, 0, fb_w, fb_h);
    panel_->render();
    if (screenshot_requested_ && state_.panel_in_screenshot) {
      try {
        save_screenshot(stamped_name("voxview-", ".png").string(), fb_w, fb_h);
      } catch (const std::exception& e) {
        set_error(e.what());
      }
    }
    screenshot_requested_ = false;
    glfwSwapBuffers(window_);
    if (startup_.first_on_screen_s < 0 && !frames_.empty()) {
      glFinish();  // the swap has been carried out, not only queued
      startup_.first_on_screen_s = seconds_since_start();
    }
    if (closing) break;
  }
  if (options_.stats_json)
    write_frame_stats(*options_.stats_json, frames_, detail_.level, options_.frame_budget_ms, startup_, selection_ms_);
  return 0;
}

}  // namespace

int run_window(const ViewerOptions& o) {
  const auto start = process_start();
  GlfwLibrary glfw;                                   // first: without a display, fail before any slow conversion
  auto session = std::make_unique<ViewerSession>(o);  // a bad file or image fails before the window opens
  RegionEditor regions(o);                            // parses the regions: a bad one fails there too
  WindowPtr window = open_window(o);
  StartupTimes startup;
  startup.window_open_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  session->choose_detail(o);  // the driver's limits: the window's context is current
  ViewerWindow viewer(o, std::move(session), std::move(regions), window.get(), start, startup);
  return viewer.run();
}

}  // namespace vxl::app
