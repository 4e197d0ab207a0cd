#include "viewer/render/frame_plan.h"

#include <algorithm>
#include <cmath>
#include <tuple>

namespace vxl {

ViewParams make_view_params(const glm::dvec3& eye, const glm::dvec3& forward, bool orthographic,
                            const glm::dmat4& projection, const glm::dmat3& rotation) {
  ViewParams v;
  v.eye = eye;
  v.forward = forward;
  v.orthographic = orthographic;
  glm::dmat4 m = projection * glm::dmat4(rotation);  // camera-relative position -> clip space
  auto row = [&](int r) { return glm::dvec4(m[0][r], m[1][r], m[2][r], m[3][r]); };
  v.planes = {row(3) + row(0), row(3) - row(0), row(3) + row(1), row(3) - row(1), row(3) + row(2), row(3) - row(2)};
  return v;
}

std::pair<std::uint32_t, bool> nearest_order(std::span<const glm::vec3> directions, const glm::dvec3& w) {
  // Order k drawn forwards is back to front for an eye looking along -d_k; reversed, along +d_k. We want
  // the signed direction s maximising s . (-w): |d_k . w| largest, reversed when d_k . w > 0.
  std::uint32_t best = 0;
  double best_abs = -1, best_dot = 0;
  for (std::uint32_t k = 0; k < directions.size(); ++k) {
    double d = directions[k].x * w.x + directions[k].y * w.y + directions[k].z * w.z;
    if (std::abs(d) > best_abs) {
      best_abs = std::abs(d);
      best_dot = d;
      best = k;
    }
  }
  return {best, best_dot > 0};
}

double order_alignment(std::span<const glm::vec3> directions, std::uint32_t slot, bool reversed, const glm::dvec3& w) {
  const glm::vec3& d = directions[slot];
  const double dot = d.x * w.x + d.y * w.y + d.z * w.z;
  return reversed ? dot : -dot;  // forwards serves w = -d, backwards w = +d
}

namespace {

// Whether the box [lo, hi] lies wholly on the negative side of plane p: its corner farthest along the
// normal is outside.
bool box_outside(const glm::dvec4& p, const glm::dvec3& lo, const glm::dvec3& hi) {
  glm::dvec3 c(p.x >= 0 ? hi.x : lo.x, p.y >= 0 ? hi.y : lo.y, p.z >= 0 ? hi.z : lo.z);
  return p.x * c.x + p.y * c.y + p.z * c.z + p.w < 0;
}

bool outside(const ViewParams& view, const VoxelDrawInfo& v) {
  glm::dvec3 lo = glm::dvec3(v.tight_min) - view.eye, hi = glm::dvec3(v.tight_max) - view.eye;
  for (const glm::dvec4& p : view.planes)
    if (box_outside(p, lo, hi)) return true;
  for (const glm::dvec4& p : view.clip)
    if (box_outside(p, lo, hi)) return true;
  return false;
}

}  // namespace

void plan_frame(const SceneLayout& layout, const ViewParams& view, PlanOrder order, FramePlan& plan) {
  plan.first.clear();
  plan.count.clear();
  plan.voxels.clear();
  plan.sort_keys.clear();
  plan.voxels_drawn = plan.segments_drawn = 0;
  const auto& voxels = layout.voxels();
  for (std::uint32_t i = 0; i < voxels.size(); ++i) {
    const VoxelDrawInfo& v = voxels[i];
    if (v.segment_count == 0 || outside(view, v)) continue;
    glm::dvec3 d = v.center - view.eye;
    // back to front = descending distance: sort ascending on the negated key
    double key = view.orthographic                ? -glm::dot(d, view.forward)
                 : order == PlanOrder::Visibility ? -(std::abs(d.x) + std::abs(d.y) + std::abs(d.z))
                                                  : -glm::dot(d, d);
    plan.sort_keys.push_back({key, i});
  }
  if (order != PlanOrder::Any) std::sort(plan.sort_keys.begin(), plan.sort_keys.end());
  const bool hysteresis = order == PlanOrder::Nearest && plan.order_hysteresis > 0;
  if (order == PlanOrder::Nearest && !hysteresis) plan.previous_order.clear();
  if (hysteresis && plan.previous_order.size() != voxels.size())
    plan.previous_order.assign(voxels.size(), FramePlan::kNoOrder);
  plan.first.reserve(plan.sort_keys.size());
  plan.count.reserve(plan.sort_keys.size());
  plan.voxels.reserve(plan.sort_keys.size());
  for (const auto& [key, i] : plan.sort_keys) {
    const VoxelDrawInfo& v = voxels[i];
    std::uint32_t slot = layout.block_slot(v);
    bool reversed = false;
    if (order == PlanOrder::Nearest) {
      glm::dvec3 w = view.orthographic ? view.forward : glm::normalize(v.center - view.eye);
      const std::span<const glm::vec3> directions = layout.directions_of(i);
      std::tie(slot, reversed) = nearest_order(directions, w);
      if (hysteresis) {
        std::uint8_t& previous = plan.previous_order[i];
        if (previous != FramePlan::kNoOrder) {
          const std::uint32_t kept_slot = previous >> 1;
          const bool kept_reversed = previous & 1;
          if (order_alignment(directions, slot, reversed, w) -
                  order_alignment(directions, kept_slot, kept_reversed, w) <=
              plan.order_hysteresis) {
            slot = kept_slot;
            reversed = kept_reversed;
          }
        }
        previous = static_cast<std::uint8_t>(2 * slot + (reversed ? 1 : 0));
      }
    }
    plan.first.push_back(layout.first_id(v, slot, reversed));
    plan.count.push_back(layout.id_count(v, slot));
    plan.voxels.push_back(i);
    plan.segments_drawn += v.segment_count;
  }
  plan.voxels_drawn = plan.first.size();
}

}  // namespace vxl
