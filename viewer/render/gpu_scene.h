// The GPU copy of a scene of one or more .vxl files, laid out as scene_layout.h describes: per texture span the
// file's bytes — each voxel's packed positions and its stored orders at the span's level, copied from the
// mapping into mapped GPU buffers by several threads, never re-encoded — with their voxels' decoding info and
// lookup tables, and — only when first needed — a dataset-order buffer and per-vertex values. Float32 files
// are packed on the way (the .vxl spec §5.4's encoding, their voxline ends from order 0). The vertex shader
// decodes what it reads and clamps every index to its buffer, so a damaged file draws wrong lines but never
// reads outside a buffer; the checks that tell a damaged file (format/vxl_draw_check.h) run beside the
// drawing, on other threads, for every span uploaded (check_uploaded).
//
// Spans are uploaded on demand within a GPU memory budget shared with the context's other scenes
// (gpu_memory_pool.h): as many as fit when the scene is made, then each frame the spans its voxels lie in
// (make_resident), the least recently used ones of any scene evicted to make room; a frame draws only
// voxels whose span is resident. Uploading a span again gives the same bytes, so an evicted and
// re-uploaded span draws the same picture.
//
// The dataset-order buffer holds either the streamline order (`unsorted`) or the view order the `segsort`
// mode writes every frame (segment_sort.h), never both: the GPU memory budget counts one.
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "format/base/parallel.h"
#include "format/vxl_file.h"
#include "viewer/render/gl_util.h"
#include "viewer/render/gpu_memory_pool.h"
#include "viewer/render/scene_layout.h"
#include "viewer/render/vertex_attributes.h"

namespace vxl {

struct GpuTextureSpan {
  gl::TextureBuffer words;    // GL_RGBA32UI: packed positions, voxel info, segment and vertex tables
  gl::TextureBuffer orders;   // GL_R16UI: K x S low halves, then K x W high halves
  gl::TextureBuffer dataset;  // GL_R32UI, span vertex indices: streamline or view order (empty until needed)
  gl::TextureBuffer
      attributes;  // GL_RG32UI, (value bits, streamline) per span vertex (empty until a colour mode needs it)
};

class GpuScene {
 public:
  // Needs a current GL context. max_texels 0: ask the driver (GL_MAX_TEXTURE_BUFFER_SIZE). level: the level
  // of detail uploaded (scene_layout.h). pool: the budget shared with other scenes (none: no budget). The
  // files must outlive the scene.
  // eager: upload the whole scene now when it fits the pool's free room (else spans come as frames need them).
  // file_levels: when not empty, each file's own level instead of `level` (SceneLayout's per-file levels).
  GpuScene(std::vector<const VxlFile*> files, std::uint64_t max_texels = 0, std::uint32_t level = 0,
           std::shared_ptr<GpuMemoryPool> pool = nullptr, bool eager = true,
           const std::vector<std::uint32_t>& file_levels = {});
  GpuScene(const VxlFile& file, std::uint64_t max_texels = 0, std::uint32_t level = 0)
      : GpuScene(std::vector<const VxlFile*>{&file}, max_texels, level) {}
  // The driver's GL_MAX_TEXTURE_BUFFER_SIZE (needs a current context).
  static std::uint64_t driver_limit();
  ~GpuScene();
  GpuScene(const GpuScene&) = delete;
  GpuScene& operator=(const GpuScene&) = delete;

  const SceneLayout& layout() const { return layout_; }
  // Span c's buffers (empty while it is not resident).
  const std::vector<GpuTextureSpan>& texture_spans() const { return spans_; }
  bool resident(std::uint32_t span) const { return resident_[span]; }
  // The GPU memory the resident spans take.
  std::uint64_t gpu_bytes() const { return gpu_bytes_; }
  const GpuMemoryPool& pool() const { return *pool_; }

