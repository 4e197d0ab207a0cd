// `voxview`: look into a tractogram with correct-looking transparency, in a window or headless.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "format/error.h"
#include "viewer/app/camera_file.h"
#include "viewer/app/headless_render.h"
#include "viewer/app/viewer_options.h"
#include "viewer/app/window_app.h"

int main(int argc, char** argv) {
  using namespace vxl;
  app::ViewerOptions o;
  std::string mode = "axis", view, size = "1024x1024", color = "direction", background = "black", camera_file;
  std::string fixed_color, scalar, colormap = "viridis", range;
  std::vector<std::string> groups;
  float opacity = 0.3f, line_width = 1.0f;
  double slab = 0;
  bool lighting = false;
  CLI::App cli{
      "voxview " VOXLINES_VERSION
      " — transparent tractogram viewer (Voxlines method).\n"
      "voxview FILE... [--render OUT.png]: a window, or headless to PNG with --render.\n"
      "Opens a .vxl instantly (memory-mapped); a .tck/.trk/.trx/.vtk/.vtp is converted in memory first.\n"
      "Opening a .vxl checks its structure (header, section table, section sizes, voxel table, names) in\n"
      "O(voxels) but not its checksums: damaged positions, orders or values are drawn as they are. --verify\n"
      "checks everything first, as 'voxlines verify' does.\n"
      "Window: left drag orbits, right/middle drag (or Shift+left) pans, wheel zooms. Keys: 1/2/3 "
      "axial/sagittal/coronal,\n"
      "Shift+1/2/3 or 4/5/6 their opposites, O orthographic, M next mode, +/- opacity, L lighting, S screenshot, R "
      "reset,\n"
      "Esc/Q quit.\n"
      "Slab and clip planes: C slab on/off, [ ] thinner/thicker, PageUp/PageDown or Ctrl+wheel move the slab\n"
      "(the focus) along the view direction (Shift: 10x), F1/F2/F3 toggle clip planes 1/2/3. V saves the view (see\n"
      "--save-camera) for replaying headless with --camera.\n"
      "Image slices (--image): Up/Down move the focus (and the axial slice) along S/I, Right/Left along R/L (the\n"
      "sagittal slice), Home/End along A/P (the coronal slice), 1 mm a press (Shift: 10 mm); I shows/hides the\n"
      "slices."};
  cli.add_option("files", o.inputs,
                 "a .vxl file, a .vxlz package, or a .tck / .trk / .trk.gz / .trx / .vtk / .vtp tractogram; several "
                 "are shown together "
                 "(their voxels sorted back to front as one scene, one group per file for --color group and --group)")
      ->required();
  cli.add_option("--render", o.render_png, "render headless (EGL, no display needed) to this PNG and exit");
  cli.add_option("--turntable", o.turntable,
                 "with --render: N frames turning once around the vertical (superior) axis, written as OUT_000.png, "
                 "OUT_001.png, ... (frame i at azimuth + 360 i / N degrees; frame 0 looks from the --view direction; "
                 "all frames share one framing in which each is whole)")
      ->check(CLI::Range(1, 100000));
  cli.add_option("--camera", camera_file,
                 "start from a saved view (camera and settings; JSON, see --save-camera); options given as well "
                 "override it");
  cli.add_option("--save-camera", o.save_camera,
                 "write the view (camera and settings) to this JSON file: headless after rendering, in the window on "
                 "V, the panel's Save view button, or on quitting after --frames");
  cli.add_option("--mode", mode, "opaque | unsorted | additive | wboit | basic | axis | exact")
      ->default_val("axis")
      ->check(CLI::IsMember({"opaque", "unsorted", "additive", "wboit", "basic", "axis", "exact"}));
  cli.add_option("--opacity", opacity, "line opacity, 1 down to 0.001")
      ->default_val(0.3)
      ->check(CLI::Range(0.001, 1.0));
  cli.add_option("--view", view,
                 "axial, inferior, sagittal (left), right, coronal (anterior), posterior, or AZ,EL in degrees");
  cli.add_option("--size", size, "image or window size WxH")->default_val("1024x1024");
  cli.add_flag("--ortho", o.orthographic, "orthographic projection (default perspective)");
  cli.add_option(
         "--color", color,
         "direction (|p1 - p0| as RGB), fixed (--fixed-color), scalar (a value set through --colormap) or group "
         "(one colour per TRX group, or per file when several are shown)")
      ->default_val("direction")
      ->check(CLI::IsMember({"direction", "fixed", "scalar", "group"}));
  cli.add_option("--fixed-color", fixed_color, "the fixed colour, #RRGGBB (also for points without a value)")
      ->check([](const std::string& v) {
        return parse_hex_color(v) ? std::string() : "expected #RRGGBB, got '" + v + "'";
      });
  cli.add_option("--scalar", scalar,
                 "the value set to colour by (a TSF's file name, a TRK scalar or property, a TRX dpv or dps name); "
                 "default: the first");
  cli.add_option("--colormap", colormap, "grey, hot or viridis, for --color scalar")
      ->default_val("viridis")
      ->check(CLI::IsMember({"grey", "gray", "hot", "viridis"}));
  cli.add_option("--range", range,
                 "MIN,MAX: the values at the colour map's ends (default: the set's minimum and maximum)");
  cli.add_option(
         "--group", groups,
         "NAME=#RRGGBB[:OPACITY] or NAME=:OPACITY: a group's colour and opacity (a factor on --opacity; 0 hides "
         "it), repeatable")
      ->expected(1)
      ->take_all();
  cli.add_option("--tsf", o.tsf,
                 "a TSF file of per-point values for a .tck given as input (converted in memory), repeatable")
      ->expected(1)
      ->take_all();
  cli.add_flag(
      "--lighting", lighting,
      "light the lines (illuminated lines: a line along the light, which comes from the viewer's upper left, is "
      "dark, one across it bright)");
  cli.add_option("--line-width", line_width, "line width in pixels")->default_val(1.0)->check(CLI::Range(1.0, 16.0));
  cli.add_option("--background", background, "black or white")
      ->default_val("black")
      ->check(CLI::IsMember({"black", "white"}));
  std::string image_range, slices, focus;
  cli.add_option(
      "--image", o.image,
      "an anatomical image (NIfTI-1 or -2, .nii or .nii.gz, e.g. a T1) shown as opaque grey slices through the "
      "focus point under the lines (lines behind a slice are hidden by it, lines in front blend over it)");
  cli.add_option(
      "--image-range", image_range,
      "MIN,MAX: the image values shown black and white (default: the 2nd and 98th percentiles of the image's "
      "non-zero voxels)");
  cli.add_option(
      "--slices", slices,
      "which slices of --image to show: a comma list of axial, coronal, sagittal and view (the plane through the "
      "focus facing the viewer: with --slab, the slice in its middle), or none; default axial,coronal,sagittal");
  cli.add_option("--focus", focus,
                 "X,Y,Z: the focus point in RAS mm (the view's centre, where the slices cross, the slab's centre); "
                 "default the centre of the tractograms' bounds");
  std::vector<std::string> clips;
  cli.add_option("--slab", slab,
                 "crop to a slab MM thick, centred on the focus point (the view's centre), perpendicular to the view "
                 "direction (mrview's crop to slab)")
      ->check(CLI::PositiveNumber);
  cli.add_option(
         "--clip", clips,
         "clip plane AXIS,POS in RAS mm, up to 3: x,10 keeps x >= 10, -x,10 keeps x <= 10 (axes x y z, -x -y -z)")
      ->expected(1)
      ->take_all();
  cli.add_flag("--verify", o.verify,
               "before drawing, check every .vxl in full (every checksum and padding byte, every order, the streamline "
               "tables; reads the whole file, as 'voxlines verify') and refuse a damaged one (exit 3, naming the first "
               "problem); a .vxlz's unpacked file too (a package's own checksums are always checked)");
  cli.add_option("--voxel-size", o.voxel_size, "voxel size in mm when converting a source file in memory")
      ->default_val(10.0)
      ->check(CLI::PositiveNumber);
  cli.add_option("--frames", o.frames, "window: quit after this many frames (for scripts and tests)")
      ->check(CLI::PositiveNumber);
  cli.add_option("--screenshot", o.screenshot, "window: save the last frame to this PNG before quitting");
  try {
    // "--clip -x,10", "--focus -5,0,0": CLI11 would take "-x,10" for an option; pass it as "--clip=-x,10".
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
    cli.name("voxview");
    cli.parse(args);
    auto given = [&](const char* name) { return cli.get_option(name)->count() > 0; };
    if (o.turntable && !o.render_png)
      throw Error(ErrorKind::Usage, "", std::nullopt,
                  "--turntable needs --render OUT.png (it writes OUT_000.png, ...)");

    // Settings: the defaults, then a saved view, then what the command line gives explicitly.
    RenderSettings& s = o.settings;
    s.opacity = opacity;
    if (!camera_file.empty()) {
      app::SavedView defaults;
      defaults.settings = s;
      app::SavedView saved = app::read_view(camera_file, defaults);
      s = saved.settings;
      o.camera = saved.camera;
      if (saved.size && !given("--size"))
        size = std::to_string((*saved.size)[0]) + "x" + std::to_string((*saved.size)[1]);
    }
    const bool from_file = o.camera.has_value();
    if (!from_file || given("--mode")) s.mode = *parse_render_mode(mode);
    if (!from_file || given("--opacity")) s.opacity = opacity;
    if (!from_file || given("--color")) s.color = *parse_color_mode(color);
    if (given("--fixed-color")) s.fixed_color = *parse_hex_color(fixed_color);
    if (given("--scalar")) s.scalar = scalar;
    if (!from_file || given("--colormap")) s.colormap = *parse_colormap(colormap);
    if (given("--range")) {
      float lo = 0, hi = 0;
      char end = 0;
      if (std::sscanf(range.c_str(), "%f,%f%c", &lo, &hi, &end) != 2 || !std::isfinite(lo) || !std::isfinite(hi) ||
          !(hi > lo))
        throw Error(ErrorKind::Usage, "", std::nullopt,
                    "--range: expected MIN,MAX with MIN < MAX (e.g. 0,0.5); got '" + range + "'");
      s.range = std::array<float, 2>{lo, hi};
    }
    for (const std::string& g : groups) {
      auto style = parse_group_style(g);
      if (!style)
        throw Error(
            ErrorKind::Usage, "", std::nullopt,
            "--group: expected NAME=#RRGGBB, NAME=#RRGGBB:OPACITY or NAME=:OPACITY (opacity 0..1); got '" + g + "'");
      GroupStyle& existing = s.style_of(style->name);
      if (style->color) existing.color = style->color;
      existing.opacity = style->opacity;
    }
    if (!from_file || given("--background")) s.white_background = background == "white";
    if (!from_file || given("--line-width")) s.line_width = line_width;
    if (lighting) s.lighting = true;
    if (given("--slab")) s.clipping.slab_mm = slab;
    if (clips.size() > Clipping::kMaxPlanes)
      throw Error(ErrorKind::Usage, "", std::nullopt,
                  "--clip: at most 3 clip planes (got " + std::to_string(clips.size()) + ")");
    if (!clips.empty()) s.clipping.planes.clear();
    for (const std::string& c : clips) {
      auto plane = parse_axis_clip(c);
      if (!plane)
        throw Error(
            ErrorKind::Usage, "", std::nullopt,
            "--clip: expected AXIS,POS with AXIS one of x y z -x -y -z and POS in mm (e.g. -z,12.5); got '" + c + "'");
      s.clipping.planes.push_back(*plane);
    }
    if (given("--image-range")) {
      float lo = 0, hi = 0;
      char end = 0;
      if (std::sscanf(image_range.c_str(), "%f,%f%c", &lo, &hi, &end) != 2 || !std::isfinite(lo) ||
          !std::isfinite(hi) || !(hi > lo))
        throw Error(ErrorKind::Usage, "", std::nullopt,
                    "--image-range: expected MIN,MAX with MIN < MAX (e.g. 0,800); got '" + image_range + "'");
      s.slices.range = std::array<float, 2>{lo, hi};
    }
    if (given("--slices")) {
      SliceSettings& sl = s.slices;
      sl.axial = sl.coronal = sl.sagittal = sl.view_plane = false;
      std::size_t start = 0;
      while (slices != "none") {
        const std::size_t comma = slices.find(',', start);
        const std::string name = slices.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
        if (name == "axial")
          sl.axial = true;
        else if (name == "coronal")
          sl.coronal = true;
        else if (name == "sagittal")
          sl.sagittal = true;
        else if (name == "view")
          sl.view_plane = true;
        else
          throw Error(
              ErrorKind::Usage, "", std::nullopt,
              "--slices: expected a comma list of axial, coronal, sagittal, view, or none; got '" + slices + "'");
        if (comma == std::string::npos) break;
        start = comma + 1;
      }
    }
    if (given("--focus")) {
      double x = 0, y = 0, z = 0;
      char end = 0;
      if (std::sscanf(focus.c_str(), "%lf,%lf,%lf%c", &x, &y, &z, &end) != 3 || !std::isfinite(x) ||
          !std::isfinite(y) || !std::isfinite(z))
        throw Error(ErrorKind::Usage, "", std::nullopt,
                    "--focus: expected X,Y,Z in mm (e.g. 0,-10,12.5); got '" + focus + "'");
      o.focus = glm::dvec3(x, y, z);
    }
    if ((given("--image-range") || given("--slices")) && !o.image)
      throw Error(ErrorKind::Usage, "", std::nullopt, "--image-range and --slices need --image FILE.nii[.gz]");
    if (!view.empty()) {
      o.view = parse_view(view);
      if (!o.view) throw Error(ErrorKind::Usage, "", std::nullopt, "--view: unknown view '" + view + "'");
    }
    if (std::sscanf(size.c_str(), "%dx%d", &o.width, &o.height) != 2 || o.width < 1 || o.height < 1 ||
        o.width > 16384 || o.height > 16384)
      throw Error(ErrorKind::Usage, "", std::nullopt, "--size must be WxH, each 1..16384");
    return o.render_png ? app::run_headless(o) : app::run_window(o);
  } catch (const CLI::ParseError& e) {
    int code = cli.exit(e);
    return code == 0 ? 0 : static_cast<int>(ErrorKind::Usage);
  } catch (const Error& e) {
    std::fprintf(stderr, "voxview: error: %s\n", e.what());
    return static_cast<int>(e.kind());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "voxview: error: %s\n", e.what());
    return 6;
  }
}
