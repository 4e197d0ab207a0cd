// The selection's regions as the renderer shows them: faint translucent shells (spheres and boxes; a mask
// has no shape to draw), one colour per role, the active region brighter. Plain data and the shell's
// colour rules, no GL: region_shells.h draws them, the tests compute expected pixels from the same rules.
#pragma once

#include <glm/glm.hpp>

namespace vxl {

struct RegionShape {
  enum class Kind { Sphere, Box };
  enum class Role { Include, Exclude, EndsIn };
  Kind kind = Kind::Sphere;
  Role role = Role::Include;
  glm::dvec3 centre{0.0};  // sphere
  double radius = 0;
  glm::dvec3 lo{0.0}, hi{0.0};  // box corners
  bool active = false;
  bool operator==(const RegionShape&) const = default;
};

// Which half of a shell a pass draws: the one facing away from the viewer (drawn under the lines) or the
// one facing it (drawn over them), so that lines inside a region show between the two.
enum class ShellHalf { Back, Front };

// The shell's colour for its role: include green, exclude red, ends-in blue.
glm::vec3 region_shell_color(RegionShape::Role role);

// The shell's opacity where its surface normal makes an angle with cosine `facing` (0..1, 1: straight at
// the viewer) with the view direction: fainter face-on and denser at the rim, so that a sphere reads as a
// shell; the active region about twice as dense as the others.
float region_shell_alpha(float facing, bool active);

}  // namespace vxl
