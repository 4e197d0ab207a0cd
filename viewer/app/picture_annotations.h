// What voxview draws over a picture besides the lines, when asked (RenderSettings::orientation_labels,
// ::colorbar): the anatomical directions at the picture's edges (L/R, P/A, I/S: the world is RAS mm), a small
// axes triad in the lower left corner (x red, y green, z blue, each tip lettered R, A, S), and for
// ColorMode::Scalar a colour bar at the right edge (the colour map from the range's minimum at the bottom to
// its maximum at the top, both numbers and the value set's name).
//
// Text and shapes go through Dear ImGui's draw lists and its OpenGL 3 backend, with a Dear ImGui context of
// this class's own (the window's panel keeps its own): ImGui needs only a current GL context, so headless
// pictures and the window draw the same annotations the same way.
#pragma once

#include <array>

#include "viewer/render/camera.h"
#include "viewer/render/render_settings.h"

struct ImGuiContext;
struct ImFont;

namespace vxl {
class Renderer;
}

namespace vxl::app {

// The letter of the anatomical direction a world direction points to most: R/L (+x/-x), A/P (+y/-y),
// S/I (+z/-z).
char anatomical_letter(const glm::dvec3& direction);

// The letters at the middles of the picture's edges: for each screen direction, the world axis most aligned
// with it (in perspective, the view's centre).
struct EdgeLetters {
  char right, left, top, bottom;
};
EdgeLetters edge_letters(const Camera& camera);

// A box in pixels from the picture's top-left corner (x0, y0 inclusive; x1, y1 exclusive).
struct PixelBox {
  float x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};

// Where the last draw() put things: what the tests check pixels against.
struct AnnotationLayout {
  float text_px = 0;
  std::array<PixelBox, 4> edge_labels;  // right, left, top, bottom; empty without orientation labels
  PixelBox triad;                       // the triad's lines and letters; empty without orientation labels
  PixelBox colorbar;                    // the gradient alone; empty without a colour bar
  PixelBox colorbar_texts;              // the bar's frame, numbers and name
};

class PictureAnnotations {
 public:
  // Needs a current OpenGL 3.3 core context, as the renderer does; destroy it with that context current.
  PictureAnnotations();
  ~PictureAnnotations();
  PictureAnnotations(const PictureAnnotations&) = delete;
  PictureAnnotations& operator=(const PictureAnnotations&) = delete;

  // Whether `settings` ask for anything over the picture.
  static bool wanted(const RenderSettings& settings);
  // Draws into the bound framebuffer, a picture of width x height seen by `camera`; `renderer` names the value
  // set and range the lines are coloured by. Leaves the current ImGui context (the window's panel) as it was.
  void draw(const Camera& camera, const RenderSettings& settings, const Renderer& renderer, int width, int height);
  const AnnotationLayout& layout() const { return layout_; }

 private:
  ImGuiContext* context_ = nullptr;
  std::array<ImFont*, 4> fonts_{};  // the built-in font at 13, 26, 39 and 52 pixels: crisp at each
  AnnotationLayout layout_;
};

}  // namespace vxl::app
