// The web viewer's side in WebAssembly: a .vxl file's bytes (fetched by the page) opened by the same reader
// as voxview's, drawn by the same renderer into the page's canvas with WebGL2, with the same camera
// controller. The page (page/viewer.js) calls these functions through Emscripten's cwrap; each returns 0
// or an error whose message vw_error() gives.
//
// The first picture is drawn at the level of detail voxview's window draws its first at (first_picture_level:
// at most kFirstPictureSegments; a software WebGL draws a 144k-streamline file's 8M segments in about 9 s on
// 2 cores); vw_refine() then adds
// the full-detail renderer, which draws the view at rest while the first one keeps drawing it in motion. "Full
// detail" is the finest level whose GPU copy fits the page's GPU memory budget (vw_set_gpu_budget), as voxview's
// --gpu-memory chooses: level 0 when it fits.
// Its spans are uploaded a few per call of vw_upload, nearest the view first, so that the page's thread —
// WebAssembly here has no other — takes input between them: until the view's spans are all on the GPU, frames
// at rest come from the first picture's level, or from the finest coarser level fetched since. A file fetched
// by ranges fetches full detail span by span, the view's nearest first (vw_next_ranges), and frames at rest draw
// the spans in with that coarser level in place of the others, back to front in one order. For the same reason a frame
// at rest finer than the first picture is drawn in pieces (vw_draw_piece), and the draw checks run a slice a call
// (vw_check). A .vxlz is unpacked into a .vxl in memory first (web_package.h).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <iterator>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <malloc.h>

#include <emscripten/emscripten.h>
#include <emscripten/html5.h>
#include <nlohmann/json.hpp>

#include "format/base/error.h"
#include "format/base/memory_size.h"
#include "format/vxl_fetch_plan.h"
#include "format/vxl_file.h"
#include "format/vxl_level_image.h"
#include "format/vxl_levels.h"
#include "viewer/app/camera_controller.h"
#include "viewer/app/frame_budget.h"
#include "viewer/render/camera.h"
#include "viewer/render/colormap.h"
#include "viewer/render/render_settings.h"
#include "viewer/render/renderer.h"
#include "viewer/render/scene_framing.h"
#include "viewer/render/scene_layout.h"
#include "viewer/web/web_package.h"

