// Everything `voxview` is told on its command line, shared by the headless and the window paths.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "viewer/app/partial_pictures.h"
#include "viewer/render/camera.h"
#include "viewer/render/render_settings.h"

namespace vxl::app {

// The colour settings a saved view (--camera FILE) gave and the command line left. A scene that cannot
// honour them makes the file the problem (exit 3, naming it), not the command line (exit 2).
struct ViewFileSettings {
  std::string path;  // empty: no view file
  bool color = false, scalar = false;
  std::vector<std::string> groups;
};

struct ViewerOptions {
  std::vector<std::string>
      inputs;  // .vxl, .vxlz, or a source (readers/source_formats.h) converted first; several: one scene
  // How the inputs are named in messages and titles: the first file's name, "+ N more" for the others.
  std::string inputs_name() const;
  std::optional<std::string> image;       // an anatomical NIfTI image shown as slices under the lines
  std::optional<glm::dvec3> focus;        // the focus point (camera target, slices, slab centre), RAS mm
  std::optional<std::string> render_png;  // headless: render one frame to this PNG and exit
  RenderSettings settings;
  std::optional<std::array<double, 2>> view;  // azimuth, elevation; default: an oblique view
  std::optional<Camera> camera;               // a saved view's camera (--camera); --view and --ortho still apply
  int turntable = 0;                          // headless: frames around the vertical axis (0: one plain frame)
  std::optional<std::string> save_camera;     // write the view here (headless: after rendering)
  bool orthographic = false;
  int width = 1024, height = 1024;
  bool size_given = false;       // by --size or a saved view: the window keeps it (else it fits the screen)
  double voxel_size = 10.0;      // for converting a source tractogram
  bool voxel_size_auto = false;  // --voxel-size auto: chosen from the data, as `voxlines convert` chooses it
  // --memory-limit: a source tractogram is streamed within this many bytes (converter/convert/source_to_vxl.h);
  // 0: only a TCK too big for the available memory is.
  std::uint64_t memory_limit = 0;
  // Level of detail (.vxl spec §5.12): the one --level names, else the finest within the GPU memory budget
  // (--gpu-memory, else a share of what the driver reports; scene_detail.h).
  std::optional<std::uint32_t> level;
  std::optional<std::uint64_t> gpu_memory;  // bytes
  // The most texels a GPU texture span holds (the driver's limit when smaller): the granule a tight budget
  // uploads and evicts (gpu_scene.h). None: chosen (scene_detail.h).
  std::optional<std::uint64_t> span_texels;
  bool verify = false;           // --verify: check every .vxl in full (as `voxlines verify`) before drawing
  std::vector<std::string> tsf;  // per-point values for a source tractogram (read whole with it)
  // Window: while the camera moves, draw the finest level whose measured frame time fits this budget
  // (frame_budget.h); at rest, the scene's level. 0: no budget.
  double frame_budget_ms = 100;
  // Window, at rest: after full detail, draw the exact mode run by run where GL 4.3 is there (rest_refinement.h).
  bool exact_when_still = true;
  // Window, at rest: while the level refined to is uploading, show the spans in so far (partial_pictures.h).
  PartialPictures partial_pictures = PartialPictures::Auto;
  std::optional<double> orbit_deg;  // window: turn the camera by this azimuth every frame (benchmarks)
  // Window: move the active region by this offset (mm) every frame, a scripted drag (benchmarks).
  std::optional<std::array<double, 3>> drag_region_mm;
  std::optional<std::string> stats_json;  // --stats: the window's frames on quitting, or the pictures --render wrote
  // What the options given change nothing in (a colour option of another colour mode, headless): printed as notes.
  std::vector<std::string> notes;
  // Window automation (tests, scripted screenshots): quit after N frames, saving a screenshot first.
  std::optional<int> frames;
  bool until_refined = false;  // with frames: after them, stay at rest until the refinement is done, then quit
  std::optional<std::string> screenshot;
  // A selection (`voxlines select`'s regions and rules): its streamlines are the focus, the others context,
  // with the opacities of the groups "selected" and "context" (scene_selection.h).
  std::vector<std::string> include, exclude, ends_in;
  bool selecting() const { return !include.empty() || !exclude.empty() || !ends_in.empty(); }
  // Headless: draw the regions' spheres and boxes as translucent shells (region_shells.h). The window
  // shows them unless the user hides them (H, the panel).
  bool show_regions = false;
  // A saved view's choice of shells (--camera): the window starts with it (else it shows them).
  std::optional<bool> saved_show_regions;
  ViewFileSettings from_view_file;
};

}  // namespace vxl::app
