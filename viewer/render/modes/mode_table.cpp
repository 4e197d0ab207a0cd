#include "viewer/render/modes/mode_table.h"

#include <stdexcept>
#include <string>

#include "viewer/render/gl_api.h"

namespace vxl {
namespace {

struct ModeMaker {
  RenderMode mode;
  std::unique_ptr<ModePass> (*make)();
};

// Every mode's pass: the one place a mode is tied to its drawing.
constexpr ModeMaker kModeMakers[] = {
    {RenderMode::Opaque, make_opaque_pass},     {RenderMode::Unsorted, make_unsorted_pass},
    {RenderMode::Additive, make_additive_pass}, {RenderMode::Wboit, make_wboit_pass},
    {RenderMode::Basic, make_basic_pass},       {RenderMode::Axis, make_axis_pass},
#if !VOXLINES_WEBGL  // WebGL2 has neither storage buffers and compute shaders nor buffers rewritten in place
    {RenderMode::Segsort, make_segsort_pass},   {RenderMode::Exact, make_exact_pass},
#endif
};

}  // namespace

std::unique_ptr<ModePass> make_mode_pass(RenderMode mode) {
  for (const ModeMaker& m : kModeMakers)
    if (m.mode == mode) return m.make();
  throw std::logic_error("no pass for render mode " + std::to_string(static_cast<int>(mode)));
}

}  // namespace vxl
