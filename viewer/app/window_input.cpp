// The window's input: mouse drags and the wheel on the scene, keys and what they do (key_bindings.h).
#include <algorithm>
#include <cmath>

#include "viewer/app/region_drag.h"
#include "viewer/app/viewer_window.h"

namespace vxl::app {

namespace {

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

}  // namespace

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

}  // namespace vxl::app
