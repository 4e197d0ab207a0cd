// How a scene of one or more .vxl files is laid out on the GPU, computed on the CPU in O(voxels) (no GL
// here, so the per-frame planning can be tested and benchmarked without a context).
//
// The voxels of all files form one table (file 0's, then file 1's, ...), so that one frame plan sorts them
// all together, back to front, interleaved across files. Voxels are grouped into texture spans (contiguous voxel
// ranges of one file) small enough for the driver's texture-buffer limit. Each span holds, in texture
// buffers:
//   positions: 3 floats per vertex;
//   orders:    (K + 1) "slots" of S entries each (S = the span's segments; K its file's stored orders): the K
//              stored orders widened to
//              span-global vertex indices, then the block (dataset) order inside each voxel. A voxel owns the
//              same range [seg_first, seg_first + n) in every slot;
//   dataset:   S entries in streamline order (built only when the `unsorted` mode is first used).
// The vertex shader maps gl_VertexID ("virtual vertex id") to a segment end: per span, ids
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

#include "format/vxl_file.h"

namespace vxl {

struct VoxelDrawInfo {
  glm::dvec3 center;  // cube centre, mm
  glm::vec3 tight_min, tight_max;
  std::uint32_t span;  // its texture span
  std::uint32_t segment_count;
  std::uint64_t seg_first;  // within its span's slots
};

// One set of texture buffers: a contiguous voxel range of one file. Named "span", not "chunk", because the
// .vxlz package's position chunks are another thing.
struct TextureSpan {
  std::uint32_t file = 0;                            // the file its voxels come from
  std::uint32_t slots = 1;                           // its file's K + 1
  std::uint32_t voxel_first = 0, voxel_count = 0;    // scene voxel range
  std::uint64_t vertex_first = 0, vertex_count = 0;  // vertex range within its file
  std::uint64_t segments = 0;                        // S
  std::uint64_t virtual_base = 0;                    // first virtual vertex id
};

// Where one file's voxels are in the scene, and its sorting directions.
struct FileLayout {
  std::uint32_t voxel_first = 0, voxel_count = 0;
  std::uint32_t stored_orders = 0;          // K
  std::vector<glm::vec3> directions;        // DIRS
  std::vector<glm::vec3> voxel_directions;  // VDIR, voxel-major, K per voxel; empty without
};

class SceneLayout {
 public:
  // max_texels: the driver's GL_MAX_TEXTURE_BUFFER_SIZE (tests pass small values to force many spans).
  // Throws vxl::Error (Unsupported) when the scene needs more than kMaxTextureSpans texture spans or 2^31 virtual ids.
  SceneLayout(std::span<const VxlFile* const> files, std::uint64_t max_texels);
  SceneLayout(const VxlFile& file, std::uint64_t max_texels);

  static constexpr std::uint32_t kMaxTextureSpans = 8;  // each span needs 4 samplers in the vertex shader

  // Of the first file (all of a single-file scene): K, K + 1 slots, the block order's slot, DIRS.
  std::uint32_t stored_orders() const { return files_[0].stored_orders; }
  std::uint32_t slots() const { return stored_orders() + 1; }
  std::uint32_t block_slot() const { return stored_orders(); }
  const std::vector<glm::vec3>& directions() const { return files_[0].directions; }
  // The slot of a voxel's block (dataset) order: its file's K.
  std::uint32_t block_slot(const VoxelDrawInfo& v) const { return spans_[v.span].slots - 1; }
  // The K directions voxel `voxel`'s stored orders are sorted by: its own (VDIR, random order sets) or
  // its file's DIRS.
  std::span<const glm::vec3> directions_of(std::uint32_t voxel) const {
    const FileLayout& f = files_[spans_[voxels_[voxel].span].file];
    if (f.voxel_directions.empty()) return f.directions;
    return std::span<const glm::vec3>(f.voxel_directions)
        .subspan(std::size_t(voxel - f.voxel_first) * f.stored_orders, f.stored_orders);
  }
  const std::vector<VoxelDrawInfo>& voxels() const { return voxels_; }
  const std::vector<TextureSpan>& texture_spans() const { return spans_; }
  const std::vector<FileLayout>& files() const { return files_; }
  // The file a scene voxel belongs to, and its index in that file's voxel table.
  std::uint32_t file_of(std::uint32_t voxel) const { return spans_[voxels_[voxel].span].file; }
  std::uint32_t local_voxel(std::uint32_t voxel) const { return voxel - files_[file_of(voxel)].voxel_first; }
  std::uint64_t virtual_ids() const { return virtual_ids_; }
  double voxel_size() const { return voxel_size_; }  // the largest of the files'
  // Whether every file's voxels are cells of one grid (same size, origins a whole number of voxels
  // apart): then PlanOrder::Visibility is a visibility order for the whole scene.
  bool one_grid() const { return one_grid_; }

  // First virtual vertex id of voxel v's range in `slot`, forwards or reversed.
  std::int64_t first_id(const VoxelDrawInfo& v, std::uint32_t slot, bool reversed) const {
    const TextureSpan& c = spans_[v.span];
    const std::uint64_t s = c.segments, a = std::uint64_t(c.slots) * s;
    std::uint64_t seg = reversed ? a + slot * s + (s - v.seg_first - v.segment_count) : slot * s + v.seg_first;
    return static_cast<std::int64_t>(c.virtual_base + 2 * seg);
  }
  // First virtual id of entry j of a span's dataset-order array.
  std::int64_t dataset_id(std::uint32_t span, std::uint64_t j) const {
    const TextureSpan& c = spans_[span];
    return static_cast<std::int64_t>(c.virtual_base + 2 * (2 * std::uint64_t(c.slots) * c.segments + j));
  }

 private:
  std::vector<FileLayout> files_;
  std::vector<VoxelDrawInfo> voxels_;
  std::vector<TextureSpan> spans_;
  std::uint64_t virtual_ids_ = 0;
  double voxel_size_ = 0;
  bool one_grid_ = true;
};

}  // namespace vxl
