#include "viewer/render/modes/blend_states.h"

#include "viewer/render/gl_util.h"

namespace vxl {

void over_blending() {
  glEnable(GL_BLEND);
  // Premultiply colour, accumulate coverage: destination alpha reaches 1 (docs/rendering.md, pitfall 1).
  glBlendFuncSeparate(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
}

void opaque_blending() {
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  // The colour replaces, the alpha stays the clear's 1: an opaque picture (a PNG would otherwise keep the
  // lines' opacity as their alpha).
  glEnable(GL_BLEND);
  glBlendFuncSeparate(GL_ONE, GL_ZERO, GL_ZERO, GL_ONE);
}

}  // namespace vxl
