#include "viewer/render/gpu_scene.h"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <limits>
#include <thread>
#include <utility>

#include "format/base/error.h"
#include "format/base/parallel.h"
#include "format/vxl_draw_check.h"
#include "format/vxl_streamlines.h"

namespace vxl {

std::uint64_t GpuScene::driver_limit() {
  const std::uint64_t texels = gl::max_buffer_texels();
  return texels > 1 ? texels : 65536;  // 65536 is the GL 3.3 minimum
}

template <typename T>
void GpuScene::FillWindow<T>::put(std::uint64_t at, const T* from, std::uint64_t n) const {
  const std::uint64_t begin = std::max(at, first), stop = std::min(at + n, end);
  if (begin < stop) std::memcpy(data + (begin - first), from + (begin - at), (stop - begin) * sizeof(T));
}

template <typename T>
void GpuScene::FillWindow<T>::fill(std::uint64_t at, std::uint64_t n, T value) const {
  const std::uint64_t begin = std::max(at, first), stop = std::min(at + n, end);
  if (begin < stop) std::fill(data + (begin - first), data + (stop - first), value);
}

// Voxel i's orders at the span's level, as the file stores them.
void GpuScene::copy_voxel_orders(const VxlFile& file, std::uint32_t i, std::uint32_t li, const TextureSpan& c,
                                 const FillWindow<std::uint8_t>& orders) const {
  const VoxelEntry& v = file.voxels()[li];
  const std::uint32_t level = layout_.files()[c.file].level;
  orders.put(4 * layout_.voxels()[i].order_word,
             file.order_bytes().data() + level_orders_offset(v, file.levels_of(li), level,
                                                             file.meta().stored_order_count, file.order_packing()),
             level_orders_size(file.level(li, level), c.slots, file.order_packing()));
}

// Voxel i's part of its span's words: the block's packed words as stored (a float32 block packed here, its
// voxline-end bits from order 0, whose entries this therefore checks), zeros after the block up to the next
// voxel's, and the small decoding info and table entries.
void GpuScene::fill_voxel_words(const VxlFile& file, std::uint32_t i, std::uint32_t li, std::uint32_t index,
                                const TextureSpan& c, const FillWindow<std::uint32_t>& words,
                                VoxelScratch& scratch) const {
  const VoxelEntry& v = file.voxels()[li];
  const VoxelDrawInfo& d = layout_.voxels()[i];
  // The scene's level of the voxel: a prefix of its block and that level's orders (.vxl spec §5.12).
  const std::uint32_t level = layout_.files()[c.file].level;
  const LevelEntry counts = file.level(li, level);
  const std::uint64_t group = SceneLayout::kGroup;
  const std::uint64_t padded_vertices = (counts.vertex_count + group - 1) / group * group;
  const std::uint64_t padded_segments = (counts.segment_count + group - 1) / group * group;
  const std::uint64_t info_at = c.info_first() + TextureSpan::kInfoWords * std::uint64_t(index);
  const std::uint64_t segment_table_at = c.segment_table_first() + d.seg_first / group;
  const std::uint64_t vertex_table_at = c.vertex_table_first() + d.vertex_first / group;
  if (!words.meets(d.vertex_first, padded_vertices) && !words.meets(info_at, TextureSpan::kInfoWords) &&
      !words.meets(segment_table_at, padded_segments / group) && !words.meets(vertex_table_at, padded_vertices / group))
    return;
  if (file.position_encoding() == PositionEncoding::Packed) {
    words.put(d.vertex_first, file.packed_vertices().data() + v.vertex_first, counts.vertex_count);
  } else {
    // float32 blocks carry no end bits: they come from order 0 (a vertex where no segment starts).
    std::vector<std::uint8_t>& is_start = scratch.is_start;
    is_start.assign(counts.vertex_count, 0);
    const OrderView o = file.order(li, 0, level);
    for (std::uint32_t n = 0; n < o.count; ++n) {
      const std::uint32_t e = o[n];
      if (e + 1ull >= counts.vertex_count)
        throw Error(ErrorKind::Input, file.path(),
                    file.orders_offset() + level_orders_offset(v, file.levels_of(li), level,
                                                               file.meta().stored_order_count, file.order_packing()),
                    "order entry out of range in voxel " + std::to_string(li) + " (run `voxlines verify`)");
      is_start[e] = 1;
    }
    scratch.xyz.resize(3 * std::uint64_t(counts.vertex_count));
    file.read_vertices(li, v.vertex_first, counts.vertex_count, scratch.xyz.data());
    scratch.block.resize(counts.vertex_count);
    pack_block(v, scratch.xyz.data(), counts.vertex_count, scratch.block.data());
    for (std::uint32_t n = 0; n < counts.vertex_count; ++n) scratch.block[n] |= is_start[n] ? 0u : kPackedVoxlineEnd;
    words.put(d.vertex_first, scratch.block.data(), counts.vertex_count);
  }
  words.fill(d.vertex_first + counts.vertex_count, padded_vertices - counts.vertex_count, 0u);

  // Decoding info (TextureSpan::kInfoWords): lo and step per axis as the spec computes them (binary32), where
  // the block and the orders are, and the level's counts, which the shader clamps the file's entries to.
  std::uint32_t info[TextureSpan::kInfoWords] = {};
  for (int a = 0; a < 3; ++a) {
    const float lo = v.tight_min[a], step = (v.tight_max[a] - v.tight_min[a]) / static_cast<float>(kPackedSteps);
    std::memcpy(info + a, &lo, 4);
    std::memcpy(info + 3 + a, &step, 4);
  }
  info[6] = static_cast<std::uint32_t>(d.vertex_first);
  info[7] = counts.vertex_count;
  info[8] = static_cast<std::uint32_t>(d.seg_first);
  info[9] = counts.segment_count;
  info[10] = d.order_bits;
  info[11] = static_cast<std::uint32_t>(d.order_word);
  words.put(info_at, info, TextureSpan::kInfoWords);
  words.fill(segment_table_at, padded_segments / group, index);
  words.fill(vertex_table_at, padded_vertices / group, index);
}

namespace {

SceneLayout scene_layout(const std::vector<const VxlFile*>& files, std::uint64_t max_texels, std::uint32_t level,
                         const std::vector<std::uint32_t>& file_levels) {
  if (file_levels.empty()) return SceneLayout(files, max_texels, level);
  return SceneLayout(files, max_texels, file_levels);
}

}  // namespace

GpuScene::GpuScene(std::vector<const VxlFile*> files, std::uint64_t max_texels, std::uint32_t level,
                   std::shared_ptr<GpuMemoryPool> pool, bool eager, const std::vector<std::uint32_t>& file_levels)
    : files_(std::move(files)),
      layout_(scene_layout(files_, max_texels ? max_texels : driver_limit(), level, file_levels)),
      pool_(pool ? std::move(pool) : std::make_shared<GpuMemoryPool>()),
      spans_(layout_.texture_spans().size()),
      resident_(layout_.texture_spans().size(), false),
      uploaded_bytes_(layout_.texture_spans().size(), 0),
      checked_(layout_.texture_spans().size(), false) {
  owner_ = pool_->add_owner([this](std::uint32_t c) { evict(c); });
  try {
    // A scene that fits the budget's free room is uploaded whole now; one that does not, span by span as
    // frames need them, the nearest first.
    std::uint64_t whole = 0;
    for (std::uint32_t c = 0; c < spans_.size(); ++c) whole += span_bytes(c);
    if (eager && pool_->fits(whole)) {
      const std::uint64_t use = pool_->begin_use();
      for (std::uint32_t c = 0; c < spans_.size(); ++c) {
        upload_span(c);
        pool_->add(owner_, c, uploaded_bytes_[c], use);
      }
    }
  } catch (...) {
    release();  // the spans made so far: no destructor runs for a constructor that throws
    pool_->remove_owner(owner_);
    throw;
  }
}

std::uint64_t GpuScene::span_bytes(std::uint32_t c) const {
  const TextureSpan& t = layout_.texture_spans()[c];
  std::uint64_t bytes = 4 * t.words() + 4 * t.order_words;
  if (dataset_content_ == DatasetContent::StreamlineOrder) bytes += 4 * dataset_per_span_[c].size();
  if (dataset_content_ == DatasetContent::ViewOrder) bytes += 4 * t.segments;
  if (t.file < attributes_.size()) bytes += 8 * t.vertices;
  return bytes;
}

void GpuScene::upload_span(std::uint32_t c) {
  begin_upload(c);
  finish_upload(filling_.size() - 1);
}

void GpuScene::begin_parts(Filling& f) {
  const TextureSpan& c = layout_.texture_spans()[f.span];
  GpuTextureSpan& g = spans_[f.span];
  f.in_parts = true;
  g.words.begin_parts(GL_RGBA32UI, 4 * c.words());
  g.orders.begin_parts(GL_R32UI, 4 * c.order_words);
}

bool GpuScene::fill_next_part(Filling& f) {
  const TextureSpan& c = layout_.texture_spans()[f.span];
  const VxlFile& file = *files_[c.file];
  const std::uint32_t file_first = layout_.files()[c.file].voxel_first;
  GpuTextureSpan& g = spans_[f.span];
  if (!f.words_made) {
    VoxelScratch scratch;
    f.words_made = !g.words.fill_part([&](std::uint64_t first_byte, std::span<std::uint8_t> part) {
      const FillWindow<std::uint32_t> words{reinterpret_cast<std::uint32_t*>(part.data()), first_byte / 4,
                                            (first_byte + part.size()) / 4};
      for (std::uint32_t k = 0; k < c.voxel_count; ++k)
        fill_voxel_words(file, c.voxel_first + k, c.voxel_first + k - file_first, k, c, words, scratch);
    });
    return true;
  }
  return g.orders.fill_part([&](std::uint64_t first_byte, std::span<std::uint8_t> part) {
    const FillWindow<std::uint8_t> orders{part.data(), first_byte, first_byte + part.size()};
    for (std::uint32_t k = 0; k < c.voxel_count; ++k)
      copy_voxel_orders(file, c.voxel_first + k, c.voxel_first + k - file_first, c, orders);
  });
}

void GpuScene::drop_filling(std::size_t k) {
  const std::uint32_t ci = filling_[k].span;
  filling_.erase(filling_.begin() + static_cast<std::ptrdiff_t>(k));
  spans_[ci].words.destroy();
  spans_[ci].orders.destroy();
  gpu_bytes_ -= uploaded_bytes_[ci];
  pool_->remove(owner_, ci);
}

void GpuScene::begin_upload(std::uint32_t ci) {
  if constexpr (!kThreadsAvailable) {  // made here, part by part: nothing fills on other threads
    Filling f;
    f.span = ci;
    f.begun = UploadTally::Clock::now();
    begin_parts(f);
    filling_.push_back(std::move(f));
    uploaded_bytes_[ci] = span_bytes(ci);
    gpu_bytes_ += uploaded_bytes_[ci];
    return;
  }
  const TextureSpan& c = layout_.texture_spans()[ci];
  const VxlFile& file = *files_[c.file];
  const std::uint32_t file_first = layout_.files()[c.file].voxel_first;
  GpuTextureSpan& g = spans_[ci];
  // Filled in place in the GPU's buffers (on llvmpipe, host memory handed to the driver once filled) by other
  // threads: voxels fill disjoint ranges of both. The words fill while this thread has the order buffer made.
  Filling f;
  f.span = ci;
  f.begun = UploadTally::Clock::now();
  auto* words = static_cast<std::uint32_t*>(g.words.create_mapped(4 * c.words()));
  f.words = BackgroundTask<UploadTally::Clock::time_point>([this, &c, &file, file_first, words] {
    std::vector<VoxelScratch> scratch(resolve_threads(0));  // per thread
    const FillWindow<std::uint32_t> window{words, 0, c.words()};
    parallel_for(c.voxel_count, 0, [&](std::uint64_t k, unsigned t) {
      const std::uint32_t i = c.voxel_first + static_cast<std::uint32_t>(k);
      fill_voxel_words(file, i, i - file_first, static_cast<std::uint32_t>(k), c, window, scratch[t]);
    });
    // The last words of the tables' texel, which no voxel fills.
    std::fill(words + c.vertex_table_first() + c.vertices / SceneLayout::kGroup, words + c.words(), 0u);
    return UploadTally::Clock::now();
  });
  try {
    auto* orders = static_cast<std::uint8_t*>(g.orders.create_mapped(4 * c.order_words));
    f.orders = BackgroundTask<UploadTally::Clock::time_point>([this, &c, &file, file_first, orders] {
      const FillWindow<std::uint8_t> window{orders, 0, 4 * std::uint64_t(c.order_words)};
      parallel_for(c.voxel_count, 0, [&](std::uint64_t k, unsigned) {
        const std::uint32_t i = c.voxel_first + static_cast<std::uint32_t>(k);
        copy_voxel_orders(file, i, i - file_first, c, window);
      });
      return UploadTally::Clock::now();
    });
  } catch (...) {
    f.words = {};  // joined: nothing writes to the mapping after this
    g.words.finish_mapped(GL_RGBA32UI);
    g.words.destroy();
    throw;
  }
  filling_.push_back(std::move(f));
  uploaded_bytes_[ci] = span_bytes(ci);
  gpu_bytes_ += uploaded_bytes_[ci];
}

void GpuScene::finish_upload(std::size_t k) {
  Filling f = std::move(filling_[k]);
  filling_.erase(filling_.begin() + static_cast<std::ptrdiff_t>(k));
  const std::uint32_t ci = f.span;
  GpuTextureSpan& g = spans_[ci];
  std::exception_ptr error;
  // When the fills ended (made in parts on this thread: now, once the last part is made).
  UploadTally::Clock::time_point filled = f.begun;
  for (BackgroundTask<UploadTally::Clock::time_point>* task : {&f.words, &f.orders}) try {
      if (task->valid()) filled = std::max(filled, task->get());
    } catch (...) {
      if (!error) error = std::current_exception();
    }
  try {
    if (f.in_parts) {
      while (fill_next_part(f)) {
      }
      filled = UploadTally::Clock::now();
    }
    const auto handing = UploadTally::Clock::now();
    g.words.finish_mapped(GL_RGBA32UI);
    g.orders.finish_mapped(GL_R32UI);
    if (error) std::rethrow_exception(error);
    upload_extras(ci);
    // The fills' time, and this thread's handing the buffers to the driver; not the wait for this call.
    pool_->uploads().add(uploaded_bytes_[ci], f.begun, filled + (UploadTally::Clock::now() - handing));
  } catch (...) {
    g.words.destroy();
    g.orders.destroy();
    gpu_bytes_ -= uploaded_bytes_[ci];
    pool_->remove(owner_, ci);
    throw;
  }
  resident_[ci] = true;
  if (!checked_[ci]) {
    checked_[ci] = true;
    unchecked_.push_back(ci);
  }
}

std::optional<std::size_t> GpuScene::filling_index(std::uint32_t c) const {
  for (std::size_t k = 0; k < filling_.size(); ++k)
    if (filling_[k].span == c) return k;
  return std::nullopt;
}

void GpuScene::finish_uploads() {
  while (!filling_.empty()) finish_upload(0);
}

void GpuScene::check_uploaded(bool wait) {
  if (check_failure_) std::rethrow_exception(check_failure_);
  if constexpr (!kThreadsAvailable) {
    if (wait) check_some(std::numeric_limits<double>::infinity());
    return;
  }
  do {
    if (checks_.valid() && (wait || checks_.ready())) {
      try {
        checks_.get();
      } catch (...) {
        check_failure_ = std::current_exception();
        throw;
      }
    }
    start_checks();
  } while (wait && checks_.valid());
}

bool GpuScene::check_some(double max_ms) {
  if (check_failure_) std::rethrow_exception(check_failure_);
  checking_.insert(checking_.end(), unchecked_.begin(), unchecked_.end());
  unchecked_.clear();
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<std::uint8_t> scratch;
  try {
    for (; checking_span_ < checking_.size(); ++checking_span_, checking_voxel_ = 0) {
      const std::uint32_t ci = checking_[checking_span_];
      while (checking_voxel_ < layout_.texture_spans()[ci].voxel_count) {
        check_span_voxel(ci, checking_voxel_++, scratch);
        if (std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() >= max_ms)
          return false;
      }
    }
  } catch (...) {
    check_failure_ = std::current_exception();
    throw;
  }
  return true;
}

void GpuScene::start_checks() {
  if constexpr (!kThreadsAvailable) return;  // check_some runs them
  if (checks_.valid() || unchecked_.empty()) return;
  // Each span's voxels at its file's level; one core is left to the drawing thread.
  std::vector<std::uint32_t> spans = std::move(unchecked_);
  unchecked_.clear();
  checks_ = BackgroundTask<>([this, spans = std::move(spans)] {
    for (std::uint32_t ci : spans) {
      std::vector<std::vector<std::uint8_t>> scratch(resolve_threads(0));
      parallel_for(layout_.texture_spans()[ci].voxel_count, std::max(1u, resolve_threads(0) - 1),
                   [&](std::uint64_t k, unsigned t) { check_span_voxel(ci, k, scratch[t]); });
    }
  });
}

void GpuScene::check_span_voxel(std::uint32_t ci, std::uint64_t k, std::vector<std::uint8_t>& scratch) const {
  const TextureSpan& c = layout_.texture_spans()[ci];
  const FileLayout& f = layout_.files()[c.file];
  check_voxel_drawing(*files_[c.file], c.voxel_first + static_cast<std::uint32_t>(k) - f.voxel_first, f.level, scratch);
}

void GpuScene::upload_extras(std::uint32_t ci) {
  const TextureSpan& c = layout_.texture_spans()[ci];
  GpuTextureSpan& g = spans_[ci];
  g.dataset.destroy();
  g.attributes.destroy();
  if (dataset_content_ == DatasetContent::StreamlineOrder)
    g.dataset.create(GL_R32UI, dataset_per_span_[ci].data(), dataset_per_span_[ci].size() * 4);
  else  // the view order's entries are written every frame (upload_view_order)
    g.dataset.create(GL_R32UI, nullptr, dataset_content_ == DatasetContent::ViewOrder ? 4 * c.segments : 0);
  if (c.file >= attributes_.size()) {
    g.attributes.create(GL_RG32UI, nullptr, 0);
    return;
  }
  // Two words per vertex, each voxel's at its block's place in the span (scene_layout.h), made here so that
  // only what is uploaded is made.
  const VxlFile& file = *files_[c.file];
  const std::uint32_t file_first = layout_.files()[c.file].voxel_first;
  std::vector<std::uint32_t> padded(2 * c.vertices, 0);
  parallel_for(c.voxel_count, 0, [&](std::uint64_t k, unsigned) {
    const VoxelDrawInfo& d = layout_.voxels()[c.voxel_first + k];
    voxel_attributes(file, c.voxel_first + k - file_first, attributes_[c.file], d.vertex_count,
                     padded.data() + 2 * std::uint64_t(d.vertex_first));
  });
  g.attributes.create(GL_RG32UI, padded.data(), padded.size() * 4);
}

void GpuScene::evict(std::uint32_t c) {
  if (const std::optional<std::size_t> k = filling_index(c)) {
    // Its fill is joined (its failure dropped: nothing of it stays) before its buffers go.
    Filling f = std::move(filling_[*k]);
    filling_.erase(filling_.begin() + static_cast<std::ptrdiff_t>(*k));
    f = {};
    for (const auto& [buffer, format] :
         {std::pair{&spans_[c].words, GLenum(GL_RGBA32UI)}, std::pair{&spans_[c].orders, GLenum(GL_R32UI)}})
      try {
        buffer->finish_mapped(format);
      } catch (const std::exception&) {  // contents lost: they are dropped anyway
      }
  } else if (!resident_[c]) {
    return;
  }
  gpu_bytes_ -= uploaded_bytes_[c];
  spans_[c].words.destroy();
  spans_[c].orders.destroy();
  spans_[c].dataset.destroy();
  spans_[c].attributes.destroy();
  resident_[c] = false;
}

GpuScene::Residency GpuScene::make_resident(std::span<const std::uint32_t> needed, double max_ms, bool wait) {
  const auto start = std::chrono::steady_clock::now();
  auto elapsed_ms = [&] {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  };
  const std::uint64_t use = pool_->begin_use();
  for (std::uint32_t c : needed)
    if (resident_[c] || filling_index(c)) pool_->touch(owner_, c, use);
  Residency r;
  bool uploaded = false;
  for (std::uint32_t c : needed) {
    if (resident_[c]) continue;
    if (const std::optional<std::size_t> k = filling_index(c)) {
      if (wait) finish_upload(*k);
      continue;
    }
    // Waiting: at least one span, then until the time is up. Not waiting: a few spans filling at a time.
    if (wait ? uploaded && elapsed_ms() >= max_ms : filling_.size() >= kMaxFilling) {
      r.complete = false;
      r.out_of_time = true;
      break;
    }
    const std::uint64_t bytes = span_bytes(c);
    if (!pool_->reserve(bytes, use)) {
      r.complete = false;
      continue;
    }
    begin_upload(c);
    pool_->add(owner_, c, bytes, use);
    if (wait) finish_upload(filling_.size() - 1);
    uploaded = true;
  }
  if (!wait) {
    // The fills that end within the time, finished here (a millisecond's sleep between looks). Spans made in parts
    // get at least one part in all (not one each: a part is a long task on a web page), then as many as the time
    // allows; one that fails is dropped.
    const auto done = [](const BackgroundTask<UploadTally::Clock::time_point>& task) {
      return !task.valid() || task.ready();
    };
    bool part_made = false;
    const auto parts_left = [&](std::size_t k) {
      try {
        bool more = true;
        while (more && (!part_made || elapsed_ms() < max_ms)) {
          more = fill_next_part(filling_[k]);
          part_made = true;
        }
        return more;
      } catch (...) {
        drop_filling(k);
        throw;
      }
    };
    for (;;) {
      for (std::size_t k = 0; k < filling_.size();)
        if (filling_[k].in_parts ? !parts_left(k) : done(filling_[k].words) && done(filling_[k].orders))
          finish_upload(k);
        else
          ++k;
      if (filling_.empty() || elapsed_ms() >= max_ms) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    if (!filling_.empty()) {
      r.complete = false;
      r.out_of_time = true;
    }
  }
  return r;
}

void GpuScene::upload_resident_again() {
  // Only the dataset and attribute buffers change: the positions and orders stay. A span whose new size
  // does not fit the budget is evicted whole.
  finish_uploads();
  const std::uint64_t use = pool_->begin_use();
  for (std::uint32_t c = 0; c < spans_.size(); ++c)
    if (resident_[c]) pool_->touch(owner_, c, use);
  for (std::uint32_t c = 0; c < spans_.size(); ++c) {
    if (!resident_[c]) continue;
    pool_->remove(owner_, c);
    const std::uint64_t bytes = span_bytes(c);
    if (!pool_->reserve(bytes, use)) {
      evict(c);
      continue;
    }
    const auto begun = UploadTally::Clock::now();
    upload_extras(c);
    const TextureSpan& t = layout_.texture_spans()[c];
    if (const std::uint64_t extras = bytes - 4 * (t.words() + t.order_words); extras > 0)
      pool_->uploads().add(extras, begun, UploadTally::Clock::now());
    gpu_bytes_ += bytes - uploaded_bytes_[c];
    uploaded_bytes_[c] = bytes;
    pool_->add(owner_, c, bytes, use);
  }
}

GpuScene::~GpuScene() {
  release();
  pool_->remove_owner(owner_);
}

void GpuScene::release() {
  for (std::uint32_t c = 0; c < spans_.size(); ++c) {
    if (resident_[c] || filling_index(c)) pool_->remove(owner_, c);
    evict(c);
  }
}

void GpuScene::upload_attributes(std::vector<AttributeSource> per_file) {
  attributes_ = std::move(per_file);
  upload_resident_again();
}

void GpuScene::set_dataset_content(DatasetContent content) {
  dataset_content_ = content;
  if (content != DatasetContent::StreamlineOrder) {
    dataset_per_span_.clear();
    dataset_first_.clear();
    dataset_count_.clear();
  }
  upload_resident_again();
}

void GpuScene::prepare_view_order() {
  if (dataset_content_ != DatasetContent::ViewOrder) set_dataset_content(DatasetContent::ViewOrder);
}

void GpuScene::upload_view_order(const std::vector<const std::vector<std::uint32_t>*>& per_span,
                                 const std::vector<std::pair<std::uint64_t, std::uint64_t>>& ranges) {
  prepare_view_order();
  for (std::size_t c = 0; c < spans_.size(); ++c) {
    const auto [first, end] = ranges[c];
    if (first >= end || !resident_[c]) continue;
    spans_[c].dataset.update(4 * first, per_span[c]->data() + first, 4 * (end - first));
  }
}

const std::vector<std::int64_t>& GpuScene::dataset_first() {
  if (dataset_content_ != DatasetContent::StreamlineOrder) {
    dataset_first_.clear();
    dataset_count_.clear();
    // Walk the streamlines, file after file: every voxline contributes its segments, in order, to its
    // span's dataset array; consecutive segments in one span form one draw range.
    std::vector<std::vector<std::uint32_t>> per_span(layout_.texture_spans().size());
    std::int64_t run_span = -1;
    for (std::uint32_t fi = 0; fi < files_.size(); ++fi) {
      const std::uint32_t file_first = layout_.files()[fi].voxel_first;
      WalkCallbacks cb;
      const auto file_voxels = files_[fi]->voxels();
      cb.voxline = [&](const VoxlineVisit& v) {
        const std::uint32_t voxel = v.voxel;
        const std::uint64_t first_vertex = v.first_vertex;
        const std::uint32_t own = v.own_points;
        const bool connected = v.connected;
        const VoxelDrawInfo& d = layout_.voxels()[file_first + voxel];
        const std::uint32_t c = d.span;
        // The voxline's first vertex in its span's words; voxlines past the level's prefix are not drawn.
        const std::uint64_t in_block = first_vertex - file_voxels[voxel].vertex_first;
        if (in_block >= d.vertex_count) return;
        const std::uint64_t span_vertex = d.vertex_first + in_block;
        const std::uint64_t segments = own + (connected ? 1 : 0) - 1;
        if (segments == 0) return;
        auto& arr = per_span[c];
        if (run_span != c) {
          dataset_first_.push_back(layout_.dataset_id(c, arr.size()));
          dataset_count_.push_back(0);
          run_span = c;
        }
        for (std::uint64_t s = 0; s < segments; ++s) arr.push_back(static_cast<std::uint32_t>(span_vertex + s));
        dataset_count_.back() += static_cast<std::int32_t>(2 * segments);
      };
      walk_streamlines(*files_[fi], cb);
    }
    dataset_per_span_ = std::move(per_span);
    set_dataset_content(DatasetContent::StreamlineOrder);
  }
  return dataset_first_;
}

const std::vector<std::int32_t>& GpuScene::dataset_count() {
  dataset_first();
  return dataset_count_;
}

}  // namespace vxl
