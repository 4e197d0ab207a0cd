// The GPU copy of a scene of one or more .vxl files: per texture span (see scene_layout.h) a positions buffer (one
// large copy straight from the memory-mapped file), an orders buffer (stored orders widened to span-global u32
// indices, each entry checked, plus the block order), and — only when first needed — a dataset-order buffer.
#pragma once

#include <cstdint>
#include <vector>

#include "format/vxl_file.h"
#include "viewer/render/gl_util.h"
#include "viewer/render/scene_layout.h"

namespace vxl {

struct GpuTextureSpan {
  gl::TextureBuffer positions;   // GL_R32F, 3 texels per vertex
  gl::TextureBuffer orders;      // GL_R32UI, slots x S
  gl::TextureBuffer dataset;     // GL_R32UI, S (empty until needed)
  gl::TextureBuffer attributes;  // GL_RG32F, (value, group) per vertex (empty until a colour mode needs it)
};

class GpuScene {
 public:
  // Needs a current GL context. max_texels 0: ask the driver (GL_MAX_TEXTURE_BUFFER_SIZE). The files must
  // outlive the scene.
  GpuScene(std::vector<const VxlFile*> files, std::uint64_t max_texels = 0);
  GpuScene(const VxlFile& file, std::uint64_t max_texels = 0)
      : GpuScene(std::vector<const VxlFile*>{&file}, max_texels) {}
  ~GpuScene();
  GpuScene(const GpuScene&) = delete;
  GpuScene& operator=(const GpuScene&) = delete;

  const SceneLayout& layout() const { return layout_; }
  const std::vector<GpuTextureSpan>& texture_spans() const { return spans_; }
  std::uint64_t gpu_bytes() const { return gpu_bytes_; }

  // Replaces every span's attribute buffer with its vertices' share of its file's `per_file` entry (2 floats
  // per vertex of that file, vertex_attributes.h); an empty vector empties them.
  void upload_attributes(const std::vector<std::vector<float>>& per_file);

  // Streamline-order draw ranges for the `unsorted` mode, built on first use (O(segments)).
  const std::vector<std::int32_t>& dataset_first();
  const std::vector<std::int32_t>& dataset_count();

 private:
  static std::uint64_t driver_limit();
  void release();
  // Voxel `voxel` of the scene (`local` in its file).
  void widen_voxel(const VxlFile& file, std::uint32_t voxel, std::uint32_t local, const TextureSpan& span,
                   std::vector<std::uint32_t>& entries, std::vector<std::uint8_t>& is_start) const;
  std::vector<const VxlFile*> files_;
  SceneLayout layout_;
  std::vector<GpuTextureSpan> spans_;
  std::uint64_t gpu_bytes_ = 0;
  bool dataset_built_ = false;
  std::vector<std::int32_t> dataset_first_, dataset_count_;
};

}  // namespace vxl
