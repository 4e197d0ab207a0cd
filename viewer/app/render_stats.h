// What `voxview FILE --render OUT.png --stats S.json` writes: where the time from the process start to each
// picture written went — loading the program, opening the files, the GL context, the scene's upload (bytes and
// rate), and per picture its drawing, reading back, waiting for the draw checks and writing — so that a
// benchmark reads a headless start the way it reads the window's (frame_log.h).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "viewer/render/upload_tally.h"

namespace vxl::app {

struct RenderedPicture {
  double draw_ms = 0;         // the frame drawn, the GPU's work included
  double read_back_ms = 0;    // its pixels read back
  double checks_wait_ms = 0;  // waiting for the draw checks of what was uploaded (a damaged file writes nothing)
  double write_ms = 0;        // the picture file encoded and written
  double written_s = 0;       // when it was written, in seconds since the process started
  std::uint64_t voxels = 0, segments = 0;
};

struct RenderStats {
  std::string gl_renderer;  // GL_RENDERER
  std::string mode;         // the transparency mode drawn
  int width = 0, height = 0;
  std::uint32_t level = 0;  // the level of detail drawn (the context's, with a focus drawn first)
  // Seconds since the process started (process_clock.h); -1 where not reached.
  double main_s = -1;         // the program and its shared libraries loaded
  double files_open_s = -1;   // the files opened and validated (and any selection made)
  double context_s = -1;      // the GL context made
  double scene_ready_s = -1;  // the level chosen and its renderer made, the scene uploaded where it fits
  UploadTally uploads;        // what was uploaded to the GPU up to the last picture
  std::vector<RenderedPicture> pictures;
};

// Writes `stats` as JSON to `path` (atomically). Throws vxl::Error (Output).
void write_render_stats(const std::string& path, const RenderStats& stats);

}  // namespace vxl::app
