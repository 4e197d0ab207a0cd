// What one view of a scene needs, computed on the CPU from the scene's layout, without GL: the projection
// fitted to the scene, the frame plan (culling and sort), the spans the plan touches and the GPU memory they
// take. The renderer draws with these; the viewer picks a level of detail with them before it makes a
// renderer.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "viewer/render/camera.h"
#include "viewer/render/clip_planes.h"
#include "viewer/render/frame_plan.h"
#include "viewer/render/scene_layout.h"
#include "viewer/render/volume.h"

namespace vxl {

class VxlFile;

struct SceneBounds {
  glm::dvec3 min{0.0}, max{0.0};
};

// The union of the files' line bounds (a file without points does not count); all zero when none has points.
SceneBounds line_bounds(std::span<const VxlFile* const> files);
// What the renderer's projection covers: the lines' bounds joined with the anatomical image's box (none: the
// lines alone).
SceneBounds scene_bounds(std::span<const VxlFile* const> files, const Volume* volume);

// The projection of `camera` with near and far planes on the sphere (centre, radius), for depth precision.
glm::dmat4 projection_around(const Camera& camera, double aspect, const glm::dvec3& centre, double radius);
// The projection of `camera` with near and far planes hugging `scene`'s bounding sphere. voxel_size: the
// scene's voxel size, the margin (never more than the scene's own size).
glm::dmat4 fitted_projection(const Camera& camera, double aspect, const SceneBounds& scene, double voxel_size);

// The frame plan of `camera` with `projection`: voxels outside the frustum or the slab / clip planes of
// `clipping` culled, the rest in `order`.
void plan_view(const SceneLayout& layout, const Camera& camera, const glm::dmat4& projection, PlanOrder order,
               FramePlan& out, const Clipping& clipping);

// The spans a plan's voxels lie in, each once, those of the nearest voxels first (a sorted plan is back to front).
std::vector<std::uint32_t> spans_nearest_first(const SceneLayout& layout, const FramePlan& plan);

// The most GPU memory a frame of `camera` with `clipping` can need: the spans its visible voxels lie in, with
// everything a mode may upload for them (SceneLayout::span_upload_bytes).
std::uint64_t view_bytes(const SceneLayout& layout, const Camera& camera, double aspect, const SceneBounds& scene,
                         const Clipping& clipping);

}  // namespace vxl