  // Uploads the spans in `needed` that are not resident, in that order (the most important first), evicting
  // the least recently used spans of the pool's scenes that `needed` does not hold; a span that does not fit
  // stays out. Waiting (the default), with a time limit, stops once `max_ms` have passed (at least one span
  // is uploaded). Not waiting (`wait` false: a window at rest, whose event loop must not block on an upload),
  // starts the fills of up to kMaxFilling spans on other threads (without threads, a web page: makes their parts
  // on this thread, at least one in all, fill_next_part), and returns once those that end within
  // `max_ms` are resident: calling again finishes and starts more. A span still filling is not drawn.
  struct Residency {
    bool complete = true;      // every span of `needed` is resident
    bool out_of_time = false;  // stopped by the time limit or by fills still running: calling again uploads more
  };
  static constexpr std::size_t kMaxFilling = 2;
  Residency make_resident(std::span<const std::uint32_t> needed,
                          double max_ms = std::numeric_limits<double>::infinity(), bool wait = true);

  // Gives every span an attribute buffer of 2 words per vertex made from its file's `per_file` entry
  // (vertex_attributes.h) as the span is uploaded; an empty vector empties them. Resident spans are
  // uploaded again (their size changes).
  void upload_attributes(std::vector<AttributeSource> per_file);

  // Streamline-order draw ranges for the `unsorted` mode, built on first use (O(segments)), and again after
  // the view order replaced them; each span's dataset array joins its upload.
  const std::vector<std::int64_t>& dataset_first();
  const std::vector<std::int32_t>& dataset_count();

  // The `segsort` mode's view order: makes every span's dataset buffer S entries (its padded segment count,
  // the voxels' segment ranges of scene_layout.h) when it held something else, and uploads entries
  // [first, end) of per_span[c] into span c's. prepare_view_order() only makes the buffers.
  void prepare_view_order();
  void upload_view_order(const std::vector<const std::vector<std::uint32_t>*>& per_span,
                         const std::vector<std::pair<std::uint64_t, std::uint64_t>>& ranges);

  // The draw checks (format/vxl_draw_check.h) of the spans uploaded so far, run on other threads than the
  // caller's, one core left to it: starts them for the spans uploaded since the last call, and rethrows the
  // failure (vxl::Error, Input) of checks that have finished. With `wait`, returns once every span uploaded
  // is checked. A scene whose checks failed stays failed: every later call rethrows.
  // Without threads (the web viewer) nothing runs beside the drawing: without `wait` this only rethrows, and the
  // caller runs the checks a slice at a time between its frames (check_some).
  void check_uploaded(bool wait);
  // Starts the checks of the spans uploaded since they last started, unless some are still running.
  void start_checks();
  // Without threads: runs the checks of the spans uploaded so far for about `max_ms` (at least one voxel's), and
  // rethrows a failure as check_uploaded does. True once every span uploaded is checked.
  bool check_some(double max_ms);

