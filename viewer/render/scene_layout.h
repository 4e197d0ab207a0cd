// How a scene of one or more .vxl files is laid out on the GPU, computed on the CPU in O(voxels) (no GL
// here, so the per-frame planning can be tested and benchmarked without a context).
//
// The voxels of all files form one table (file 0's, then file 1's, ...), so that one frame plan sorts them
// all together, back to front, interleaved across files. Voxels are grouped into texture spans (contiguous voxel
// ranges of one file) small enough for the driver's texture-buffer limit; there may be any number of spans:
// a draw binds a few at a time (LinePass::draw_plan). Each span holds, in four texture
// buffers (gpu_scene.h says how each is filled):
//   words:   RGBA32UI, 4 words a texel: the packed positions as the file stores them (.vxl spec §5.4), each
//            voxel's block starting at a multiple of kGroup words; then kInfoWords words of decoding info per
//            voxel (VoxelGpuInfo); then one voxel index per kGroup slot entries (the segment table) and per
//            kGroup vertices (the vertex table), so that the vertex shader finds any entry's or vertex's voxel
//            with one fetch;
//   orders:  R32UI: each voxel's K stored orders of the span's level as the file stores them (ORDB, or whole
//            bytes in an older file's ORDR: spec §5.5), from the word `order_word`; the vertex shader decodes an
//            entry with one or two fetches and a shift;
//   dataset: S entries in streamline order (built only when the `unsorted` mode is first used);
//   values:  per vertex, for the colour modes that need them.
// "Slots" number the entries the vertex shader can draw: K slots of S entries each (S = the span's segments,
// each voxel's range starting at a multiple of kGroup, so that the segment table finds it; K its file's
// stored orders); entry j of voxel v's range in slot k is entry j of v's order k.
// The vertex shader maps gl_VertexID ("virtual vertex id") to a segment end: per span, ids
//   [0, 2A)             forward slot entries (A = K S),
//   [2A, 4A)            the same slots read backwards (entry j of a slot appears at S - 1 - j), so a voxel's
//                       reversed order is again one contiguous range,
//   [4A, 4A + 2V)       the block order: segment (v, v + 1) for every vertex v of the span's blocks, dropped
//                       where v ends its voxline (the packed word's bit 30),
//   [4A + 2V, .. + 2S)  dataset order,
// two ids per segment. The spans' id ranges follow one another ("virtual" ids, 64-bit: the scene's may pass
// 2^31); a span's own range stays below 2^31, so that a draw of a few spans, rebased, is one
// glMultiDrawArrays of any sequence of their voxels, each in any stored order, forwards or backwards, or in
// block order, with no per-frame work beyond filling the first/count arrays.
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
  std::uint32_t vertex_count;
  std::uint64_t seg_first;     // within its span's slots; a multiple of SceneLayout::kGroup
  std::uint64_t vertex_first;  // within its span's words; a multiple of SceneLayout::kGroup
  std::uint64_t order_word;    // where its orders start in its span's order buffer, in 32-bit words
  std::uint32_t order_bits;    // bits per order entry at its level (spec §5.5)
};

// One set of texture buffers: a contiguous voxel range of one file. Named "span", not "chunk", because the
// .vxlz package's position chunks are another thing.
struct TextureSpan {
  std::uint32_t file = 0;                          // the file its voxels come from
  std::uint32_t slots = 1;                         // its file's K
  std::uint32_t voxel_first = 0, voxel_count = 0;  // scene voxel range
  std::uint64_t segments = 0;                      // S, with each voxel's range padded to a multiple of kGroup
  std::uint64_t vertices = 0;                      // V, with each voxel's block padded to a multiple of kGroup
  std::uint64_t order_words = 0;                   // its voxels' stored orders at its level, in 32-bit words
  std::uint64_t virtual_base = 0;                  // first virtual vertex id
  // How many virtual ids the span's four ranges take (below 2^31).
  std::uint64_t virtual_ids() const { return 2 * (2 * std::uint64_t(slots) * segments + vertices + segments); }
  // Where the parts of the words buffer start, in words (see above); its size in words.
  std::uint64_t info_first() const { return vertices; }
  std::uint64_t segment_table_first() const { return vertices + kInfoWords * std::uint64_t(voxel_count); }
  std::uint64_t vertex_table_first() const { return segment_table_first() + segments / kGroupSize; }
  std::uint64_t words() const { return (vertex_table_first() + vertices / kGroupSize + 3) / 4 * 4; }
  static constexpr std::uint64_t kGroupSize = 32;
  // Decoding info per voxel, three texels (line_shaders.cpp reads them):
  //   lo.x lo.y lo.z step.x | step.y step.z vertex_first vertex_count | seg_first segment_count bits order_word
  // (lo and step as binary32 bits, spec §5.4; the rest the VoxelDrawInfo fields and the level's counts).
  static constexpr std::uint64_t kInfoWords = 12;
};

// Where one file's voxels are in the scene, and its sorting directions.
struct FileLayout {
  std::uint32_t voxel_first = 0, voxel_count = 0;
  std::uint32_t level = 0;                  // the level of detail its voxels are drawn at (.vxl spec §5.12)
  std::uint32_t stored_orders = 0;          // K
  std::vector<glm::vec3> directions;        // DIRS
  std::vector<glm::vec3> voxel_directions;  // VDIR, voxel-major, K per voxel; empty without
};