namespace vxl::web {
namespace {

// The modes WebGL2 can draw: exact needs storage buffers and compute shaders, segsort rewrites buffer
// textures in place; WebGL2 has neither.
bool drawable_on_the_web(RenderMode mode) { return mode != RenderMode::Exact && mode != RenderMode::Segsort; }

struct Viewer {
  std::optional<VxlFile> file;
  std::unique_ptr<Renderer> quick;  // at the first picture's level; null when that is full detail
  // A file fetched by ranges, at rest until full detail is ready: the finest level fetched since (vw_show_level).
  std::unique_ptr<Renderer> interim;
  std::unique_ptr<Renderer> full;  // full detail: made by vw_open when it is the first picture's, else by vw_refine
  std::unique_ptr<app::CameraController> controller;
  RenderSettings settings = [] {
    RenderSettings s;
    s.opacity = kDefaultLineOpacity;
    return s;
  }();
  int width = 1, height = 1;
  // The file's level 0 is level `level_of_whole` of a larger whole (a package's first look while the rest arrives,
  // vw_set "package-level"; a level image of a file too large for the page, vw_open_image): drawn with that
  // level's opacity, so that it looks as bright as the whole.
  std::uint32_t level_of_whole = 0;
  // A level image (vxl_level_image.h): where its vertex and order bytes lie in the file fetched, and the file's META.
  bool image = false;
  std::vector<ImagePlacement> image_data;
  MetaSection file_meta{};
  std::uint64_t gpu_budget = 0;   // bytes; 0: none (vw_set_gpu_budget)
  std::uint32_t full_level = 0;   // the level drawn at rest: the finest within gpu_budget
  std::uint32_t first_level = 0;  // the first picture's level of detail
  // A file fetched by ranges whose full-detail renderer was made before that level's bytes were all in: its spans
  // are uploaded as their bytes arrive (span_in), the view's nearest first (vw_next_ranges), and a frame at rest
  // draws those resident with the coarser renderer standing in for the others (Renderer::begin_pieces).
  bool spans_arriving = false;
  std::vector<bool> span_in;                  // per full-detail span: every byte it reads is in the buffer
  std::uint64_t drawn_uploaded = 0;           // the full-detail renderer's GPU bytes when the last frame was drawn
  bool drawn_mixed = false;                   // the last frame at rest was drawn with a stand-in
  bool drawn_full = false;                    // the last frame at rest was drawn by the full-detail renderer alone
  std::vector<std::uint64_t> level_segments;  // the file's segments at each level
  // A file fetched by ranges (vw_plan_open): the bytes its buffer holds so far, sorted and disjoint, and those the
  // page was last asked to fetch (held once vw_arrived says they are in).
  std::vector<ByteRange> held, asked;
  // A picture at rest drawn in pieces (vw_draw_piece), copied to the canvas once complete: `piecing` is the
  // renderer drawing it (null when none is under way).
  gl::RenderTarget piece_target;
  Renderer* piecing = nullptr;
};

Viewer& viewer() {
  static Viewer v;
  return v;
}

// Drops the file and its renderers (the GL objects first, the bytes they were made from last).
void close(Viewer& v) {
  v.piecing = nullptr;
  v.piece_target.destroy();
  v.controller.reset();
  v.quick.reset();
  v.interim.reset();
  v.full.reset();
  v.file.reset();
  v.held.clear();
  v.asked.clear();
  v.level_segments.clear();
  v.spans_arriving = false;
  v.span_in.clear();
  v.drawn_uploaded = 0;
  v.drawn_mixed = false;
  v.drawn_full = false;
  v.level_of_whole = 0;
  v.image = false;
  v.image_data.clear();
}

// Whether the buffer holds the whole file (fetched whole, or every range fetched).
bool complete(const Viewer& v) {
  return v.file && v.held.size() == 1 && v.held[0].begin == 0 && v.held[0].end >= v.file->bytes().size();
}

// What vw_plan_open named (with the first bytes): what a buffer given to vw_open without `whole` holds.
std::vector<ByteRange>& planned_ranges() {
  static std::vector<ByteRange> ranges;
  return ranges;
}

// `ranges` of the open file as the page fetches them: of a level image, where its bytes lie in the file fetched,
// merged where less than `gap` apart.
std::vector<ByteRange> ranges_to_fetch(const Viewer& v, std::span<const ByteRange> ranges, std::uint64_t gap) {
  return v.image ? source_ranges(v.image_data, ranges, gap) : std::vector<ByteRange>(ranges.begin(), ranges.end());
}

// JSON [[begin, end], ...] for the page.
nlohmann::json ranges_json(std::span<const ByteRange> ranges) {
  nlohmann::json j = nlohmann::json::array();
  for (const ByteRange& r : ranges) j.push_back({r.begin, r.end});
  return j;
}

// An error about a level image's bytes, said of the file fetched: the byte the image's came from, else the image's
// own (a table it rewrote), and the image's voxel numbers named as such.
std::string said_of_the_file(const Viewer& v, const Error& e) {
  if (!v.image || !e.offset() || e.file().empty()) return e.what();
  const std::uint64_t at = *e.offset();
  const std::string image = "level " + std::to_string(v.level_of_whole) + " image";
  const auto p = std::partition_point(v.image_data.begin(), v.image_data.end(),
                                      [&](const ImagePlacement& q) { return q.at + q.size <= at; });
  if (p != v.image_data.end() && p->at <= at)
    return e.file() + ": at byte " + std::to_string(p->source + (at - p->at)) + ": " + e.reason() + " (voxels as the " +
           image + " numbers them)";
  return e.file() + ": at byte " + std::to_string(at) + " of its " + image + ": " + e.reason();
}

// Closes `v` after its file failed to open or show (inside a catch), the error said of the file first: closing
// forgets the image's placements.
[[noreturn]] void close_and_rethrow(Viewer& v) {
  try {
    throw;
  } catch (const Error& e) {
    Error said(e.kind(), "", std::nullopt, said_of_the_file(v, e));
    close(v);
    throw said;
  } catch (...) {
    close(v);
    throw;
  }
}

std::string& last_error() {
  static std::string e;
  return e;
}

// Runs `fn`, turning an exception into an error code and vw_error()'s message.
template <typename Fn>
int guarded(Fn&& fn) {
  try {
    fn();
    last_error().clear();
    return 0;
  } catch (const Error& e) {
    last_error() = said_of_the_file(viewer(), e);
    return static_cast<int>(e.kind());
  } catch (const std::exception& e) {
    last_error() = e.what();
    return 70;
  }
}

void make_context() {
  static EMSCRIPTEN_WEBGL_CONTEXT_HANDLE context = 0;
  if (context > 0) return;
  EmscriptenWebGLContextAttributes a;
  emscripten_webgl_init_context_attributes(&a);
  a.majorVersion = 2;
  a.minorVersion = 0;
  a.alpha = false;      // the picture is opaque over its background, as voxview's PNG
  a.antialias = false;  // as voxview's offscreen picture
  a.depth = true;
  a.preserveDrawingBuffer = true;  // the screenshot reads the canvas after the frame
  context = emscripten_webgl_create_context("#canvas", &a);
  if (context <= 0) throw std::runtime_error("this browser offers no WebGL2 context");
  emscripten_webgl_make_context_current(context);
  // The wboit and additive modes render to float targets.
  emscripten_webgl_enable_extension(context, "EXT_color_buffer_float");
}

// The camera a file opens with: the default view, framing the streamlines at full detail (as voxview's).
Camera home_camera(const VxlFile& file, double aspect) {
  Camera c;
  c.azimuth_deg = kDefaultView[0];
  c.elevation_deg = kDefaultView[1];
  c.frame_points(framing_points(SceneLayout(file, gl::max_buffer_texels(), 0)), aspect);
  return c;
}

// How long a piece of a picture at rest draws, GPU work included (Renderer::draw_piece): the page takes input
// between pieces, and the browser calls a task of 50 ms or more a long one.
constexpr double kPieceMs = 40;

// Draws the next piece of the picture under way; once it is complete, copies it to the canvas. True then.
bool draw_next_piece(Viewer& v) {
  const bool complete = v.piecing->draw_piece(kPieceMs);
  v.piecing->check_uploaded(false);
  if (!complete) return false;
  v.piecing = nullptr;
  glBindFramebuffer(GL_READ_FRAMEBUFFER, v.piece_target.fbo);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
  glBlitFramebuffer(0, 0, v.width, v.height, 0, 0, v.width, v.height, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  return true;
}

// What upload_full found.
enum class FullDetail { Ready, Uploading, WaitingForBytes };

// The full-detail spans the view needs, the nearest first.
std::vector<std::uint32_t> full_spans_for_view(const Viewer& v) {
  return v.full->spans_for(v.controller->camera(), double(v.width) / v.height);
}

// Whether those spans are all on the GPU.
bool all_resident(const Viewer& v, const std::vector<std::uint32_t>& spans) {
  return std::all_of(spans.begin(), spans.end(), [&](std::uint32_t c) { return v.full->span_resident(c); });
}

// Uploads a few more of the full-detail spans the view needs (the nearest first) whose bytes are in.
FullDetail upload_full(Viewer& v) {
  const std::vector<std::uint32_t> needed = full_spans_for_view(v);
  if (!v.spans_arriving) return v.full->upload_spans(needed, 0.0) ? FullDetail::Ready : FullDetail::Uploading;
  std::vector<std::uint32_t> in;  // those whose bytes are in
  std::copy_if(needed.begin(), needed.end(), std::back_inserter(in), [&](std::uint32_t c) { return v.span_in[c]; });
  const bool done = v.full->upload_spans(in, 0.0);
  return all_resident(v, needed) ? FullDetail::Ready : done ? FullDetail::WaitingForBytes : FullDetail::Uploading;
}

// The renderer a frame is drawn with: the first picture's while moving or while full detail is not ready for
// the view (the finest coarser level fetched meanwhile, at rest).
Renderer* renderer_for(Viewer& v, bool moving) {
  if (!v.quick) return v.full.get();
  if (moving) return v.quick.get();
  // Whether full detail is ready; a frame uploads nothing: it would wait, in its first call that needs the GPU (a
  // framebuffer's check), for the GPU process to take the upload. vw_upload uploads, a part a call, and the page waits
  // for the GPU between calls.
  if (!v.full || !all_resident(v, full_spans_for_view(v))) return v.interim ? v.interim.get() : v.quick.get();
  if (v.piecing == v.interim.get()) v.piecing = nullptr;
  v.interim.reset();  // full detail is on the GPU for this view
  return v.full.get();
}

// Marks the full-detail spans whose bytes are all in the buffer now.
void note_spans_in(Viewer& v) {
  if (!v.full || !v.spans_arriving) return;
  const std::vector<TextureSpan>& spans = v.full->layout().texture_spans();
  v.span_in.resize(spans.size(), false);
  for (std::uint32_t c = 0; c < spans.size(); ++c)
    if (!v.span_in[c])
      v.span_in[c] =
          ranges_held(ranges_of_voxels(*v.file, v.full_level, spans[c].voxel_first, spans[c].voxel_count, 0), v.held);
}

// The full-detail spans in the order their bytes are fetched: those the view needs, the nearest first, then the
// others by the distance of their nearest voxel to the eye; with that distance (mm) and whether the view needs it.
struct SpanToFetch {
  std::uint32_t span;
  double distance;
  bool in_view;
};
std::vector<SpanToFetch> spans_to_fetch(const Viewer& v) {
  const Camera& camera = v.controller->camera();
  const SceneLayout& layout = v.full->layout();
  std::vector<double> nearest(layout.texture_spans().size(), std::numeric_limits<double>::infinity());
  for (const VoxelDrawInfo& voxel : layout.voxels())
    nearest[voxel.span] = std::min(nearest[voxel.span], glm::length(voxel.center - camera.eye()));
  std::vector<SpanToFetch> order;
  std::vector<bool> listed(nearest.size(), false);
  for (const std::uint32_t c : v.full->spans_for(camera, double(v.width) / v.height)) {
    order.push_back({c, nearest[c], true});
    listed[c] = true;
  }
  const std::size_t in_view = order.size();
  for (std::uint32_t c = 0; c < nearest.size(); ++c)
    if (!listed[c]) order.push_back({c, nearest[c], false});
  std::stable_sort(order.begin() + static_cast<std::ptrdiff_t>(in_view), order.end(),
                   [](const SpanToFetch& a, const SpanToFetch& b) { return a.distance < b.distance; });
  return order;
}

// Whether the buffer holds every byte `level` draws from (ranges_of_level).
bool holds_level(const Viewer& v, std::uint32_t level) {
  const std::vector<ByteRange> missing = ranges_missing(v.held, v.file->bytes().size());
  return ranges_intersection(ranges_of_level(*v.file, level, 0), missing).empty();
}

// Opens `bytes` into `v` (closed): the file, the level drawn at rest (the finest within the GPU budget) and the
// first picture's (nothing drawn yet). A level's GPU bytes do not depend on how its voxels are cut into spans (each
// span rounds its words to 4), so the level is chosen here as for one span, without the context's texture limit:
// a context made before the first level is fetched delayed the first picture (0.4 s on SwiftShader).
void open_file(Viewer& v, MappedFile bytes, int width, int height) {
  v.file.emplace(VxlFile::open(std::move(bytes)));
  v.width = std::max(width, 1);
  v.height = std::max(height, 1);
  const std::vector<const VxlFile*> files{&*v.file};
  v.level_segments = app::level_segments(files);
  constexpr std::uint64_t kOneSpan = std::numeric_limits<std::uint64_t>::max();
  v.full_level = v.gpu_budget > 0 ? SceneLayout::finest_level_within(files, kOneSpan, v.gpu_budget) : 0;
  v.first_level = app::first_picture_level(v.level_segments, v.full_level);
}

// The first picture's renderer and the camera: the file's bytes of that level are in (all of them, or those of
// ranges_of_level).
void show_file(Viewer& v) {
  make_context();
  const std::vector<const VxlFile*> files{&*v.file};
  (v.first_level > v.full_level ? v.quick : v.full) = std::make_unique<Renderer>(files, 0, v.first_level);
  const Camera home = home_camera(*v.file, double(v.width) / v.height);
  const Renderer& any = *renderer_for(v, false);
  const glm::dvec3 extent = any.bounds_max() - any.bounds_min();
  v.controller = std::make_unique<app::CameraController>(home, 0.5 * glm::length(extent));
  v.controller->set_window_height(v.height);
}

// Why a level image cannot draw `what` (it reads the streamline tables, which the image has not).
Error not_in_image(const Viewer& v, const std::string& what) {
  return Error(ErrorKind::Unsupported, v.file->path(), std::nullopt,
               what + " reads the streamline tables, which a file this large leaves out in the page (it draws level " +
                   std::to_string(v.level_of_whole) + " and coarser, sorted by voxels)");
}

// What the renderers have on the GPU.
std::uint64_t gpu_bytes(const Viewer& v) {
  std::uint64_t bytes = 0;
  for (const Renderer* r : {v.quick.get(), v.interim.get(), v.full.get()})
    if (r) bytes += r->gpu_bytes();
  return bytes;
}

// vw_info's JSON: the file, the renderers, and the modes the page may offer.
void describe(Viewer& v, nlohmann::json& j) {
  if (v.controller) {  // open
    const auto& m = v.file->meta();
    j["streamlines"] = m.streamline_count;
    j["points"] = m.point_count;
    j["vertices"] = m.vertex_count;
    j["voxels"] = v.file->voxels().size();
    j["bytes"] = v.file->bytes().size();
    j["gpu_bytes"] = gpu_bytes(v);
    j["first_level"] = v.quick ? v.quick->layout().level() : v.full_level;
    j["full_level"] = v.full_level;
    for (const RenderModeInfo& m : render_modes())
      if (m.mode == v.settings.mode) j["mode"] = m.name;  // what frames are drawn in now
    j["gpu_budget"] = v.gpu_budget;
    j["level_segments"] = v.level_segments;
    j["full_detail"] = v.full != nullptr;
    const Renderer& r = v.full ? *v.full : *v.quick;
    // How much of full detail is on the GPU, of the most it can take.
    j["full_uploaded"] = v.full ? v.full->gpu_bytes() : 0;
    j["full_bytes"] = v.full ? v.full->layout().upload_bytes() : 0;
    // Full detail's spans, those whose bytes are in (all, unless they arrive after it was made), and whether the
    // last frame at rest drew some of them with a coarser level in place of the others.
    const std::size_t spans = v.full ? v.full->layout().texture_spans().size() : 0;
    j["full_spans"] = spans;
    j["full_spans_in"] =
        v.spans_arriving ? static_cast<std::size_t>(std::count(v.span_in.begin(), v.span_in.end(), true)) : spans;
    j["mixed"] = v.drawn_mixed;
    // A level image: its level 0 is the file's level_offset, the file's own counts beside the image's.
    j["image"] = v.image;
    j["level_offset"] = v.image ? v.level_of_whole : 0;
    if (v.image) {
      j["streamlines"] = v.file_meta.streamline_count;
      j["file_vertices"] = v.file_meta.vertex_count;
    }
    j["values"] = r.value_set_names();
    nlohmann::json groups = nlohmann::json::array();
    for (std::size_t g = 0; g < r.groups().groups().size(); ++g) {
      const SceneGroup& group = r.groups().groups()[g];
      const glm::vec4 c = v.settings.group_color(group.name, g);
      groups.push_back({{"name", group.name}, {"streamlines", group.streamlines}, {"color", {c.r, c.g, c.b}}});
    }
    j["groups"] = groups;
    // What colouring by value shows: the set, its range and the colour map's samples (for the colour bar).
    const auto range = r.scalar_range(v.settings);
    nlohmann::json samples = nlohmann::json::array();
    for (const glm::vec3& c : colormap_samples(v.settings.colormap)) samples.push_back({c.r, c.g, c.b});
    j["scalar"] = {{"name", r.scalar_name(v.settings)}, {"range", {range[0], range[1]}}, {"samples", samples}};
  }
  nlohmann::json modes = nlohmann::json::array();
  for (const RenderModeInfo& m : render_modes())
    if (drawable_on_the_web(m.mode) && !(v.image && m.mode == RenderMode::Unsorted))
      modes.push_back({{"name", m.name}, {"description", m.description}});
  j["modes"] = modes;
}

}  // namespace
}  // namespace vxl::web

using vxl::web::guarded;
using vxl::web::viewer;

extern "C" {

// Takes the file's bytes (from malloc; freed by the viewer, also on failure) and opens them; the canvas is
// then width x height pixels. A .vxlz package (whole) is unpacked first, and its bytes freed once it is. `whole`: the
// buffer holds the whole file, and the first picture's renderer is made; else it holds what vw_plan_open named, and
// vw_level_ranges says what the first picture needs before vw_show makes it.
EMSCRIPTEN_KEEPALIVE int vw_open(std::uint8_t* bytes, double size, const char* name, int width, int height, int whole) {
  if (!(size >= 0 && size <= double(std::numeric_limits<std::size_t>::max()))) {
    std::free(bytes);
    vxl::web::last_error() = std::string(name) + ": too large for the web viewer";
    return static_cast<int>(vxl::ErrorKind::Input);
  }
  auto file = vxl::MappedFile::adopt(name, bytes, static_cast<std::size_t>(size));
  return guarded([&] {
    auto& v = viewer();
    vxl::web::close(v);
    try {
      if (whole && vxl::web::is_package(file.bytes())) file = vxl::web::unpack_package(std::move(file), name);
      vxl::web::open_file(v, std::move(file), width, height);
      if (whole) {
        v.held = {{0, v.file->bytes().size()}};  // an unpacked package's, not the package's
        vxl::web::show_file(v);
      } else {
        v.held = vxl::web::planned_ranges();
      }
    } catch (...) {
      vxl::web::close(v);  // nothing half open
      throw;
    }
  });
}

// Fetching by ranges. `first`: the file's first `first_size` bytes (at least vxl::kSectionTableBytesMax, or the
// whole file if shorter) of `file_size`. What the reader needs to open the file, as JSON [[begin, end], ...]
// (end exclusive), or {"error": ...}; the page fetches them into a buffer of the file's size, then vw_open. A file
// larger than `max_bytes` (the most of it the page may hold) is drawn from a level image (vxl_level_image.h): then
// {"image": [[begin, end], ...], "bytes": N}, the tables the image is made from, which the page fetches into a
// buffer of N bytes one after another, then vw_open_image.
EMSCRIPTEN_KEEPALIVE const char* vw_plan_open(const std::uint8_t* first, double first_size, double file_size,
                                              const char* name, double max_bytes) {
  static std::string text;
  nlohmann::json j = nlohmann::json::array();
  std::vector<vxl::ByteRange> ranges;
  const std::span<const std::uint8_t> first_bytes{first, static_cast<std::size_t>(first_size)};
  const bool image = file_size > max_bytes;
  const int error = guarded([&] {
    ranges = image ? vxl::ranges_for_level_image(name, first_bytes, static_cast<std::uint64_t>(file_size))
                   : vxl::ranges_to_open(name, first_bytes, static_cast<std::uint64_t>(file_size));
  });
  if (error != 0) {
    j = {{"error", vxl::web::last_error()}};
  } else if (image) {
    std::uint64_t bytes = 0;
    nlohmann::json tables = nlohmann::json::array();
    for (const vxl::ByteRange& r : ranges) {
      tables.push_back({r.begin, r.end});
      bytes += r.end - r.begin;
    }
    j = {{"image", tables}, {"bytes", bytes}};
  } else {
    const auto held = static_cast<std::uint64_t>(first_size);
    for (const vxl::ByteRange& r : ranges)
      if (r.end > held) j.push_back({std::max(r.begin, held), r.end});
    ranges.push_back({0, held});
    vxl::web::planned_ranges() = vxl::merge_ranges(std::move(ranges), 0);
  }
  text = j.dump();
  return text.c_str();
}

// Opens a level image (vw_plan_open's "image"): the finest level of the file, of `file_size` bytes, whose image
// takes at most `max_bytes`, made from `tables` (from malloc, freed by the viewer, also on failure; the bytes of
// vw_plan_open's ranges one after another). Its bytes are then fetched as a file's (vw_level_ranges, ...), placed in
// it as vw_placement says.
EMSCRIPTEN_KEEPALIVE int vw_open_image(std::uint8_t* tables, double size, const char* name, double file_size,
                                       double max_bytes, int width, int height) {
  auto gathered = vxl::MappedFile::adopt(name, tables, static_cast<std::size_t>(size));
  return guarded([&] {
    auto& v = viewer();
    vxl::web::close(v);
    try {
      vxl::LevelImage image = vxl::make_level_image(name, gathered.bytes(), static_cast<std::uint64_t>(file_size),
                                                    static_cast<std::uint64_t>(max_bytes));
      { const vxl::MappedFile done = std::move(gathered); }  // the tables' bytes, before the image's are fetched
      v.image = true;  // before the image opens: its errors are then said of the file
      v.image_data = std::move(image.data);
      v.file_meta = image.file_meta;
      v.level_of_whole = image.level;
      vxl::web::open_file(v, std::move(image.bytes), width, height);
      v.held = std::move(image.written);
    } catch (...) {
      vxl::web::close_and_rethrow(v);
    }
  });
}

// Where the ranges the page fetches go in the open file's buffer (vw_file_pointer): for a level image, JSON [[begin,
// end, at], ...], the file's bytes [begin, end) to `at` in the image, sorted; [] when the buffer is the file's own.
EMSCRIPTEN_KEEPALIVE const char* vw_placement() {
  static std::string text;
  nlohmann::json j = nlohmann::json::array();
  if (guarded([&] {
        for (const vxl::ImagePlacement& p : viewer().image_data) j.push_back({p.source, p.source + p.size, p.at});
      }) != 0)
    j = {{"error", vxl::web::last_error()}};
  text = j.dump();
  return text.c_str();
}

// The open file's buffer (its address in the WebAssembly memory), which the page fills as ranges arrive.
EMSCRIPTEN_KEEPALIVE double vw_file_pointer() {
  const auto& v = viewer();
  return v.file ? double(reinterpret_cast<std::uintptr_t>(v.file->bytes().data())) : 0;
}

// The ranges level `level` needs (the first picture's: -1) that the buffer does not hold yet (JSON, as
// vw_plan_open's); vw_arrived once they are in. `gap`: ranges closer than this are fetched as one.
EMSCRIPTEN_KEEPALIVE const char* vw_level_ranges(int level, double gap) {
  static std::string text;
  auto& v = viewer();
  nlohmann::json j = nlohmann::json::array();
  if (v.file) {
    const std::uint32_t wanted_level =
        level < 0 ? v.first_level : std::min(static_cast<std::uint32_t>(level), v.file->level_count() - 1);
    const std::vector<vxl::ByteRange> wanted =
        vxl::ranges_of_level(*v.file, wanted_level, static_cast<std::uint64_t>(gap));
    v.asked = vxl::ranges_intersection(wanted, vxl::ranges_missing(v.held, v.file->bytes().size()));
    j = vxl::web::ranges_json(vxl::web::ranges_to_fetch(v, v.asked, static_cast<std::uint64_t>(gap)));
  }
  text = j.dump();
  return text.c_str();
}

// The rest of the file (JSON ranges of at most `piece` bytes each; vw_arrived once they are in): full detail,
// the unsorted mode and colouring by value or group read it.
EMSCRIPTEN_KEEPALIVE const char* vw_missing_ranges(double piece) {
  static std::string text;
  auto& v = viewer();
  nlohmann::json j = nlohmann::json::array();
  if (v.file) {
    const auto step = std::max<std::uint64_t>(1, static_cast<std::uint64_t>(piece));
    v.asked = vxl::ranges_missing(v.held, v.file->bytes().size());
    for (const vxl::ByteRange& r : vxl::web::ranges_to_fetch(v, v.asked, 0))
      for (std::uint64_t at = r.begin; at < r.end; at += step) j.push_back({at, std::min(r.end, at + step)});
  }
  text = j.dump();
  return text.c_str();
}

// Draws frames at rest at `level` (finer than the first picture's, coarser than full detail) once its ranges are
// in (vw_level_ranges), until full detail is ready; frames in motion stay at the first picture's level.
EMSCRIPTEN_KEEPALIVE int vw_show_level(int level) {
  return guarded([&] {
    auto& v = viewer();
    if (!v.controller || !v.quick) throw std::runtime_error("no first picture to refine");
    if (level <= 0 || static_cast<std::uint32_t>(level) <= v.full_level ||
        static_cast<std::uint32_t>(level) >= v.first_level)
      throw std::runtime_error("not a level between");
    // Its pieces end with it, and so do full detail's where it stands in for spans still coming.
    if (v.piecing == v.interim.get() || v.piecing == v.full.get()) v.piecing = nullptr;
    v.interim.reset();  // its GPU memory before the next one's
    v.interim = std::make_unique<vxl::Renderer>(std::vector<const vxl::VxlFile*>{&*v.file}, 0, level);
  });
}

// The ranges vw_level_ranges or vw_missing_ranges gave last are in the buffer.
EMSCRIPTEN_KEEPALIVE void vw_arrived() {
  auto& v = viewer();
  v.asked.insert(v.asked.end(), v.held.begin(), v.held.end());
  v.held = vxl::merge_ranges(std::move(v.asked), 0);
  v.asked.clear();
  vxl::web::note_spans_in(v);
}

// The next full-detail spans to fetch (vw_refine made the renderer before their bytes were in): the view's, the
// nearest first, then the others, nearest first; at least one span, and more while their bytes stay under `batch`.
// JSON {"ranges": [[begin, end], ...] (vw_arrived once they are in; ranges closer than `gap` merged), "spans":
// [{"span", "distance" (mm, its nearest voxel's from the eye), "in_view"}, ...]}; no ranges once every span is in.
EMSCRIPTEN_KEEPALIVE const char* vw_next_ranges(double gap, double batch) {
  static std::string text;
  auto& v = viewer();
  nlohmann::json spans = nlohmann::json::array(), ranges = nlohmann::json::array();
  if (v.full && v.controller && v.spans_arriving) {
    const std::vector<vxl::ByteRange> missing = vxl::ranges_missing(v.held, v.file->bytes().size());
    std::vector<vxl::ByteRange> wanted;
    std::uint64_t bytes = 0;
    for (const vxl::web::SpanToFetch& next : vxl::web::spans_to_fetch(v)) {
      if (v.span_in[next.span]) continue;
      const vxl::TextureSpan& c = v.full->layout().texture_spans()[next.span];
      for (const vxl::ByteRange& r : vxl::ranges_intersection(
               vxl::ranges_of_voxels(*v.file, v.full_level, c.voxel_first, c.voxel_count, 0), missing)) {
        wanted.push_back(r);
        bytes += r.end - r.begin;
      }
      spans.push_back({{"span", next.span}, {"distance", next.distance}, {"in_view", next.in_view}});
      if (double(bytes) >= batch) break;
    }
    v.asked = vxl::ranges_intersection(vxl::merge_ranges(std::move(wanted), static_cast<std::uint64_t>(gap)), missing);
    ranges = vxl::web::ranges_json(vxl::web::ranges_to_fetch(v, v.asked, static_cast<std::uint64_t>(gap)));
  }
  text = nlohmann::json{{"ranges", ranges}, {"spans", spans}}.dump();
  return text.c_str();
}

// Makes the first picture's renderer once its ranges are in (vw_open without `whole`).
EMSCRIPTEN_KEEPALIVE int vw_show() {
  return guarded([&] {
    auto& v = viewer();
    if (!v.file) throw std::runtime_error("no file is open");
    try {
      vxl::web::show_file(v);
    } catch (...) {
      vxl::web::close_and_rethrow(v);  // the first level's draw checks name the file's byte
    }
  });
}

EMSCRIPTEN_KEEPALIVE const char* vw_error() { return vxl::web::last_error().c_str(); }

// The largest file the page may hand to vw_open (a double: JavaScript's number, past a 32-bit integer's range).
EMSCRIPTEN_KEEPALIVE double vw_max_file_bytes() { return double(vxl::kWebMaxFileBytes); }

// What the page shows about the file: counts and the modes it can draw, as JSON ({"error": …} if that fails).
EMSCRIPTEN_KEEPALIVE const char* vw_info() {
  static std::string text;
  nlohmann::json j;
  auto& v = viewer();
  if (guarded([&] { vxl::web::describe(v, j); }) != 0) j = {{"error", vxl::web::last_error()}};
  text = j.dump();
  return text.c_str();
}

// The memory's use, for benchmarks (a walk of malloc's heap: not for every step): JSON {"in_use": malloc's bytes in
// use now, "peak": the most its heap has held, which the memory, never shrinking, keeps, "gpu_bytes": what the
// renderers have on the GPU, which the page draws from}.
EMSCRIPTEN_KEEPALIVE const char* vw_memory() {
  static std::string text;
  const struct mallinfo heap = mallinfo();
  text = nlohmann::json{{"in_use", static_cast<std::uint64_t>(heap.uordblks)},
                        {"peak", static_cast<std::uint64_t>(heap.usmblks)},
                        {"gpu_bytes", vxl::web::gpu_bytes(viewer())}}
             .dump();
  return text.c_str();
}

// One setting by name, as voxview's options spell them: mode, color, opacity, fixed-color (hex), background
// (hex), scalar (a value set's name), colormap, view ("AZ,EL" or a standard view's name), lighting (0/1); and the
// page's package-level (the open file is that level of a package alone, web_package.h's first look; 0: the whole).
EMSCRIPTEN_KEEPALIVE int vw_set(const char* key_text, const char* value_text) {
  return guarded([&] {
    const std::string key = key_text, value = value_text;
    auto& v = viewer();
    auto bad = [&] { return vxl::Error(vxl::ErrorKind::Usage, "", std::nullopt, "bad " + key + ": '" + value + "'"); };
    if (key == "mode") {
      const auto mode = vxl::parse_render_mode(value);
      if (!mode) throw bad();
      if (!vxl::web::drawable_on_the_web(*mode))
        throw vxl::Error(vxl::ErrorKind::Unsupported, "", std::nullopt,
                         "the " + value + " mode needs storage buffers or compute shaders, which WebGL2 lacks");
      // It draws in the streamlines' order, from the voxline and streamline tables.
      if (*mode == vxl::RenderMode::Unsorted && v.image) throw vxl::web::not_in_image(v, "the unsorted mode");
      if (*mode == vxl::RenderMode::Unsorted && !vxl::web::complete(v))
        throw vxl::Error(vxl::ErrorKind::Usage, "", std::nullopt, "the unsorted mode waits for the whole file");
      v.settings.mode = *mode;
    } else if (key == "color") {
      const auto color = vxl::parse_color_mode(value);
      if (!color) throw bad();
      // Values and groups are read per vertex from the voxline and streamline tables.
      if ((*color == vxl::ColorMode::Scalar || *color == vxl::ColorMode::Group) && v.image)
        throw vxl::web::not_in_image(v, "colouring by " + value);
      if ((*color == vxl::ColorMode::Scalar || *color == vxl::ColorMode::Group) && !vxl::web::complete(v))
        throw vxl::Error(vxl::ErrorKind::Usage, "", std::nullopt,
                         "colouring by " + value + " waits for the whole file");
      v.settings.color = *color;
    } else if (key == "opacity") {
      const float o = std::strtof(value.c_str(), nullptr);
      if (!(o >= 0.001f && o <= 1.0f)) throw bad();
      v.settings.opacity = o;
    } else if (key == "fixed-color" || key == "background") {
      const auto c = vxl::parse_hex_color(value);
      if (!c) throw bad();
      (key == "background" ? v.settings.background_color : v.settings.fixed_color) = *c;
    } else if (key == "scalar") {
      const vxl::Renderer* r = v.full ? v.full.get() : v.quick.get();
      const auto& names = r ? r->value_set_names() : std::vector<std::string>{};
      if (std::find(names.begin(), names.end(), value) == names.end())
        throw vxl::Error(vxl::ErrorKind::Usage, "", std::nullopt, "no value set '" + value + "' in this file");
      v.settings.scalar = value;
    } else if (key == "colormap") {
      const auto map = vxl::parse_colormap(value);
      if (!map) throw bad();
      v.settings.colormap = *map;
    } else if (key == "package-level") {
      const long level = std::strtol(value.c_str(), nullptr, 10);
      if (!(level >= 0 && level < static_cast<long>(vxl::kMaxLevels)) || !v.file) throw bad();
      v.level_of_whole = static_cast<std::uint32_t>(level);
    } else if (key == "lighting") {
      v.settings.lighting = value == "1";
    } else if (key == "view") {
      const auto view = vxl::parse_view(value);
      if (!view || !v.controller) throw bad();
      v.controller->set_view((*view)[0], (*view)[1]);
    } else {
      throw vxl::Error(vxl::ErrorKind::Usage, "", std::nullopt, "no setting '" + key + "'");
    }
  });
}

// Mouse input in canvas pixels (y down): mode 1 orbits, 2 pans, 0 ends the drag.
EMSCRIPTEN_KEEPALIVE void vw_drag(int mode, double x, double y) {
  auto& c = viewer().controller;
  if (!c) return;
  if (mode == 0) return c->end_drag();
  if (c->dragging() == vxl::app::DragMode::None)
    c->begin_drag(mode == 1 ? vxl::app::DragMode::Orbit : vxl::app::DragMode::Pan, x, y);
  else
    c->drag_to(x, y);
}

EMSCRIPTEN_KEEPALIVE void vw_zoom(double steps) {
  if (viewer().controller) viewer().controller->zoom(steps);
}

// The camera as JSON (target, distance, azimuth, elevation), for the link to this view; vw_set_camera takes it back.
EMSCRIPTEN_KEEPALIVE const char* vw_camera() {
  static std::string text;
  auto& v = viewer();
  if (!v.controller) return "{}";
  const vxl::Camera& c = v.controller->camera();
  text = nlohmann::json{{"az", c.azimuth_deg},
                        {"el", c.elevation_deg},
                        {"distance", c.distance},
                        {"target", {c.target.x, c.target.y, c.target.z}}}
             .dump();
  return text.c_str();
}

EMSCRIPTEN_KEEPALIVE int vw_set_camera(double az, double el, double distance, double tx, double ty, double tz) {
  return guarded([&] {
    auto& v = viewer();
    if (!v.controller) throw std::runtime_error("no file is open");
    vxl::Camera c = v.controller->camera();
    if (!(distance >= vxl::ViewLimits::kMinMm && distance <= vxl::ViewLimits::kMaxMm) || !std::isfinite(az) ||
        !std::isfinite(el) || !std::isfinite(tx) || !std::isfinite(ty) || !std::isfinite(tz))
      throw vxl::Error(vxl::ErrorKind::Usage, "", std::nullopt, "a view outside the limits of a picture");
    c.azimuth_deg = az;
    c.elevation_deg = std::clamp(el, -90.0, 90.0);
    c.distance = distance;
    c.target = {tx, ty, tz};
    v.controller->set_camera(c);
  });
}

// The GPU memory budget of the files opened from now on, written as voxview's --gpu-memory ("512M", "2G"; empty:
// none): what is drawn at rest is the finest level whose GPU copy fits it.
EMSCRIPTEN_KEEPALIVE int vw_set_gpu_budget(const char* text) {
  return guarded([&] {
    const std::string_view t = text;
    const std::optional<std::uint64_t> bytes = vxl::parse_memory_size(t);
    if (!t.empty() && !bytes)
      throw vxl::Error(vxl::ErrorKind::Usage, "gpu", std::nullopt,
                       "'" + std::string(t) + "' is not a size of memory (e.g. 512M, 2G)");
    viewer().gpu_budget = bytes.value_or(0);
  });
}

// Makes the full-detail renderer (at the budget's level) when the first picture was coarser (nothing otherwise).
// Where the bytes that level draws from are not all in yet (a file fetched by ranges), its spans are smaller, and
// each is uploaded once its bytes are (vw_next_ranges names them, the view's nearest first); frames at rest draw
// the spans in, with the coarser level in place of the others. The rest of the file may still be coming.
EMSCRIPTEN_KEEPALIVE int vw_refine() {
  return guarded([&] {
    auto& v = viewer();
    if (!v.file) throw std::runtime_error("no file is open");
    if (v.full) return;
    const std::vector<const vxl::VxlFile*> files{&*v.file};
    // Spans of about 4 MiB of orders (2^20 words) while the bytes arrive: a span is uploaded and drawn once all of
    // its voxels are in. Else as large as the driver allows: where runs of voxels are short, each span more in a
    // draw costs every vertex a branch of texture fetches (SwiftShader: spans of 2^23 texels, two for the 144k
    // set, took its full-detail frame from 11 s to 14-16 s).
    constexpr std::uint64_t kArrivingSpanTexels = std::uint64_t(1) << 20;
    v.spans_arriving = !vxl::web::complete(v) && !vxl::web::holds_level(v, v.full_level);
    const std::uint64_t max_texels =
        v.spans_arriving ? std::min(vxl::GpuScene::driver_limit(),
                                    std::max(kArrivingSpanTexels, vxl::SceneLayout::largest_voxel_texels(files)))
                         : 0;
    // Made without its spans (eager false): vw_upload uploads them a few at a time.
    v.full = std::make_unique<vxl::Renderer>(files, max_texels, v.full_level, nullptr, false);
    vxl::web::note_spans_in(v);
  });
}

// Whether the last frame (drawn, or being drawn in pieces) lacks full detail: drawn in motion from the first level, or
// at rest before the view's full-detail spans were all uploaded. Uploads since do not change it: that picture,
// complete later, still lacks them.
EMSCRIPTEN_KEEPALIVE int vw_pending() {
  const auto& v = viewer();
  return v.quick && v.full && !v.drawn_full ? 1 : 0;
}

// Uploads a few more full-detail spans for the view: 1 once all it needs are on the GPU (the next frame at
// rest is drawn at full detail), 0 while more remain, else an error code (vw_error). Where the rest wait for
// their bytes: -1 when spans were uploaded since the last frame (a frame at rest now shows more), -2 otherwise.
// -3: all are, and the last frame at rest (drawn, or being drawn in pieces) is full detail already.
EMSCRIPTEN_KEEPALIVE int vw_upload() {
  int state = 1;
  const int error = guarded([&] {
    auto& v = viewer();
    if (!v.controller || !v.full) throw std::runtime_error("no full-detail renderer to upload for");
    if (!v.quick) return;
    switch (vxl::web::upload_full(v)) {
      case vxl::web::FullDetail::Ready: state = v.drawn_full ? -3 : 1; break;
      case vxl::web::FullDetail::Uploading: state = 0; break;
      case vxl::web::FullDetail::WaitingForBytes: state = v.full->gpu_bytes() != v.drawn_uploaded ? -1 : -2; break;
    }
  });
  return error != 0 ? error : state;
}

// Draws a frame into the canvas, now width x height pixels; `moving` (a drag) draws the first picture's level. At rest,
// a level finer than the first picture's is drawn in pieces (a software WebGL draws the 144k set's full detail in
// about 9 s): the first here, the rest by vw_draw_piece, the canvas keeping the last picture until it is complete.
// A frame drawn meanwhile abandons the pieces.
EMSCRIPTEN_KEEPALIVE int vw_draw(int width, int height, int moving) {
  return guarded([&] {
    auto& v = viewer();
    if (!v.controller) throw std::runtime_error("no file is open");
    v.piecing = nullptr;
    v.width = std::max(width, 1);
    v.height = std::max(height, 1);
    vxl::Renderer* renderer = vxl::web::renderer_for(v, moving != 0);
    v.controller->set_window_height(v.height);
    // At rest with some of full detail's spans in and others still coming: those, with this one standing in.
    vxl::Renderer* stand_in = nullptr;
    if (!moving && v.full && renderer != v.full.get() && v.full->gpu_bytes() > 0 &&
        v.full->draws_in_voxel_pieces(v.settings.mode))
      stand_in = std::exchange(renderer, v.full.get());
    v.drawn_mixed = stand_in != nullptr;
    v.drawn_full = !moving && renderer == v.full.get() && !stand_in;
    if (v.full) v.drawn_uploaded = v.full->gpu_bytes();
    vxl::RenderSettings settings = v.settings;
    if (v.level_of_whole > 0) settings.opacity = vxl::SceneLayout::level_opacity(settings.opacity, v.level_of_whole);
    if (renderer == v.quick.get() || !v.quick) {
      renderer->draw(v.controller->camera(), settings, v.width, v.height, 0);
      renderer->check_uploaded(false);
      return;
    }
    v.piece_target.ensure(v.width, v.height, GL_RGBA8, 0, true);
    renderer->begin_pieces(v.controller->camera(), settings, v.width, v.height, v.piece_target.fbo, stand_in);
    v.piecing = renderer;
    vxl::web::draw_next_piece(v);
  });
}

// Draws the next piece of the picture vw_draw began: 1 once it is complete and on the canvas (or when none is under
// way), 0 while more remain, else an error code (vw_error).
EMSCRIPTEN_KEEPALIVE int vw_draw_piece() {
  bool complete = true;
  const int error = guarded([&] {
    auto& v = viewer();
    if (v.piecing) complete = vxl::web::draw_next_piece(v);
  });
  return error != 0 ? error : complete ? 1 : 0;
}

// Runs the draw checks (format/vxl_draw_check.h) of what the renderers have uploaded for about 30 ms: 1 once none
// are left, 0 while some are, else an error code (the file is damaged: vw_error). voxview runs them beside the
// drawing; here the page calls this between its other tasks, and a failure stops every later frame.
EMSCRIPTEN_KEEPALIVE int vw_check() {
  constexpr double kCheckSliceMs = 30;
  bool done = true;
  const int error = guarded([&] {
    auto& v = viewer();
    for (vxl::Renderer* r : {v.quick.get(), v.interim.get(), v.full.get()})
      if (r && !r->check_some(kCheckSliceMs)) {
        done = false;
        return;
      }
  });
  return error != 0 ? error : done ? 1 : 0;
}

// Whether a picture vw_draw began in pieces is not complete yet.
EMSCRIPTEN_KEEPALIVE int vw_pieces_under_way() { return viewer().piecing ? 1 : 0; }

}  // extern "C"