 private:
  // The bytes span c takes on the GPU with its current attributes and dataset order.
  std::uint64_t span_bytes(std::uint32_t c) const;
  // A span's upload: its buffers made and mapped here, filled on other threads (begin_upload); joined,
  // unmapped and made resident (finish_upload of its entry in filling_). upload_span does both at once.
  void upload_span(std::uint32_t c);
  void begin_upload(std::uint32_t c);
  void finish_upload(std::size_t filling);
  void finish_uploads();  // every span filling
  std::optional<std::size_t> filling_index(std::uint32_t c) const;
  // Span c's dataset and attribute buffers, for the current dataset content and attributes.
  void upload_extras(std::uint32_t c);
  void evict(std::uint32_t c);
  // Remakes the resident spans' dataset and attribute buffers (after what they hold changed), within the
  // budget.
  void upload_resident_again();
  void release();
  // Elements [first, end) of a span's words or order bytes being filled, at `data`: the whole buffer, or one part
  // of it (TextureBuffer::fill_part); what falls outside is not written.
  template <typename T>
  struct FillWindow {
    T* data;
    std::uint64_t first, end;
    bool meets(std::uint64_t at, std::uint64_t n) const { return n > 0 && at < end && at + n > first; }
    void put(std::uint64_t at, const T* from, std::uint64_t n) const;
    void fill(std::uint64_t at, std::uint64_t n, T value) const;
  };
  // Voxel `voxel` of the scene (`local` in its file, `index` in its span): its block, info and table entries
  // into the span's words; its orders into the span's order bytes (as far as the windows reach).
  struct VoxelScratch {
    std::vector<std::uint8_t> is_start;
    std::vector<float> xyz;
    std::vector<std::uint32_t> block;
  };
  void fill_voxel_words(const VxlFile& file, std::uint32_t voxel, std::uint32_t local, std::uint32_t index,
                        const TextureSpan& span, const FillWindow<std::uint32_t>& words, VoxelScratch& scratch) const;
  void copy_voxel_orders(const VxlFile& file, std::uint32_t voxel, std::uint32_t local, const TextureSpan& span,
                         const FillWindow<std::uint8_t>& orders) const;
  struct Filling;
  // Without threads (a web page) a span's words, then its orders, are made a part at a time
  // (TextureBuffer::begin_parts), a part a call of fill_next_part (false once the last is made), so that a page
  // takes input between parts; make_resident without waiting makes parts for its time, at least one.
  void begin_parts(Filling& f);
  bool fill_next_part(Filling& f);
  // Forgets filling_[k] and what it made (a fill that failed).
  void drop_filling(std::size_t k);
  // The draw checks (format/vxl_draw_check.h) of voxel k of span ci, at its file's level.
  void check_span_voxel(std::uint32_t ci, std::uint64_t k, std::vector<std::uint8_t>& scratch) const;
  std::vector<const VxlFile*> files_;
  SceneLayout layout_;
  std::shared_ptr<GpuMemoryPool> pool_;
  std::uint32_t owner_ = 0;  // this scene in the pool
  std::vector<GpuTextureSpan> spans_;
  std::vector<bool> resident_;
  std::vector<std::uint64_t> uploaded_bytes_;  // per resident span, as the pool counts it
  std::uint64_t gpu_bytes_ = 0;
  std::vector<AttributeSource> attributes_;  // per file, as upload_attributes got them; empty: none
  enum class DatasetContent { Nothing, StreamlineOrder, ViewOrder };
  DatasetContent dataset_content_ = DatasetContent::Nothing;
  // Switches the dataset buffers' content: the resident spans are uploaded again with it.
  void set_dataset_content(DatasetContent content);
  std::vector<std::vector<std::uint32_t>> dataset_per_span_;  // StreamlineOrder: each span's array
  std::vector<std::int64_t> dataset_first_;
  std::vector<std::int32_t> dataset_count_;
  struct Filling {
    std::uint32_t span = 0;
    // Filling the span's mapped buffers; each returns when it ended, for the upload's time (upload_tally.h).
    BackgroundTask<UploadTally::Clock::time_point> words, orders;
    UploadTally::Clock::time_point begun;
    bool in_parts = false;    // made part by part on this thread instead (fill_next_part)
    bool words_made = false;  // in parts: the words are, the orders come next
  };
  std::vector<Filling> filling_;          // spans being uploaded (begun, not finished)
  std::vector<bool> checked_;             // per span: its draw checks have run or are running
  std::vector<std::uint32_t> unchecked_;  // spans uploaded since the checks last started
  std::exception_ptr check_failure_;      // the first failed check, rethrown by every check_uploaded
  // Without threads: the span check_some is in (an index into checking_) and its next voxel.
  std::vector<std::uint32_t> checking_;
  std::size_t checking_span_ = 0;
  std::uint64_t checking_voxel_ = 0;
  BackgroundTask<> checks_;  // last: joined first, while what it reads still exists
};

}  // namespace vxl
