#include "viewer/render/gpu_scene.h"

#include <algorithm>

#include "format/error.h"
#include "format/parallel.h"
#include "format/vxl_streamlines.h"

namespace vxl {

std::uint64_t GpuScene::driver_limit() {
  GLint texels = 0;
  glGetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, &texels);
  return texels > 0 ? static_cast<std::uint64_t>(texels) : 65536;  // 65536 is the GL 3.3 minimum
}

// Widens voxel i's stored orders to span-global u32 and appends its block order; checks every entry,
// which open() does not (it would cost O(points) there).
void GpuScene::widen_voxel(const VxlFile& file, std::uint32_t i, std::uint32_t li, const TextureSpan& c,
                           std::vector<std::uint32_t>& entries, std::vector<std::uint8_t>& is_start) const {
  const VoxelEntry& v = file.voxels()[li];
  const VoxelDrawInfo& d = layout_.voxels()[i];
  const std::uint32_t base = static_cast<std::uint32_t>(v.vertex_first - c.vertex_first);
  is_start.assign(v.vertex_count, 0);
  for (std::uint32_t k = 0; k + 1 < c.slots; ++k) {
    OrderView o = file.order(li, k);
    std::uint32_t* out = entries.data() + k * c.segments + d.seg_first;
    for (std::uint32_t n = 0; n < o.count; ++n) {
      std::uint32_t e = o[n];
      if (e + 1ull >= v.vertex_count)
        throw Error(ErrorKind::Input, file.path(), file.find_section(section_id("ORDR"))->offset + v.order_offset,
                    "order entry out of range in voxel " + std::to_string(li) + " (run `voxlines verify`)");
      out[n] = base + e;
      if (k == 0) is_start[e] = 1;
    }
  }
  std::uint32_t* block = entries.data() + layout_.block_slot(d) * c.segments + d.seg_first;
  std::uint32_t n = 0;
  for (std::uint32_t e = 0; e < v.vertex_count && n < v.segment_count; ++e)
    if (is_start[e]) block[n++] = base + e;
  if (n != v.segment_count)  // a repeated entry in order 0: it is no permutation
    throw Error(
        ErrorKind::Input, file.path(), file.find_section(section_id("ORDR"))->offset + v.order_offset,
        "order 0 of voxel " + std::to_string(li) + " is not a permutation of its segments (run `voxlines verify`)");
}

GpuScene::GpuScene(std::vector<const VxlFile*> files, std::uint64_t max_texels)
    : files_(std::move(files)), layout_(files_, max_texels ? max_texels : driver_limit()) {
  std::vector<std::uint32_t> entries;
  for (const TextureSpan& c : layout_.texture_spans()) {
    const VxlFile& file = *files_[c.file];
    const std::uint32_t file_first = layout_.files()[c.file].voxel_first;
    GpuTextureSpan g;
    if (file.position_encoding() == PositionEncoding::Float32) {
      g.positions.create(GL_R32F, file.float_vertices().data() + 3 * c.vertex_first, 12 * c.vertex_count);
    } else {
      // Packed positions (spec §5.4) are decoded here, voxel by voxel, for the float32 texture.
      std::vector<float> xyz(3 * c.vertex_count);
      parallel_for(c.voxel_count, 0, [&](std::uint64_t k, unsigned) {
        const std::uint32_t local = c.voxel_first + static_cast<std::uint32_t>(k) - file_first;
        const VoxelEntry& v = file.voxels()[local];
        file.read_vertices(local, v.vertex_first, v.vertex_count, xyz.data() + 3 * (v.vertex_first - c.vertex_first));
      });
      g.positions.create(GL_R32F, xyz.data(), 12 * c.vertex_count);
    }
    entries.resize(std::uint64_t(c.slots) * c.segments);
    // Voxels fill disjoint ranges of every slot, so they are widened in parallel.
    std::vector<std::vector<std::uint8_t>> is_start(resolve_threads(0));  // scratch per thread
    try {
      parallel_for(c.voxel_count, 0, [&](std::uint64_t k, unsigned t) {
        const std::uint32_t i = c.voxel_first + static_cast<std::uint32_t>(k);
        widen_voxel(file, i, i - file_first, c, entries, is_start[t]);
      });
    } catch (...) {
      g.positions.destroy();
      release();
      throw;
    }
    g.orders.create(GL_R32UI, entries.data(), entries.size() * 4);
    g.dataset.create(GL_R32UI, nullptr, 0);
    g.attributes.create(GL_RG32F, nullptr, 0);
    gpu_bytes_ += 12 * c.vertex_count + entries.size() * 4;
    spans_.push_back(g);
  }
  entries.clear();
  entries.shrink_to_fit();
}

GpuScene::~GpuScene() { release(); }

void GpuScene::release() {
  for (GpuTextureSpan& c : spans_) {
    c.positions.destroy();
    c.orders.destroy();
    c.dataset.destroy();
    c.attributes.destroy();
  }
  spans_.clear();
}

void GpuScene::upload_attributes(const std::vector<std::vector<float>>& per_file) {
  for (std::size_t i = 0; i < spans_.size(); ++i) {
    const TextureSpan& c = layout_.texture_spans()[i];
    GpuTextureSpan& g = spans_[i];
    g.attributes.destroy();
    const std::vector<float>* values = c.file < per_file.size() ? &per_file[c.file] : nullptr;
    if (values == nullptr || values->empty())
      g.attributes.create(GL_RG32F, nullptr, 0);
    else
      g.attributes.create(GL_RG32F, values->data() + 2 * c.vertex_first, 8 * c.vertex_count);
  }
}

const std::vector<std::int32_t>& GpuScene::dataset_first() {
  if (!dataset_built_) {
    // Walk the streamlines, file after file: every voxline contributes its segments, in order, to its
    // span's dataset array; consecutive segments in one span form one draw range.
    std::vector<std::vector<std::uint32_t>> per_span(layout_.texture_spans().size());
    std::int64_t run_span = -1;
    for (std::uint32_t fi = 0; fi < files_.size(); ++fi) {
      const std::uint32_t file_first = layout_.files()[fi].voxel_first;
      WalkCallbacks cb;
      cb.voxline = [&](std::uint32_t voxel, std::uint64_t first_vertex, std::uint32_t own, bool connected) {
        const std::uint32_t c = layout_.voxels()[file_first + voxel].span;
        const TextureSpan& cl = layout_.texture_spans()[c];
        const std::uint64_t segments = own + (connected ? 1 : 0) - 1;
        if (segments == 0) return;
        auto& arr = per_span[c];
        if (run_span != c) {
          dataset_first_.push_back(static_cast<std::int32_t>(layout_.dataset_id(c, arr.size())));
          dataset_count_.push_back(0);
          run_span = c;
        }
        for (std::uint64_t s = 0; s < segments; ++s)
          arr.push_back(static_cast<std::uint32_t>(first_vertex - cl.vertex_first + s));
        dataset_count_.back() += static_cast<std::int32_t>(2 * segments);
      };
      walk_streamlines(*files_[fi], cb);
    }
    for (std::size_t c = 0; c < spans_.size(); ++c) {
      spans_[c].dataset.destroy();
      spans_[c].dataset.create(GL_R32UI, per_span[c].data(), per_span[c].size() * 4);
      gpu_bytes_ += per_span[c].size() * 4;
    }
    dataset_built_ = true;
  }
  return dataset_first_;
}

const std::vector<std::int32_t>& GpuScene::dataset_count() {
  dataset_first();
  return dataset_count_;
}

}  // namespace vxl