class SceneLayout {
 public:
  // max_texels: the driver's GL_MAX_TEXTURE_BUFFER_SIZE (tests pass small values to force many spans).
  // level: the level of detail to lay out (.vxl spec §5.12; 0: every streamline), the same for every file,
  // at most the coarsest level all files have. Throws vxl::Error (Unsupported) when one voxel alone does not
  // fit a span.
  SceneLayout(std::span<const VxlFile* const> files, std::uint64_t max_texels, std::uint32_t level = 0);
  SceneLayout(const VxlFile& file, std::uint64_t max_texels, std::uint32_t level = 0);
  // Each file at its own level (file_levels[i], at most that file's coarsest): a selection's focus copy at
  // full detail beside the context's files at a coarser level (viewer_session.h). level() is then the
  // coarsest of them.
  SceneLayout(std::span<const VxlFile* const> files, std::uint64_t max_texels,
              std::span<const std::uint32_t> file_levels);

  // The texels the largest voxel's span takes at full detail: the smallest max_texels every level fits.
  static std::uint64_t largest_voxel_texels(std::span<const VxlFile* const> files);
  // The coarsest level every file has (0 when one has no levels).
  static std::uint32_t coarsest_level(std::span<const VxlFile* const> files);
  // The finest level whose layout fits the limits and whose GPU copy (upload_bytes) is at most `budget`
  // bytes. Throws vxl::Error (Unsupported) naming what the coarsest level would need when none fits.
  static std::uint32_t finest_level_within(std::span<const VxlFile* const> files, std::uint64_t max_texels,
                                           std::uint64_t budget);
  // The most the GPU copy of this layout can take, in bytes: words and orders of every span, plus the
  // dataset order and the per-vertex attributes that some modes upload on first use.
  std::uint64_t upload_bytes() const;
  // The same for one span.
  std::uint64_t span_upload_bytes(std::uint32_t span) const;
  // The level the scene is drawn at (the coarsest file's), and the opacity that makes a segment of it stand for the
  // 8^level segments of full detail it samples (.vxl spec §6.5): 1 - (1 - opacity)^(8^level).
  std::uint32_t level() const { return level_; }
  // The most texels one of its spans may hold, as it was laid out with.
  std::uint64_t max_texels() const { return max_texels_; }
  static float level_opacity(float opacity, std::uint32_t level);

  static constexpr std::uint64_t kGroup = TextureSpan::kGroupSize;

  // Of the first file (all of a single-file scene): K, DIRS.
  std::uint32_t stored_orders() const { return files_[0].stored_orders; }
  const std::vector<glm::vec3>& directions() const { return files_[0].directions; }
  // The pseudo-slot that draws a voxel in block order: its file's K (one past its stored orders).
  std::uint32_t block_slot(const VoxelDrawInfo& v) const { return spans_[v.span].slots; }
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
  // Whether every file is drawn at level().
  bool one_level() const;
  // The file a scene voxel belongs to, and its index in that file's voxel table.
  std::uint32_t file_of(std::uint32_t voxel) const { return spans_[voxels_[voxel].span].file; }
  std::uint32_t local_voxel(std::uint32_t voxel) const { return voxel - files_[file_of(voxel)].voxel_first; }
  std::uint64_t virtual_ids() const { return virtual_ids_; }
  // The span whose range holds virtual id `id` (< virtual_ids()).
  std::uint32_t span_of_id(std::int64_t id) const;
  double voxel_size() const { return voxel_size_; }  // the largest of the files'
  // Whether every file's voxels are cells of one grid (same size, origins a whole number of voxels
  // apart): then PlanOrder::Visibility is a visibility order for the whole scene.
  bool one_grid() const { return one_grid_; }

  // First virtual vertex id of voxel v's range in `slot` (block_slot(v): block order), forwards or reversed,
  // and how many ids from there draw it.
  std::int64_t first_id(const VoxelDrawInfo& v, std::uint32_t slot, bool reversed) const {
    const TextureSpan& c = spans_[v.span];
    const std::uint64_t s = c.segments, a = std::uint64_t(c.slots) * s;
    const std::uint64_t seg = slot == c.slots ? 2 * a + v.vertex_first
                              : reversed      ? a + slot * s + (s - v.seg_first - v.segment_count)
                                              : slot * s + v.seg_first;
    return static_cast<std::int64_t>(c.virtual_base + 2 * seg);
  }
  std::int32_t id_count(const VoxelDrawInfo& v, std::uint32_t slot) const {
    if (slot == spans_[v.span].slots)
      return v.vertex_count == 0 ? 0 : static_cast<std::int32_t>(2 * (v.vertex_count - 1));
    return static_cast<std::int32_t>(2 * v.segment_count);
  }
  // First virtual id of entry j of a span's dataset-order array.
  std::int64_t dataset_id(std::uint32_t span, std::uint64_t j) const {
    const TextureSpan& c = spans_[span];
    return static_cast<std::int64_t>(c.virtual_base + 2 * (2 * std::uint64_t(c.slots) * c.segments + c.vertices + j));
  }

 private:
  void lay_out(std::span<const VxlFile* const> files, std::uint64_t max_texels,
               std::span<const std::uint32_t> file_levels);
  std::vector<FileLayout> files_;
  std::vector<VoxelDrawInfo> voxels_;
  std::vector<TextureSpan> spans_;
  std::uint64_t virtual_ids_ = 0;
  std::uint64_t max_texels_ = 0;
  std::uint32_t level_ = 0;
  double voxel_size_ = 0;
  bool one_grid_ = true;
};

}  // namespace vxl
