#include "viewer/render/scene_layout.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "format/base/error.h"

namespace vxl {

namespace {

bool same_grid(const MetaSection& a, const MetaSection& b) {
  if (a.voxel_size != b.voxel_size) return false;
  for (int c = 0; c < 3; ++c) {
    const double cells = (b.grid_origin[c] - a.grid_origin[c]) / a.voxel_size;
    if (std::abs(cells - std::round(cells)) > 1e-6) return false;
  }
  return true;
}

// A size in bytes below 1 MiB (budgets of a few bytes or KiB are allowed), else in MiB: never "0 MiB".
std::string memory_size(std::uint64_t bytes) {
  if (bytes < (std::uint64_t(1) << 20)) return std::to_string(bytes) + " bytes";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f MiB", double(bytes) / double(1 << 20));
  return buf;
}

}  // namespace

SceneLayout::SceneLayout(const VxlFile& file, std::uint64_t max_texels, std::uint32_t level)
    : SceneLayout(std::span<const VxlFile* const>(std::array<const VxlFile*, 1>{&file}), max_texels, level) {}

std::uint32_t SceneLayout::coarsest_level(std::span<const VxlFile* const> files) {
  std::uint32_t coarsest = kMaxLevels;
  for (const VxlFile* f : files) coarsest = std::min(coarsest, f->level_count() - 1);
  return files.empty() ? 0 : coarsest;
}

std::uint64_t SceneLayout::largest_voxel_texels(std::span<const VxlFile* const> files) {
  std::uint64_t largest = 0;
  auto padded = [](std::uint64_t n) { return (n + kGroup - 1) / kGroup * kGroup; };
  for (const VxlFile* f : files)
    for (std::uint32_t i = 0; i < f->voxels().size(); ++i) {
      const LevelEntry e = f->level(i, 0);  // level 0 holds the most
      TextureSpan alone;
      alone.slots = f->meta().stored_order_count;
      alone.voxel_count = 1;
      alone.vertices = padded(e.vertex_count);
      alone.segments = padded(e.segment_count);
      alone.order_words = level_orders_size(e, alone.slots, f->order_packing()) / 4;
      largest = std::max({largest, alone.words() / 4, alone.order_words});
    }
  return largest;
}

std::uint64_t SceneLayout::span_upload_bytes(std::uint32_t span) const {
  const TextureSpan& c = spans_[span];
  return 4 * c.words() + 4 * c.order_words + 4 * c.segments + 8 * c.vertices;
}

std::uint64_t SceneLayout::upload_bytes() const {
  std::uint64_t bytes = 0;
  for (std::uint32_t c = 0; c < spans_.size(); ++c) bytes += span_upload_bytes(c);
  return bytes;
}

std::uint32_t SceneLayout::finest_level_within(std::span<const VxlFile* const> files, std::uint64_t max_texels,
                                               std::uint64_t budget) {
  const std::uint32_t coarsest = coarsest_level(files);
  std::string why;
  for (std::uint32_t level = 0; level <= coarsest; ++level) {
    try {
      const SceneLayout layout(files, max_texels, level);
      if (layout.upload_bytes() <= budget) return level;
      why = "needs " + memory_size(layout.upload_bytes()) + " of GPU memory";
    } catch (const Error& e) {
      why = e.what();
    }
  }
  throw Error(ErrorKind::Unsupported, files.empty() ? "" : files[0]->path(), std::nullopt,
              "the scene does not fit the GPU memory budget of " + memory_size(budget) +
                  " even at its coarsest level of detail (" + std::to_string(coarsest) + "): it " + why +
                  (coarsest == 0 ? "; convert with levels of detail (voxlines convert --levels)" : ""));
}

float SceneLayout::level_opacity(float opacity, std::uint32_t level) {
  return static_cast<float>(1.0 - std::pow(1.0 - double(opacity), std::pow(double(kLevelRatio), double(level))));
}

SceneLayout::SceneLayout(std::span<const VxlFile* const> files, std::uint64_t max_texels, std::uint32_t level) {
  const std::vector<std::uint32_t> same(files.size(), std::min(level, coarsest_level(files)));
  lay_out(files, max_texels, same);
}

SceneLayout::SceneLayout(std::span<const VxlFile* const> files, std::uint64_t max_texels,
                         std::span<const std::uint32_t> file_levels) {
  std::vector<std::uint32_t> levels(files.size(), 0);
  for (std::size_t i = 0; i < files.size(); ++i)
    levels[i] = std::min(i < file_levels.size() ? file_levels[i] : 0u, files[i]->level_count() - 1);
  lay_out(files, max_texels, levels);
}

bool SceneLayout::one_level() const {
  return std::all_of(files_.begin(), files_.end(), [&](const FileLayout& f) { return f.level == level_; });
}

void SceneLayout::lay_out(std::span<const VxlFile* const> files, std::uint64_t max_texels,
                          std::span<const std::uint32_t> file_levels) {
  max_texels_ = max_texels;
  level_ = 0;
  for (std::uint32_t l : file_levels) level_ = std::max(level_, l);
  std::uint64_t total_voxels = 0;
  for (const VxlFile* f : files) total_voxels += f->meta().voxel_count;
  if (total_voxels > std::uint64_t(std::numeric_limits<std::int32_t>::max()))
    throw Error(ErrorKind::Unsupported, files.empty() ? "" : files[0]->path(), std::nullopt,
                "the files hold more than 2^31 voxels together");
  voxels_.resize(total_voxels);

  for (std::uint32_t fi = 0; fi < files.size(); ++fi) {
    const VxlFile& file = *files[fi];
    const MetaSection& m = file.meta();
    FileLayout fl;
    fl.voxel_first = files_.empty() ? 0 : files_.back().voxel_first + files_.back().voxel_count;
    fl.voxel_count = m.voxel_count;
    fl.stored_orders = m.stored_order_count;
    for (const DirectionEntry& d : file.directions()) fl.directions.push_back({d.xyz[0], d.xyz[1], d.xyz[2]});
    fl.voxel_directions.reserve(file.voxel_directions().size());
    for (const DirectionEntry& d : file.voxel_directions())
      fl.voxel_directions.push_back({d.xyz[0], d.xyz[1], d.xyz[2]});
    voxel_size_ = std::max(voxel_size_, m.voxel_size);
    if (fi > 0 && !same_grid(files[0]->meta(), m)) one_grid_ = false;
    const std::uint32_t slots = fl.stored_orders;
    auto padded = [](std::uint64_t n) { return (n + kGroup - 1) / kGroup * kGroup; };
    fl.level = file_levels[fi];
    auto counts = [&](std::uint32_t local) { return file.level(local, fl.level); };
    // The level's K orders as the file stores them, padded to 4 bytes (spec §5.5): whole words.
    auto order_words = [&](const LevelEntry& e) { return level_orders_size(e, slots, file.order_packing()) / 4; };
    // Both buffers of a span within the limit: its words (4 a texel) and its order words, which the vertex
    // shader also addresses in bits by a 32-bit uint (2^27 words at most); and its ids within one draw's.
    auto fits = [&](const TextureSpan& c) {
      return c.words() / 4 <= max_texels && c.order_words <= std::min<std::uint64_t>(max_texels, 1ull << 27) &&
             c.virtual_ids() <= std::uint64_t(std::numeric_limits<std::int32_t>::max() / 2);
    };
    auto voxels = file.voxels();
    TextureSpan current;
    current.file = fi;
    current.slots = slots;
    // Sets the span's voxels' ranges, in file order: vertex blocks, segment ranges and orders.
    auto close_span = [&] {
      std::uint64_t vertex = 0, seg = 0, word = 0;
      for (std::uint32_t i = current.voxel_first; i < current.voxel_first + current.voxel_count; ++i) {
        const LevelEntry e = counts(i - fl.voxel_first);
        VoxelDrawInfo& v = voxels_[i];
        v.vertex_first = vertex;
        v.seg_first = seg;
        v.order_word = word;
        v.order_bits = order_entry_bits(e.vertex_count, file.order_packing());
        vertex += padded(e.vertex_count);
        seg += padded(e.segment_count);
        word += order_words(e);
      }
      spans_.push_back(current);
    };
    for (std::uint32_t li = 0; li < voxels.size(); ++li) {
      const VoxelEntry& cube = voxels[li];
      const LevelEntry e = counts(li);
      const std::uint32_t i = fl.voxel_first + li;
      TextureSpan grown = current, alone = current;
      alone.voxel_count = 0;
      alone.segments = alone.vertices = alone.order_words = 0;
      for (TextureSpan* c : {&grown, &alone}) {
        c->voxel_count++;
        c->vertices += padded(e.vertex_count);
        c->segments += padded(e.segment_count);
        c->order_words += order_words(e);
      }
      if (!fits(alone))
        throw Error(ErrorKind::Unsupported, file.path(), std::nullopt,
                    "a voxel is larger than this GPU's texture-buffer limit (" + std::to_string(max_texels) +
                        " texels); convert with a smaller --voxel-size");
      if (current.voxel_count > 0 && !fits(grown)) {
        close_span();
        current = TextureSpan{};
        current.file = fi;
        current.slots = slots;
        grown = alone;
      }
      if (current.voxel_count == 0) grown.voxel_first = i;
      current = grown;
      VoxelDrawInfo& v = voxels_[i];
      for (int c = 0; c < 3; ++c) {
        v.center[c] = m.grid_origin[c] + (cube.coord[c] + 0.5) * m.voxel_size;
        v.tight_min[c] = cube.tight_min[c];
        v.tight_max[c] = cube.tight_max[c];
      }
      v.span = static_cast<std::uint32_t>(spans_.size());
      v.segment_count = e.segment_count;
      v.vertex_count = e.vertex_count;
    }
    if (current.voxel_count > 0) close_span();
    files_.push_back(std::move(fl));
  }
  for (TextureSpan& c : spans_) {
    c.virtual_base = virtual_ids_;
    virtual_ids_ += c.virtual_ids();
  }
}

std::uint32_t SceneLayout::span_of_id(std::int64_t id) const {
  const auto after = std::upper_bound(spans_.begin(), spans_.end(), static_cast<std::uint64_t>(id),
                                      [](std::uint64_t v, const TextureSpan& c) { return v < c.virtual_base; });
  return static_cast<std::uint32_t>(after - spans_.begin()) - 1;
}

}  // namespace vxl
