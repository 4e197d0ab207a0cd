#include "viewer/app/viewer_arguments.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "converter/voxel_size_option.h"
#include "format/base/error.h"
#include "format/base/memory_size.h"
#include "format/base/output_path.h"
#include "viewer/app/camera_file.h"
#include "viewer/app/scene_source.h"
#include "viewer/app/turntable.h"
#include "viewer/platform/image_io.h"
#include "viewer/render/background_color.h"
#include "viewer/render/scene_groups.h"

namespace vxl::app {

namespace {

[[noreturn]] void usage_error(const std::string& what) { throw Error(ErrorKind::Usage, "", std::nullopt, what); }

// "MIN,MAX" with finite MIN < MAX (--range, --image-range).
std::optional<std::array<float, 2>> parse_min_max(const std::string& text) {
  float lo = 0, hi = 0;
  char end = 0;
  if (std::sscanf(text.c_str(), "%f,%f%c", &lo, &hi, &end) != 2 || !std::isfinite(lo) || !std::isfinite(hi) ||
      !(hi > lo))
    return std::nullopt;
  return std::array<float, 2>{lo, hi};
}

// A saved view replaces the defaults: its settings and camera, and its size unless --size is given.
void apply_saved_view(const ViewerArguments& a, ViewerOptions& o, std::string& size) {
  if (a.camera_file.empty()) return;
  SavedView defaults;
  defaults.settings = o.settings;
  const SavedView saved = read_view(a.camera_file, defaults);
  o.settings = saved.settings;
  if (saved.has_camera) o.camera = saved.camera;
  // The saved regions, unless the command line gives its own.
  if (!o.selecting()) {
    o.include = saved.include;
    o.exclude = saved.exclude;
    o.ends_in = saved.ends_in;
    // Their shells as they were drawn, unless the command line asks for them.
    o.saved_show_regions = saved.show_regions;
    if (saved.show_regions && !a.was_given("--show-regions")) o.show_regions = *saved.show_regions;
  }
  // What the file names and the command line does not replace is checked against the scene as the file's.
  ViewFileSettings& from_file = o.from_view_file;
  from_file.path = a.camera_file;
  from_file.color = !a.was_given("--color");
  from_file.scalar = !a.was_given("--scalar");
  for (const GroupStyle& g : saved.settings.group_styles) {
    const bool given = std::any_of(a.groups.begin(), a.groups.end(), [&](const std::string& text) {
      const auto style = parse_group_style(text);
      return style && style->name == g.name;
    });
    if (!given) from_file.groups.push_back(g.name);
  }
  if (saved.size && !a.was_given("--size"))
    size = std::to_string((*saved.size)[0]) + "x" + std::to_string((*saved.size)[1]);
}

// Mode, opacity, colouring, groups, background, line width, lighting and what is drawn over the picture. `from_file`: a
// saved view set them, and only options given explicitly change them.
void apply_look(const ViewerArguments& a, bool from_file, RenderSettings& s) {
  auto overrides = [&](const char* option) { return !from_file || a.was_given(option); };
  if (overrides("--mode")) {
    const auto mode = parse_render_mode(a.mode);
    if (!mode) usage_error("--mode: unknown mode '" + a.mode + "'");
    s.mode = *mode;
  }
  if (overrides("--opacity")) s.opacity = a.opacity;
  if (overrides("--color")) {
    const auto color = parse_color_mode(a.color);
    if (!color) usage_error("--color: unknown colour mode '" + a.color + "'");
    s.color = *color;
  }
  if (a.was_given("--fixed-color")) {
    const auto fixed = parse_hex_color(a.fixed_color);
    if (!fixed) usage_error("--fixed-color: expected #RRGGBB, got '" + a.fixed_color + "'");
    s.fixed_color = *fixed;
  }
  if (a.was_given("--scalar")) s.scalar = a.scalar;
  if (overrides("--colormap")) {
    const auto colormap = parse_colormap(a.colormap);
    if (!colormap) usage_error("--colormap: unknown colour map '" + a.colormap + "'");
    s.colormap = *colormap;
  }
  if (a.was_given("--range")) {
    s.range = parse_min_max(a.range);
    if (!s.range) usage_error("--range: expected MIN,MAX with MIN < MAX (e.g. 0,0.5); got '" + a.range + "'");
  }
  for (const std::string& g : a.groups) {
    const auto style = parse_group_style(g);
    if (!style)
      usage_error("--group: expected NAME=#RRGGBB, NAME=#RRGGBB:OPACITY or NAME=:OPACITY (opacity 0..1); got '" + g +
                  "'");
    GroupStyle& existing = s.style_of(style->name);
    if (style->color) existing.color = style->color;
    existing.opacity = style->opacity;
  }
  if (overrides("--background")) {
    const auto background = parse_background_color(a.background);
    if (!background) usage_error("--background: expected " + background_color_forms() + "; got '" + a.background + "'");
    s.background_color = *background;
  }
  if (overrides("--line-width")) s.line_width = a.line_width;
  if (a.lighting) s.lighting = true;
  if (a.orientation_labels) s.orientation_labels = true;
  if (a.colorbar) {
    // The bar shows the colour map and range of the values the lines are coloured by.
    if (s.color != ColorMode::Scalar) usage_error("--colorbar goes with --color scalar (a saved view's colour too)");
    s.colorbar = true;
  }
}

// Headless without --save-camera, the options of a colour mode other than the picture's change nothing; in the window
// they preset the panel's choices, and a saved view keeps them. Said, not refused.
void note_other_colour_modes_options(const ViewerArguments& a, ViewerOptions& o) {
  if (!o.render_png || o.save_camera) return;
  const struct {
    const char* option;
    ColorMode mode;
  } options[] = {{"--fixed-color", ColorMode::Fixed},
                 {"--scalar", ColorMode::Scalar},
                 {"--colormap", ColorMode::Scalar},
                 {"--range", ColorMode::Scalar}};
  for (const auto& [option, mode] : options)
    // The fixed colour is also scalar's, for the points without a value.
    if (a.was_given(option) && o.settings.color != mode &&
        !(mode == ColorMode::Fixed && o.settings.color == ColorMode::Scalar))
      o.notes.push_back(std::string(option) + " goes with --color " + color_mode_name(mode) +
                        "; this picture is coloured by " + color_mode_name(o.settings.color));
  // A group's opacity applies in every colour mode, its colour only in the group mode.
  if (o.settings.color == ColorMode::Group) return;
  for (const std::string& g : a.groups)
    if (const auto style = parse_group_style(g); style && style->color)
      o.notes.push_back("--group " + g + ": its colour goes with --color group; this picture is coloured by " +
                        color_mode_name(o.settings.color) + " (its opacity applies)");
}

// --slab and --clip: clip planes given replace a saved view's.
void apply_clipping(const ViewerArguments& a, Clipping& c) {
  if (a.was_given("--slab")) {
    if (!slab_is_drawable(a.slab) || a.slab == 0) usage_error("--slab: expected " + slab_range_text());
    c.slab_mm = a.slab;
  }
  if (a.clips.size() > Clipping::kMaxPlanes)
    usage_error("--clip: at most 3 clip planes (got " + std::to_string(a.clips.size()) + ")");
  if (!a.clips.empty()) c.planes.clear();
  for (const std::string& text : a.clips) {
    const auto plane = parse_axis_clip(text);
    if (!plane)
      usage_error("--clip: expected AXIS,POS with AXIS one of x y z -x -y -z and POS in mm (e.g. -z,12.5); got '" +
                  text + "'");
    c.planes.push_back(*plane);
  }
}

// "axial,coronal", "view", "none", ...: which slices of the image are shown.
SliceSettings parse_slices(const std::string& text, SliceSettings sl) {
  sl.axial = sl.coronal = sl.sagittal = sl.view_plane = false;
  std::size_t start = 0;
  while (text != "none") {
    const std::size_t comma = text.find(',', start);
    const std::string name = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    if (name == "axial")
      sl.axial = true;
    else if (name == "coronal")
      sl.coronal = true;
    else if (name == "sagittal")
      sl.sagittal = true;
    else if (name == "view")
      sl.view_plane = true;
    else
      usage_error("--slices: expected a comma list of axial, coronal, sagittal, view, or none; got '" + text + "'");
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return sl;
}

// --image-range, --slices and --focus.
void apply_image(const ViewerArguments& a, ViewerOptions& o) {
  SliceSettings& sl = o.settings.slices;
  if (a.was_given("--image-range")) {
    sl.range = parse_min_max(a.image_range);
    if (!sl.range)
      usage_error("--image-range: expected MIN,MAX with MIN < MAX (e.g. 0,800); got '" + a.image_range + "'");
  }
  if (a.was_given("--slices")) sl = parse_slices(a.slices, sl);
  if (a.was_given("--focus")) {
    double x = 0, y = 0, z = 0;
    char end = 0;
    if (std::sscanf(a.focus.c_str(), "%lf,%lf,%lf%c", &x, &y, &z, &end) != 3 ||
        !(std::max({std::abs(x), std::abs(y), std::abs(z)}) <= ViewLimits::kMaxMm))
      usage_error("--focus: expected X,Y,Z in mm within +-1e7 (e.g. 0,-10,12.5); got '" + a.focus + "'");
    o.focus = glm::dvec3(x, y, z);
  }
  if ((a.was_given("--image-range") || a.was_given("--slices")) && !o.image)
    usage_error("--image-range and --slices need --image FILE.nii[.gz] or FILE.mif[.gz]");
}

// --view and the image or window size (--size, else the saved view's, else the default).
void apply_view_and_size(const ViewerArguments& a, const std::string& size, ViewerOptions& o) {
  if (!a.view.empty()) {
    o.view = parse_view(a.view);
    if (!o.view)
      usage_error("--view: unknown view '" + a.view + "' (expected " + view_names_text() +
                  ", or AZ,EL in degrees, the azimuth within +-1e6)");
  }
  if (std::sscanf(size.c_str(), "%dx%d", &o.width, &o.height) != 2 || o.width < 1 || o.height < 1 || o.width > 16384 ||
      o.height > 16384)
    usage_error("--size must be WxH, each 1..16384");
  o.size_given = a.was_given("--size") || size != a.size;
}

// Focus and context opacities as the groups "selected" and "context": the scene's opacity is the larger,
// each group's factor its share of it.
void apply_selection(const ViewerArguments& a, ViewerOptions& o) {
  if (!o.selecting()) {
    if (a.was_given("--focus-opacity") || a.was_given("--context-opacity"))
      usage_error("--focus-opacity and --context-opacity go with a selection (--include, --exclude, --ends-in)");
    if (o.show_regions) usage_error("--show-regions goes with a selection (--include, --exclude, --ends-in)");
    return;
  }
  RenderSettings& s = o.settings;
  // A saved view's focus and context opacities stay unless the command line gives others.
  const GroupStyle* saved_focus = s.find_style(SceneGroups::kSelected);
  const GroupStyle* saved_context = s.find_style(SceneGroups::kContext);
  const float focus = a.focus_opacity.value_or(saved_focus ? saved_focus->opacity * s.opacity : s.opacity);
  const float context =
      a.was_given("--context-opacity") || !saved_context ? a.context_opacity : saved_context->opacity * s.opacity;
  s.opacity = std::max(focus, context);
  s.style_of(SceneGroups::kSelected).opacity = focus / s.opacity;
  s.style_of(SceneGroups::kContext).opacity = context / s.opacity;
}

// Every output path, before anything is read or drawn: a missing folder, a directory, a FIFO or a device
// is refused now (exit 5) rather than after the rendering, and never replaced (format/base/output_path.h).
void check_outputs(const ViewerOptions& o) {
  for (const auto* path : {&o.render_png, &o.screenshot})
    if (*path && picture_format_of(**path).empty())
      usage_error(**path + ": the extension names no picture format voxview writes: use " + picture_formats_text());
  if (o.render_png) {
    const int frames = std::max(1, o.turntable);
    for (int i = 0; i < frames; ++i)
      (void)output_target(o.turntable ? turntable_frame_path(*o.render_png, i, frames) : *o.render_png);
  }
  for (const auto* path : {&o.save_camera, &o.stats_json, &o.screenshot})
    if (*path) (void)output_target(**path);
}

}  // namespace

ViewerOptions resolve_viewer_options(const ViewerArguments& a) {
  ViewerOptions o = a.options;
  if (o.turntable && !o.render_png) usage_error("--turntable needs --render OUT.png (it writes OUT_000.png, ...)");
  // The command line's opacity is also the default a saved view without one keeps.
  o.settings.opacity = a.opacity;
  std::string size = a.size;
  apply_saved_view(a, o, size);
  apply_look(a, !a.camera_file.empty(), o.settings);
  note_other_colour_modes_options(a, o);
  apply_clipping(a, o.settings.clipping);
  apply_image(a, o);
  apply_view_and_size(a, size, o);
  apply_selection(a, o);
  if (!a.gpu_memory.empty()) {
    o.gpu_memory = parse_memory_size(a.gpu_memory);
    if (!o.gpu_memory || *o.gpu_memory == 0)
      usage_error("--gpu-memory '" + a.gpu_memory + "' is not a memory size (bytes, or K/M/G: 512M, 2G)");
  }
  const VoxelSizeArgument voxel_size = parse_voxel_size(a.voxel_size);
  o.voxel_size = voxel_size.mm;
  o.voxel_size_auto = voxel_size.automatic;
  if (!a.memory_limit.empty()) {
    const std::optional<std::uint64_t> limit = parse_memory_size(a.memory_limit);
    if (!limit) usage_error("--memory-limit '" + a.memory_limit + "' is not a memory size (bytes, or K/M/G: 512M, 2G)");
    o.memory_limit = *limit;
  }
  // What shapes a conversion, where nothing is converted, would change nothing: refused rather than ignored.
  if (std::all_of(o.inputs.begin(), o.inputs.end(), opens_without_conversion))
    for (const char* option : {"--voxel-size", "--memory-limit"})
      if (a.was_given(option))
        usage_error(std::string(option) +
                    " applies to a source tractogram as it is converted; every input here is a .vxl or .vxlz, made "
                    "with the options of its conversion (voxlines convert IN.tck OUT.vxl " +
                    option + " ...)");
  if (!(o.frame_budget_ms >= 0 && o.frame_budget_ms <= 1e6))
    usage_error("--frame-budget: expected milliseconds in [0, 1e6]");
  if (o.orbit_deg && !(std::abs(*o.orbit_deg) <= 360)) usage_error("--orbit: expected degrees in [-360, 360]");
  o.partial_pictures = a.partial_pictures == "always"  ? PartialPictures::Always
                       : a.partial_pictures == "never" ? PartialPictures::Never
                                                       : PartialPictures::Auto;
  if (!a.drag_region.empty()) {
    if (a.drag_region.size() != 3 ||
        !std::all_of(a.drag_region.begin(), a.drag_region.end(), [](double d) { return std::abs(d) <= 1000; }))
      usage_error("--drag-region: expected DX,DY,DZ in mm, each in [-1000, 1000]");
    if (o.include.empty() && o.exclude.empty() && o.ends_in.empty())
      usage_error("--drag-region needs a region to drag (--include, --exclude or --ends-in)");
    o.drag_region_mm = {a.drag_region[0], a.drag_region[1], a.drag_region[2]};
  }
  check_outputs(o);
  return o;
}

}  // namespace vxl::app
