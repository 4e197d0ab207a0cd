#include "scene_layout.h"

#include <limits>

#include "error.h"

namespace vxl {

SceneLayout::SceneLayout(const VxlFile& file, std::uint64_t max_texels) {
  const MetaSection& m = file.meta();
  stored_orders_ = m.stored_order_count;
  voxel_size_ = m.voxel_size;
  for (const DirectionEntry& d : file.directions()) directions_.push_back({d.xyz[0], d.xyz[1], d.xyz[2]});
  voxel_directions_.reserve(file.voxel_directions().size());
  for (const DirectionEntry& d : file.voxel_directions()) voxel_directions_.push_back({d.xyz[0], d.xyz[1], d.xyz[2]});
  auto voxels = file.voxels();
  voxels_.resize(voxels.size());

  auto fits = [&](std::uint64_t vertices, std::uint64_t segments) {
    return 3 * vertices <= max_texels && slots() * segments <= max_texels;
  };
  ChunkLayout current;
  for (std::uint32_t i = 0; i < voxels.size(); ++i) {
    const VoxelEntry& e = voxels[i];
    if (!fits(e.vertex_count, e.segment_count))
      throw Error(ErrorKind::Unsupported, file.path(), std::nullopt,
                  "a voxel is larger than this GPU's texture-buffer limit (" + std::to_string(max_texels) +
                      " texels); convert with a smaller --voxel-size");
    if (current.voxel_count > 0 && !fits(current.vertex_count + e.vertex_count, current.segments + e.segment_count)) {
      chunks_.push_back(current);
      current = ChunkLayout{};
    }
    if (current.voxel_count == 0) {
      current.voxel_first = i;
      current.vertex_first = e.vertex_first;
    }
    VoxelDrawInfo& v = voxels_[i];
    for (int c = 0; c < 3; ++c) {
      v.center[c] = m.grid_origin[c] + (e.coord[c] + 0.5) * m.voxel_size;
      v.tight_min[c] = e.tight_min[c];
      v.tight_max[c] = e.tight_max[c];
    }
    v.chunk = static_cast<std::uint32_t>(chunks_.size());
    v.segment_count = e.segment_count;
    v.seg_first = current.segments;
    current.voxel_count++;
    current.vertex_count += e.vertex_count;
    current.segments += e.segment_count;
  }
  if (current.voxel_count > 0) chunks_.push_back(current);
  if (chunks_.size() > kMaxChunks)
    throw Error(ErrorKind::Unsupported, file.path(), std::nullopt,
                "the scene needs " + std::to_string(chunks_.size()) + " GPU chunks (at most " +
                    std::to_string(kMaxChunks) + " with a texture-buffer limit of " + std::to_string(max_texels) +
                    " texels)");
  for (ChunkLayout& c : chunks_) {
    c.virtual_base = virtual_ids_;
    virtual_ids_ += 2 * (2 * slots() * c.segments + c.segments);
  }
  if (virtual_ids_ > std::uint64_t(std::numeric_limits<std::int32_t>::max()))
    throw Error(ErrorKind::Unsupported, file.path(), std::nullopt,
                "the scene has too many segments x orders for one draw (" + std::to_string(virtual_ids_) +
                    " vertex ids > 2^31); use fewer stored orders");
}

}  // namespace vxl
