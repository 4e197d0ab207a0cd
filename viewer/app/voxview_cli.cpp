#include "viewer/app/voxview_cli.h"

#include <cmath>
#include <cstdlib>
#include <vector>

#include "converter/readers/source_formats.h"
#include "converter/voxel_size_option.h"
#include "format/vxl_levels.h"
#include "viewer/app/key_bindings.h"
#include "viewer/platform/image_io.h"
#include "viewer/render/background_color.h"
#include "viewer/render/camera.h"
#include "viewer/render/render_settings.h"

namespace vxl::app {

namespace {

std::string join(const std::vector<std::string>& items, const char* separator) {
  std::string text;
  for (const std::string& item : items) text += (text.empty() ? "" : separator) + item;
  return text;
}

// argv as CLI11 takes it (reversed). "--clip -x,10", "--focus -5,0,0": CLI11 would take "-x,10" for an option,
// so such a value is passed as "--clip=-x,10".
std::vector<std::string> cli11_arguments(int argc, const char* const* argv) {
  std::vector<std::string> args;
  for (int i = argc - 1; i >= 1; --i) {
    const std::string a = argv[i];
    const std::string before = i >= 2 ? argv[i - 1] : "";
    if ((before == "--clip" || before == "--focus") && a.size() > 1 && a[0] == '-' && a[1] != '-') {
      args.push_back(before + "=" + a);
      --i;
    } else {
      args.push_back(a);
    }
  }
  return args;
}

// A positive number (or, with `zero`, a non-negative one) of `unit`: CLI's own checks print the largest double in
// full as the range.
CLI::Validator number_above_zero(const std::string& unit, bool zero = false) {
  const std::string expected = zero ? "a number of " + unit + " >= 0" : "a positive number of " + unit;
  return CLI::Validator(
      [expected, zero](const std::string& text) -> std::string {
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        if (end == text.c_str() || *end != '\0' || !std::isfinite(v) || v < 0 || (v == 0 && !zero))
          return "expected " + expected + ", got '" + text + "'";
        return {};
      },
      "NUMBER");
}

// A number from `lo` to `hi`. CLI::Range lets NaN through (every comparison with it is false), and an opacity or a
// line width of NaN drew a black picture.
CLI::Validator number_from_to(double lo, double hi) {
  const std::string range = CLI::detail::to_string(lo) + " to " + CLI::detail::to_string(hi);
  return CLI::Validator(
      [lo, hi, range](const std::string& text) -> std::string {
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        if (end == text.c_str() || *end != '\0' || !std::isfinite(v) || v < lo || v > hi)
          return "expected a number from " + range + ", got '" + text + "'";
        return {};
      },
      "NUMBER in [" + range + "]");
}

}  // namespace

std::string voxview_description(const std::string& version) {
  return "voxview " + version +
         " — transparent tractogram viewer (Voxlines method).\n"
         "voxview FILE... [--render OUT.png]: a window, or headless to PNG with --render.\n"
         "Opens a .vxl instantly (memory-mapped); a " +
         source_suffixes_text("/") +
         " is converted first, as 'voxlines convert' does, through a temporary .vxl in $TMPDIR\n"
         "(else /tmp) that is removed once mapped.\n"
         "Opening a .vxl checks its structure (header, section table, section sizes, voxel table, names) in\n"
         "O(voxels) but not its checksums: damaged positions or values are drawn as they are; order entries outside\n"
         "their block and wrong voxline ends are found beside the drawing, which then stops (exit 3). --verify\n"
         "checks everything first, as 'voxlines verify' does.\n"
         "Exit codes: 0 ok, 2 usage, 3 bad input, 4 unsupported (a format, a size past the driver's limits), 5 output\n"
         "error, 70 an internal error (a bug).\n" +
         controls_as_paragraph(110);
}

namespace {

// The inputs, headless rendering and saved views.
void declare_input_output(CLI::App& cli, ViewerArguments& a) {
  cli.add_option(
         "files", a.options.inputs,
         "a .vxl file, a .vxlz package, or a " + source_suffixes_text(" / ") +
             " tractogram; several are shown together "
             "(their voxels sorted back to front as one scene, one group per file for --color group and --group)")
      ->required();
  cli.add_option("--render", a.options.render_png,
                 "render headless (EGL, no display needed) to this picture and exit, in the format its extension "
                 "names: " +
                     picture_formats_text());
  cli.add_option("--turntable", a.options.turntable,
                 "with --render: N frames turning once around the vertical (superior) axis, written as OUT_000.png, "
                 "OUT_001.png, ... (frame i at azimuth + 360 i / N degrees; frame 0 looks from the --view direction; "
                 "all frames share one framing in which each is whole)")
      ->check(CLI::Range(1, 100000));
  cli.add_option("--camera", a.camera_file,
                 "start from a saved view (camera and settings; JSON, see --save-camera); options given as well "
                 "override it");
  cli.add_option("--save-camera", a.options.save_camera,
                 "write the view (camera and settings) to this JSON file: headless after rendering, in the window on "
                 "V, the panel's Save view button, or on quitting after --frames");
}

// The transparency mode, the view and the colours.
void declare_picture(CLI::App& cli, ViewerArguments& a) {
  cli.add_option("--mode", a.mode, join(render_mode_names(), " | "))
      ->default_val("axis")
      ->check(CLI::IsMember(render_mode_names()));
  cli.add_option("--opacity", a.opacity, "line opacity, 1 down to 0.001")
      ->default_val(0.3)
      ->check(number_from_to(0.001, 1.0));
  cli.add_option("--view", a.view, view_names_text() + ", or AZ,EL in degrees");
  cli.add_option("--size", a.size, "image or window size WxH")->default_val("1024x1024");
  cli.add_flag("--ortho", a.options.orthographic, "orthographic projection (default perspective)");
  cli.add_option(
         "--color", a.color,
         "direction (|p1 - p0| as RGB), fixed (--fixed-color), scalar (a value set through --colormap) or group "
         "(one colour per TRX group, or per file when several are shown)")
      ->default_val("direction")
      ->check(CLI::IsMember(color_mode_names()));
  cli.add_option("--fixed-color", a.fixed_color, "the fixed colour, #RRGGBB (also for points without a value)")
      ->check([](const std::string& v) {
        return parse_hex_color(v) ? std::string() : "expected #RRGGBB, got '" + v + "'";
      });
  cli.add_option("--scalar", a.scalar,
                 "the value set to colour by (a TSF's file name, a TRK scalar or property, a TRX dpv or dps name); "
                 "default: the first");
  cli.add_option("--colormap", a.colormap, join(colormap_names(), " | ") + ", for --color scalar")
      ->default_val("viridis")
      ->check([](const std::string& name) {
        return parse_colormap(name)
                   ? std::string()
                   : "unknown colour map '" + name + "' (expected " + join(colormap_names(), ", ") + ")";
      });
  cli.add_option("--range", a.range,
                 "MIN,MAX: the values at the colour map's ends (default: the set's minimum and maximum)");
  cli.add_option(
         "--group", a.groups,
         "NAME=#RRGGBB[:OPACITY] or NAME=:OPACITY: a group's colour and opacity (a factor on --opacity; 0 hides "
         "it), repeatable")
      ->expected(1)
      ->take_all();
}

// The selection's regions and how focus and context are drawn.
void declare_selection(CLI::App& cli, ViewerArguments& a) {
  cli.add_option("--include", a.options.include,
                 "select the streamlines that pass through this region (as `voxlines select`: X,Y,Z,R, "
                 "box:X0,Y0,Z0,X1,Y1,Z1, FILE.nii[.gz][:LABEL], FILE.mif[.gz][:LABEL]); they are drawn as the "
                 "focus, the others as "
                 "context, in one back-to-front pass (repeatable)")
      ->type_name("ROI")
      ->expected(1)
      ->take_all();
  cli.add_option("--exclude", a.options.exclude, "leave out of the selection the streamlines touching this region")
      ->type_name("ROI")
      ->expected(1)
      ->take_all();
  cli.add_option("--ends-in", a.options.ends_in, "select the streamlines with an end in this region")
      ->type_name("ROI")
      ->expected(1)
      ->take_all();
  cli.add_flag("--show-regions", a.options.show_regions,
               "with a selection: draw its spheres and boxes as faint translucent shells (include green, exclude "
               "red, ends-in blue; the active, last region brighter), their back halves under the lines and their "
               "front halves over them (the window shows them unless B hides them)");
  cli.add_option("--focus-opacity", a.focus_opacity,
                 "with a selection: the selected streamlines' opacity "
                 "(default --opacity)")
      ->check(number_from_to(0.001, 1.0));
  cli.add_option("--context-opacity", a.context_opacity,
                 "with a selection: the other streamlines' opacity (0 hides them)")
      ->default_val(0.02)
      ->check(number_from_to(0.0, 1.0));
}

// Per-point values, lighting, line width, background and annotations.
void declare_lines(CLI::App& cli, ViewerArguments& a) {
  cli.add_option("--tsf", a.options.tsf,
                 "a TSF file of per-point values for a .tck given as input (read whole with it), repeatable")
      ->expected(1)
      ->take_all();
  cli.add_flag(
      "--lighting", a.lighting,
      "light the lines (illuminated lines: a line along the light, which comes from the viewer's upper left, is "
      "dark, one across it bright)");
  cli.add_option("--line-width", a.line_width, "line width in pixels")
      ->default_val(1.0)
      ->check(number_from_to(1.0, 16.0));
  cli.add_option("--background", a.background, "the background colour: " + background_color_forms())
      ->default_val("black");
  cli.add_flag("--orientation-labels", a.orientation_labels,
               "label the picture's edges with the anatomical directions the world's axes point to there (L/R "
               "for x, P/A for y, I/S for z; RAS: R, A and S are +x, +y and +z) and draw an axes triad in the lower "
               "left corner (x red, y green, z blue), so that radiological and neurological views are never guessed");
  cli.add_flag("--colorbar", a.colorbar,
               "with --color scalar: a colour bar at the right edge, the colour map from --range's minimum (bottom) "
               "to its maximum (top), with both numbers and the value set's name");
}

// The anatomical image, the focus point, the slab and the clip planes.
void declare_image_and_clipping(CLI::App& cli, ViewerArguments& a) {
  cli.add_option("--image", a.options.image,
                 "an anatomical image (NIfTI-1 or -2, .nii or .nii.gz; MRtrix .mif, .mif.gz or .mih; e.g. a T1) shown "
                 "as opaque grey slices through the "
                 "focus point under the lines (lines behind a slice are hidden by it, lines in front blend over it)");
  cli.add_option(
      "--image-range", a.image_range,
      "MIN,MAX: the image values shown black and white (default: the 2nd and 98th percentiles of the image's "
      "non-zero voxels)");
  cli.add_option(
      "--slices", a.slices,
      "which slices of --image to show: a comma list of axial, coronal, sagittal and view (the plane through the "
      "focus facing the viewer: with --slab, the slice in its middle), or none; default axial,coronal,sagittal");
  cli.add_option("--focus", a.focus,
                 "X,Y,Z: the focus point in RAS mm (the view's centre, where the slices cross, the slab's centre); "
                 "default the centre of the tractograms' bounds");
  cli.add_option("--slab", a.slab,
                 "crop to a slab MM thick, centred on the focus point (the view's centre), perpendicular to the view "
                 "direction (mrview's crop to slab)")
      ->check(number_above_zero("mm"));
  cli.add_option(
         "--clip", a.clips,
         "clip plane AXIS,POS in RAS mm, up to 3: x,10 keeps x >= 10, -x,10 keeps x <= 10 (axes x y z, -x -y -z)")
      ->expected(1)
      ->take_all();
}

// Opening and converting the inputs, the GPU memory budget and the level of detail.
void declare_loading(CLI::App& cli, ViewerArguments& a) {
  cli.add_flag("--verify", a.options.verify,
               "before drawing, check every .vxl in full (every checksum and padding byte, every order, the streamline "
               "tables; reads the whole file, as 'voxlines verify') and refuse a damaged one (exit 3, naming the first "
               "problem); a .vxlz's unpacked file too (a package's own checksums are always checked)");
  add_voxel_size_option(cli, a.voxel_size,
                        "voxel size in mm when converting a source tractogram, or auto: chosen from the data as "
                        "'voxlines convert --voxel-size auto' chooses it");
  cli.add_option("--memory-limit", a.memory_limit,
                 "convert a source tractogram within SIZE of memory (bytes, or K/M/G: 512M, 2G), as 'voxlines convert "
                 "--memory-limit' does. " +
                     source_format_names_text("/", true) + " sources only (" + source_format_names_text("/", false) +
                     " are refused). Without it, a limit is chosen from the file's size and the available memory")
      ->type_name("SIZE");
  cli.add_option("--gpu-memory", a.gpu_memory,
                 "GPU memory the lines may take (bytes, or K/M/G: 512M, 2G): the finest level of detail that fits is "
                 "drawn (a file converted with levels keeps 1/8 of the streamlines per level, opacity compensated); "
                 "with a selection, the focus is drawn at full detail first and the context at the level that "
                 "fits the rest. Default: half the free memory the driver reports, or a quarter of the available RAM "
                 "on a driver "
                 "that reports none (Mesa llvmpipe)")
      ->type_name("SIZE");
  cli.add_option("--span-texels", a.options.span_texels,
                 "the most texels one GPU texture span holds (at most the driver's texture-buffer limit): the "
                 "granule that a GPU memory budget too small for the whole scene uploads and evicts, nearest "
                 "visible spans first. Default: the driver's limit when full detail fits the budget (fewest "
                 "spans, cheapest to draw), else 4M; --render draws a level that fits the budget whole in the "
                 "driver's limit too")
      ->check(CLI::Range(std::uint64_t(1024), std::uint64_t(1) << 31));
  cli.add_option("--level", a.options.level,
                 "draw this level of detail (0: every streamline; level d keeps about 1/8^d of them), whatever the "
                 "GPU memory budget; at most the file's coarsest level")
      ->check(CLI::Range(0u, kMaxLevels - 1));
}

// The window's frame budget, refinement and scripting: refused with --render, which draws one picture and quits
// (what they ask for would not happen).
void declare_window(CLI::App& cli, ViewerArguments& a) {
  CLI::Option* const render = cli.get_option("--render");
  cli.add_option("--frame-budget", a.options.frame_budget_ms,
                 "window: while the camera moves, draw the finest level of detail whose measured frame time fits this "
                 "many milliseconds; at rest, the level --gpu-memory allows (0: always that level)")
      ->default_val(100.0)
      ->check(number_above_zero("milliseconds", true))
      ->excludes(render);
  cli.add_flag("--no-exact-when-still{false}", a.options.exact_when_still,
               "window: at rest, stop at the full-detail picture; by default, where OpenGL 4.3 is there, the basic "
               "and axis modes go on to the exact picture, run by run, dropped at the first movement (key E)")
      ->excludes(render);
  cli.add_option("--partial-pictures", a.partial_pictures,
                 "window: at rest, while the finer level being refined to uploads (the spans nearest the view first), "
                 "show the part of it that is in, the picture's level standing in for the rest: auto (once the upload "
                 "has taken as long as such a picture is expected to take to draw), always (whenever spans arrived), "
                 "never (keep the picture until the level is complete)")
      ->check(CLI::IsMember({"auto", "always", "never"}))
      ->default_val("auto")
      ->excludes(render);
  cli.add_option(
         "--orbit", a.options.orbit_deg,
         "window: turn the camera by this many degrees of azimuth every frame (a scripted orbit, with --frames, "
         "for benchmarks); the last frame is drawn at rest (with --until-refined the camera rests after --frames)")
      ->excludes(render);
  cli.add_option("--drag-region", a.drag_region,
                 "window: move the active region by DX,DY,DZ mm every frame (a scripted drag, with --frames, for "
                 "benchmarks: --stats then has the selections' times); the picture takes each new selection when it "
                 "is ready, the frames keep their budget; after the frames it draws frames until the last "
                 "position's selection and focus copy are in the picture (at most 60 s; --stats: drag_end_wait)")
      ->delimiter(',')
      ->expected(3)
      ->excludes(render);
  cli.add_option("--stats", a.options.stats_json,
                 "write to this JSON file what the GPU was sent (upload: bytes, spans, seconds, gb_per_s) and when "
                 "(since the process started) the program was loaded (main_s); with --render, when the files were "
                 "open, the GL context made and the scene ready, and per picture the time to draw it, read it back, "
                 "wait for the draw checks and write it, and when it was written; in the window, on quitting, every "
                 "frame's level of detail (with focus_level 0 where the focus was drawn first, at full detail) and "
                 "time, when the first picture reached the screen (first_on_screen_s), when it was drawn and the "
                 "first full-detail and exact pictures' times, the moving frames', the refinement pieces' and the "
                 "selections' median and 95th percentile (of all, and of those after the first, which also boxes "
                 "the voxels its regions touch)");
  cli.add_option("--frames", a.options.frames, "window: quit after this many frames (for scripts and tests)")
      ->check(number_above_zero("frames"))
      ->excludes(render);
  cli.add_flag("--until-refined", a.options.until_refined,
               "window, with --frames: after the frames, keep the camera still until the picture is refined (full "
               "detail, then exact unless --no-exact-when-still), then quit")
      ->needs("--frames")
      ->excludes(render);
  cli.add_option("--screenshot", a.options.screenshot,
                 "window: save the last frame to this picture before quitting: " + picture_formats_text())
      ->excludes(render);
}

}  // namespace

void declare_voxview_options(CLI::App& cli, ViewerArguments& arguments) {
  cli.name("voxview");
  // In the order --help lists them.
  declare_input_output(cli, arguments);
  declare_picture(cli, arguments);
  declare_selection(cli, arguments);
  declare_lines(cli, arguments);
  declare_image_and_clipping(cli, arguments);
  declare_loading(cli, arguments);
  declare_window(cli, arguments);
}

void parse_voxview_command_line(CLI::App& cli, ViewerArguments& arguments, int argc, const char* const* argv) {
  cli.parse(cli11_arguments(argc, argv));
  for (const CLI::Option* option : cli.get_options())
    if (option->count() > 0) arguments.given.insert(option->get_name());
}

}  // namespace vxl::app
