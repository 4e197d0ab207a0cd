// How a .vxl scene is laid out on the GPU, computed on the CPU in O(voxels) (no GL here, so the per-frame
// planning can be tested and benchmarked without a context).
//
// Voxels are grouped into chunks (contiguous voxel ranges) small enough for the driver's texture-buffer
// limit. Each chunk holds, in texture buffers:
//   positions: 3 floats per vertex;
//   orders:    (K + 1) "slots" of S entries each (S = the chunk's segments): the K stored orders widened to
//              chunk-global vertex indices, then the block (dataset) order inside each voxel. A voxel owns the
//              same range [seg_first, seg_first + n) in every slot;
//   dataset:   S entries in streamline order (built only when the `unsorted` mode is first used).
// The vertex shader maps gl_VertexID ("virtual vertex id") to a segment end: per chunk, ids
//   [0, 2A)        forward slot entries (A = (K + 1) S),
//   [2A, 4A)       the same slots read backwards (entry j of a slot appears at S - 1 - j), so a voxel's
//                  reversed order is again one contiguous range,
//   [4A, 4A + 2S)  dataset order,
// two ids per segment. One glMultiDrawArrays then draws any sequence of voxels, each in any stored order,
// forwards or backwards, with no per-frame work beyond filling the first/count arrays.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "vxl_file.h"

namespace vxl {

struct VoxelDrawInfo {
  glm::dvec3 center;        // cube centre, mm
  glm::vec3 tight_min, tight_max;
  std::uint32_t chunk;
  std::uint32_t segment_count;
  std::uint64_t seg_first;  // within its chunk's slots
};

struct ChunkLayout {
  std::uint32_t voxel_first = 0, voxel_count = 0;
  std::uint64_t vertex_first = 0, vertex_count = 0;  // global vertex range
  std::uint64_t segments = 0;                        // S
  std::uint64_t virtual_base = 0;                    // first virtual vertex id
  std::uint64_t slot_entries(std::uint32_t slots) const { return slots * segments; }
};

class SceneLayout {
 public:
  // max_texels: the driver's GL_MAX_TEXTURE_BUFFER_SIZE (tests pass small values to force many chunks).
  // Throws vxl::Error (Unsupported) when the scene needs more than kMaxChunks chunks or 2^31 virtual ids.
  SceneLayout(const VxlFile& file, std::uint64_t max_texels);

  static constexpr std::uint32_t kMaxChunks = 8;  // each chunk needs 3 samplers in the vertex shader

  std::uint32_t stored_orders() const { return stored_orders_; }     // K
  std::uint32_t slots() const { return stored_orders_ + 1; }         // K stored + block order
  std::uint32_t block_slot() const { return stored_orders_; }
  const std::vector<glm::vec3>& directions() const { return directions_; }  // DIRS
  // The K directions voxel `voxel`'s stored orders are sorted by: its own (VDIR, random order sets) or
  // the shared DIRS.
  std::span<const glm::vec3> directions_of(std::uint32_t voxel) const {
    if (voxel_directions_.empty()) return directions_;
    return std::span<const glm::vec3>(voxel_directions_).subspan(std::size_t(voxel) * stored_orders_, stored_orders_);
  }
  const std::vector<VoxelDrawInfo>& voxels() const { return voxels_; }
  const std::vector<ChunkLayout>& chunks() const { return chunks_; }
  std::uint64_t virtual_ids() const { return virtual_ids_; }
  double voxel_size() const { return voxel_size_; }

  // First virtual vertex id of voxel v's range in `slot`, forwards or reversed.
  std::int64_t first_id(const VoxelDrawInfo& v, std::uint32_t slot, bool reversed) const {
    const ChunkLayout& c = chunks_[v.chunk];
    const std::uint64_t s = c.segments, a = slots() * s;
    std::uint64_t seg = reversed ? a + slot * s + (s - v.seg_first - v.segment_count) : slot * s + v.seg_first;
    return static_cast<std::int64_t>(c.virtual_base + 2 * seg);
  }
  // First virtual id of entry j of a chunk's dataset-order array.
  std::int64_t dataset_id(std::uint32_t chunk, std::uint64_t j) const {
    const ChunkLayout& c = chunks_[chunk];
    return static_cast<std::int64_t>(c.virtual_base + 2 * (2 * slots() * c.segments + j));
  }

 private:
  std::uint32_t stored_orders_ = 0;
  std::vector<glm::vec3> directions_;
  std::vector<glm::vec3> voxel_directions_;  // voxel-major, K per voxel; empty without VDIR
  std::vector<VoxelDrawInfo> voxels_;
  std::vector<ChunkLayout> chunks_;
  std::uint64_t virtual_ids_ = 0;
  double voxel_size_ = 0;
};

}  // namespace vxl
