// Every frame the window draws — its level of detail, whether the camera moved, whether it drew a picture
// whole or a piece of the refinement at rest (rest_refinement.h), its time, and when it ended since voxview
// started — and the JSON summary a benchmark reads (voxview --stats): the first picture's time, the first
// full-detail picture's (at rest, at the finest level reached: the scene's, or finer where the view's
// visible part fits the budget) and the first exact one's, and the median and 95th
// percentile of the moving frames and of the refinement's pieces (how long input waits at rest).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "viewer/render/upload_tally.h"

namespace vxl::app {

enum class FrameWork {
  Whole,            // a picture drawn whole, shown at once
  FullDetailPiece,  // a piece of the full-detail picture at rest
  ExactPiece,       // a piece of the exact picture at rest
  FocusPiece,       // a piece of the picture drawn whole again with the focus's full-detail copy
  PartialPiece,     // a piece of a partial picture at rest: a level's spans in so far (partial_pictures.h)
};

struct FrameRecord {
  std::uint32_t level = 0;
  bool moving = false;
  double ms = 0;             // drawing the frame, GPU work included
  double since_start_s = 0;  // when it was on screen
  FrameWork work = FrameWork::Whole;
  bool completes = true;       // the picture it drew is complete and on screen (a piece: only the last one's)
  bool focus_first = false;    // the focus drawn at level 0 from its copy, the context at `level`
  bool selection = false;      // the picture shows a selection of the regions (focus and context)
  bool new_selection = false;  // its selection (or the focus copy) was taken into the picture for this frame
  // A partial picture's voxels: drawn from the level uploading, and from the level on screen standing in.
  std::uint64_t voxels_in = 0, voxels_standing_in = 0;
};

struct FrameSummary {
  double first_picture_s = -1, full_detail_s = -1, exact_s = -1;  // -1: none
  std::size_t moving_frames = 0, pieces = 0;
  double moving_median_ms = 0, moving_p95_ms = 0;
  double piece_median_ms = 0, piece_p95_ms = 0;
};

// Where the time before the first picture on screen went, in seconds since the process started
// (process_clock.h); -1 where not reached.
struct StartupTimes {
  double main_s = -1;             // the program and its shared libraries loaded: main() is about to run
  double window_open_s = -1;      // the window and its GL context exist (the scene files are open before it)
  double viewer_ready_s = -1;     // the first level uploaded, the shaders built, the panel made
  double first_on_screen_s = -1;  // the buffer swap that shows the first drawn picture has completed
};

// The end of a scripted drag (--drag-region with --frames): its last position's selection and focus copy are
// made off the window's thread, so after the last step the window keeps drawing frames until they are in the
// picture (or a time limit passes), then draws the last picture.
struct DragEndWait {
  bool waited = false;     // the selection or the focus copy was still being made after the last step
  double ms = 0;           // how long the window waited for them
  bool timed_out = false;  // the limit passed first: the last picture may not show them
};

FrameSummary summarize_frames(const std::vector<FrameRecord>& frames, std::uint32_t scene_level);

// The upload's figures as --stats writes them: {"bytes", "spans", "seconds", "gb_per_s"}.
nlohmann::ordered_json upload_summary(const UploadTally& uploads);
// Writes a --stats file (indented JSON, its keys in the order they were set: the summary first, the long lists last, so
// that the start of the file says the most) atomically. Throws vxl::Error (Output).
void write_stats_json(const std::string& path, const nlohmann::ordered_json& stats);

// Writes the summary, the budget, what was uploaded to the GPU and every frame as JSON to `path` (atomically),
// and the selections' run times (selection_worker.h: how long after a region moved its picture was ready), and
// for a scripted drag how its end waited. Throws vxl::Error (Output).
void write_frame_stats(const std::string& path, const std::vector<FrameRecord>& frames, std::uint32_t scene_level,
                       double frame_budget_ms, const StartupTimes& startup = {}, const UploadTally& uploads = {},
                       const std::vector<double>& selection_ms = {},
                       const std::vector<std::uint32_t>& selection_levels = {},
                       const std::optional<DragEndWait>& drag_end = std::nullopt);

}  // namespace vxl::app
