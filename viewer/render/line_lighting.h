// Lighting for lines: the illuminated-lines model (Zöckler, Stalling & Hege, "Interactive visualization of
// 3D-vector fields using illuminated stream lines", 1996). A line has no normal, only a tangent T; of all
// normals perpendicular to T the one in the plane of T and the light L gives the largest diffuse and
// specular terms:
//
//   diffuse  = sqrt(1 - (L.T)^2)
//   specular = max(0, sqrt(1 - (L.T)^2) sqrt(1 - (V.T)^2) - (L.T)(V.T))^shininess
//   colour   = base * (ambient + k_diffuse * diffuse) + k_specular * specular
//
// so a line along the light is dark and a line across it is bright, whatever way round it runs (T and -T
// light the same). The light is fixed to the camera, above and to the left of the viewer, so that lines
// pointing at the viewer are lit as well as lines across the screen and the picture stays lit as it turns.
// The shader (line_shaders.cpp) evaluates the same formula per vertex; this file is its reference.
#pragma once

#include <glm/glm.hpp>

namespace vxl::lighting {

inline constexpr float kAmbient = 0.3f;
inline constexpr float kDiffuse = 0.7f;
inline constexpr float kSpecular = 0.4f;
inline constexpr float kShininess = 24.0f;

// Unit vector towards the light in eye space (x right, y up, z towards the viewer).
glm::vec3 light_direction_eye();

// The lit colour of a line with unit tangent `t`, seen along unit `v` (towards the eye), both eye space.
glm::vec3 lit_colour(const glm::vec3& base, const glm::vec3& t, const glm::vec3& v);

}  // namespace vxl::lighting
