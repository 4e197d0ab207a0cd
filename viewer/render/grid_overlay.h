// Voxel-grid overlay: the cube outlines of the voxels a frame draws (those inside the view frustum, as the
// renderer's plan culls them) or of every voxel, as GL_LINES over the picture. Shows what the Voxlines
// method sorts. Needs only a current OpenGL 3.3 core context, like the Renderer.
//
// It outlines the voxels of the files it is made for (the files the user opened): a renderer that draws other
// files beside them (focus first's full-detail copy of the selection, viewer_session.h) has their voxels in its
// plan, but those files are an implementation detail and are not outlined.
//
// Camera-relative like the renderer, but exact in a simpler way: the shader subtracts the eye's integer
// grid cell from each voxel's integer coordinate (exact in int) and adds the eye's fractional cell
// position, so cubes far from the origin stay put.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "viewer/render/clip_planes.h"
#include "viewer/render/frame_plan.h"
#include "viewer/render/gl_util.h"

namespace vxl {

class Renderer;
class VxlFile;
struct Camera;

class GridOverlay {
 public:
  enum class Scope { Drawn, All };

  // Outlines the voxels of `files`, whichever renderer draws them; they must outlive the overlay.
  explicit GridOverlay(std::span<const VxlFile* const> files);
  // Outlines the voxels of every file `renderer` draws now.
  explicit GridOverlay(const Renderer& renderer);
  ~GridOverlay();
  GridOverlay(const GridOverlay&) = delete;
  GridOverlay& operator=(const GridOverlay&) = delete;

  // Draws into the bound framebuffer with the current viewport; blends `colour` over the picture.
  // Scope::Drawn outlines the voxels the frame draws with `clipping` (the slab and clip planes cull too). Only
  // the overlay's files are outlined, whatever else `renderer` draws.
  void draw(const Renderer& renderer, const Camera& camera, double aspect, Scope scope, const glm::vec4& colour,
            const Clipping& clipping = {});

  std::uint64_t cubes_drawn() const { return cubes_drawn_; }

 private:
  // The index of `file` among files_; none when the overlay does not outline it.
  std::optional<std::size_t> index_of(const VxlFile* file) const;

  std::vector<const VxlFile*> files_;
  std::vector<std::uint64_t> all_first_;  // files_[i]'s first instance in all_instances_
  GLuint program_ = 0, vao_ = 0, corners_ = 0, all_instances_ = 0, drawn_instances_ = 0;
  std::uint64_t voxel_count_ = 0, cubes_drawn_ = 0;
  FramePlan plan_;                        // re-planned here: the renderer keeps its own plan private
  std::vector<glm::ivec3> drawn_coords_;  // scratch, kept between frames
};

}  // namespace vxl
