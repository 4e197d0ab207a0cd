#include "viewer/app/scene_detail.h"

#include <algorithm>
#include <cmath>

#include <epoxy/gl.h>

#include "format/base/error.h"
#include "format/base/memory_available.h"
#include "format/base/memory_size.h"
#include "viewer/render/gpu_scene.h"
#include "viewer/render/scene_layout.h"

namespace vxl::app {
namespace {

// GL_NVX_gpu_memory_info and GL_ATI_meminfo report free video memory in KiB; core GL has no query.
constexpr GLenum kNvxCurrentAvailableKib = 0x9049;
constexpr GLenum kAtiTextureFreeMemory = 0x87FC;

std::optional<std::uint64_t> driver_free_bytes() {
  GLint kib[4] = {0, 0, 0, 0};
  // An error left by an earlier call must not be taken for this query's (bounded: a lost context repeats one).
  for (int i = 0; i < 16 && glGetError() != GL_NO_ERROR; ++i) {
  }
  if (epoxy_has_gl_extension("GL_NVX_gpu_memory_info"))
    glGetIntegerv(kNvxCurrentAvailableKib, kib);
  else if (epoxy_has_gl_extension("GL_ATI_meminfo"))
    glGetIntegerv(kAtiTextureFreeMemory, kib);
  if (glGetError() != GL_NO_ERROR || kib[0] <= 0) return std::nullopt;
  return std::uint64_t(kib[0]) << 10;
}

}  // namespace

namespace {

// The level for a span size: the one --level names (checked against --gpu-memory), else the finest that fits.
std::uint32_t level_within(const std::vector<const VxlFile*>& files, const SceneDetail& d,
                           std::optional<std::uint32_t> level, bool budget_given) {
  if (level) {
    const std::uint32_t forced = std::min(*level, SceneLayout::coarsest_level(files));
    const SceneLayout layout(files, d.span_texels, forced);
    if (budget_given && layout.upload_bytes() > d.budget)
      throw Error(ErrorKind::Unsupported, files.front()->path(), std::nullopt,
                  "level " + std::to_string(forced) + " needs " + format_memory_size(layout.upload_bytes()) +
                      " of GPU memory, more than --gpu-memory " + format_memory_size(d.budget) +
                      "; choose a coarser --level or leave it out");
    return forced;
  }
  return SceneLayout::finest_level_within(files, d.span_texels, d.budget);
}

}  // namespace

SceneDetail choose_scene_detail(const std::vector<const VxlFile*>& files, std::optional<std::uint32_t> level,
                                std::optional<std::uint64_t> gpu_memory, std::optional<std::uint64_t> span_texels) {
  SceneDetail d;
  if (gpu_memory) {
    d.budget = *gpu_memory;
    d.budget_source = "--gpu-memory";
  } else if (const auto free = driver_free_bytes()) {
    d.budget = *free / 2;  // the rest for the framebuffers, the exact mode's lists and other programs
    d.budget_source = "half the free GPU memory the driver reports";
  } else {
    d.budget = available_memory().value_or(std::uint64_t(4) << 30) / 4;  // the mapped file and the copy also take RAM
    d.budget_source = "a quarter of the available memory (the driver reports no GPU memory)";
  }
  d.forced = level.has_value();
  d.asked = level.value_or(0);
  const std::uint64_t driver = GpuScene::driver_limit();
  auto within_driver = [&](std::uint64_t wanted) {
    return std::min(driver, std::max(wanted, SceneLayout::largest_voxel_texels(files)));
  };
  d.span_texels = d.whole_span_texels = within_driver(span_texels.value_or(driver));
  d.level = level_within(files, d, level, gpu_memory.has_value());
  if (!span_texels && d.level > 0 && !d.forced) {  // full detail does not fit: page in small spans
    d.span_texels = within_driver(kPagingSpanTexels);
    d.level = level_within(files, d, level, gpu_memory.has_value());
  }
  return d;
}

std::string describe_scene_detail(const SceneDetail& d, std::uint32_t levels_in_files) {
  if (d.level == 0) return "";
  const std::string what = "drawing level " + std::to_string(d.level) + " (of levels 0 to " +
                           std::to_string(levels_in_files - 1) + "; about 1/" +
                           std::to_string(static_cast<std::uint64_t>(std::pow(double(kLevelRatio), double(d.level)))) +
                           " of the streamlines, opacity compensated)";
  if (d.forced && d.asked > d.level)
    return what + ": --level " + std::to_string(d.asked) + " is past the coarsest level the files have";
  if (d.forced) return what + " as --level asks";
  return what + " to stay within a GPU memory budget of " + format_memory_size(d.budget) + " (" + d.budget_source +
         (d.budget_source == "--gpu-memory" ? ")" : "; --gpu-memory sets it)");
}

}  // namespace vxl::app
