// Turns mouse and wheel input into camera changes: orbit (turntable: azimuth about +Z, elevation clamped
// to ±90°), zoom and pan. Pure logic — positions are window (input) pixels, y down, as GLFW reports them —
// so that it can be unit-tested without a window.
//
// Directions, chosen so that the scene follows the cursor:
//   orbit drag right  -> azimuth increases (the eye moves towards screen left, the scene turns right);
//   orbit drag down   -> elevation increases (the eye rises, the top of the scene tips towards the viewer);
//   pan               -> the target moves in the screen plane so that the point under the cursor stays there;
//   wheel up (+steps) -> zoom in: smaller distance (perspective) or ortho_height (orthographic).
#pragma once

#include "viewer/render/camera.h"

namespace vxl::app {

enum class DragMode { None, Orbit, Pan };

class CameraController {
 public:
  static constexpr double kDegreesPerPixel = 0.4;
  static constexpr double kZoomPerStep = 1.15;  // one wheel notch

  // `scene_radius` (mm) bounds the zoom, so that the wheel can neither pass through the target nor lose
  // the scene far away.
  CameraController(const Camera& home, double scene_radius);

  const Camera& camera() const { return camera_; }
  void set_camera(const Camera& camera) { camera_ = camera; }
  void set_home(const Camera& home) { home_ = home; }
  void reset() { camera_ = home_; }

  // Window height in input pixels (glfwGetWindowSize), for the pan scale: the projections fix the vertical
  // field, so the height alone sets how many mm a pixel spans.
  void set_window_height(int height) { window_height_ = height > 0 ? height : 1; }

  void begin_drag(DragMode mode, double x, double y);
  void drag_to(double x, double y);
  void end_drag() { drag_ = DragMode::None; }
  DragMode dragging() const { return drag_; }

  void zoom(double steps);
  // Moves the focus point (the target, where a slab is centred) along the view direction; + is away
  // from the viewer. The eye moves with it, so the picture's scale stays.
  void move_focus(double mm) { camera_.target += camera_.forward() * mm; }
  void set_view(double azimuth_deg, double elevation_deg);
  // Keeps the picture's scale at the target when switching projection.
  void set_orthographic(bool orthographic);

  // Millimetres at the target per window pixel (what a pan of one pixel moves the target by).
  double mm_per_pixel() const;

 private:
  Camera camera_, home_;
  double min_extent_, max_extent_;
  int window_height_ = 1;
  DragMode drag_ = DragMode::None;
  double last_x_ = 0, last_y_ = 0;
};

}  // namespace vxl::app
