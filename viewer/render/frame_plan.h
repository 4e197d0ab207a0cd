// The per-frame CPU work of the Voxlines method: drop voxels outside the view frustum (and outside the
// slab and clip planes), sort the visible
// voxels back to front, pick each voxel's nearest precomputed order (the paper's rule), and fill the
// first/count arrays of the multi-draws (LinePass::draw_plan). No GL here.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "viewer/render/scene_layout.h"

namespace vxl {

struct ViewParams {
  glm::dvec3 eye;
  glm::dvec3 forward;  // unit view direction (used for orthographic sorting)
  bool orthographic = false;
  std::array<glm::dvec4, 6> planes;  // frustum planes in camera-relative coordinates (p - eye), inside >= 0
  std::vector<glm::dvec4> clip;      // slab and clip half-spaces, camera-relative likewise (clip_planes.h)
};

// Frustum planes from a projection matrix and the world->eye rotation (Gribb & Hartmann).
ViewParams make_view_params(const glm::dvec3& eye, const glm::dvec3& forward, bool orthographic,
                            const glm::dmat4& projection, const glm::dmat3& rotation);

enum class PlanOrder {
  Nearest,  // sorted voxels, nearest stored order (axis)
  Block,    // sorted voxels, dataset order inside each voxel (basic)
  Any,      // visible voxels in table order (order-independent modes)
  // Sorted voxels in a visibility order of their grid, dataset order inside each voxel (exact). Sorting
  // by the distance to the eye is not one: with perspective, a voxel can be nearer to the eye than a
  // neighbour it lies behind. The L1 distance between the eye and the voxel centres is: across every
  // face of a grid of equal cubes it grows away from the eye (or ties, when the eye is in the face's
  // plane), so no voxel comes after one it hides, and drawing them in this order is exact in depth for
  // one grid (Max-Williams-Silva's argument for convex meshes without visibility cycles).
  Visibility,
};

struct FramePlan {
  std::vector<std::int64_t> first;  // virtual ids (scene_layout.h): the scene's may pass 2^31
  std::vector<std::int32_t> count;
  std::vector<std::uint32_t> voxels;  // the scene voxel each first/count range draws
  std::uint64_t voxels_drawn = 0;
  std::uint64_t segments_drawn = 0;

  // Order hysteresis for PlanOrder::Nearest (off when <= 0). A voxel keeps the order it had in the
  // previous Nearest frame unless the nearest order is closer to its view direction by more than this
  // margin (a difference of cosines). Meant against the jitter of voxels whose view direction hovers at
  // the boundary between two stored directions (paper, "Different sorting orders").
  double order_hysteresis = 0;
  // Per voxel: 2 * slot + reversed of its last Nearest order, kNoOrder when unknown. Kept only while the
  // hysteresis is on; a Nearest frame without it forgets them.
  static constexpr std::uint8_t kNoOrder = 0xFF;
  std::vector<std::uint8_t> previous_order;

  // scratch, kept between frames to avoid allocation
  std::vector<std::pair<double, std::uint32_t>> sort_keys;  // double: tiny voxels far from the origin
};

void plan_frame(const SceneLayout& layout, const ViewParams& view, PlanOrder order, FramePlan& plan);

// The paper's rule: for a voxel centre v and eye c, the stored direction d (or its reverse) that is
// closest to the back-to-front direction w = (v - c) / |v - c|. Returns {slot, reversed}.
std::pair<std::uint32_t, bool> nearest_order(std::span<const glm::vec3> directions, const glm::dvec3& view_dir);

// How close stored order {slot, reversed} is to view direction w: the cosine between the direction it
// serves and w (nearest_order maximises it).
double order_alignment(std::span<const glm::vec3> directions, std::uint32_t slot, bool reversed,
                       const glm::dvec3& view_dir);

}  // namespace vxl
