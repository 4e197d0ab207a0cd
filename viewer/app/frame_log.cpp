#include "viewer/app/frame_log.h"

#include <algorithm>
#include <cmath>
#include <tuple>
#include <utility>

#include <nlohmann/json.hpp>

#include "format/base/atomic_output.h"

namespace vxl::app {

namespace {

// The median and 95th percentile of `ms` (0 when empty).
std::pair<double, double> median_and_p95(std::vector<double> ms) {
  if (ms.empty()) return {0, 0};
  std::sort(ms.begin(), ms.end());
  auto at = [&](double q) { return ms[std::min(ms.size() - 1, std::size_t(std::ceil(q * ms.size())) - 1)]; };
  return {at(0.5), at(0.95)};
}

const char* work_name(FrameWork w) {
  switch (w) {
    case FrameWork::Whole: return "whole";
    case FrameWork::FullDetailPiece: return "full-detail piece";
    case FrameWork::ExactPiece: return "exact piece";
    case FrameWork::FocusPiece: return "focus piece";
    case FrameWork::PartialPiece: return "partial piece";
  }
  return "?";
}

}  // namespace

FrameSummary summarize_frames(const std::vector<FrameRecord>& frames, std::uint32_t scene_level) {
  FrameSummary s;
  std::vector<double> moving, pieces;
  // Full detail: a complete picture at rest at the finest level any reached, if that is the scene's level
  // or finer (the window refines a slab or a close view to a finer level than the whole scene's).
  std::uint32_t finest = scene_level;
  for (const FrameRecord& f : frames)
    if (f.completes && !f.moving && f.work != FrameWork::PartialPiece) finest = std::min(finest, f.level);
  for (const FrameRecord& f : frames) {
    if (s.first_picture_s < 0) s.first_picture_s = f.since_start_s;
    const bool full_detail = f.completes && !f.moving && f.level == finest && f.work != FrameWork::PartialPiece;
    if (s.full_detail_s < 0 && full_detail) s.full_detail_s = f.since_start_s;
    if (s.exact_s < 0 && full_detail && f.work == FrameWork::ExactPiece) s.exact_s = f.since_start_s;
    if (f.moving) moving.push_back(f.ms);
    if (f.work != FrameWork::Whole) pieces.push_back(f.ms);
  }
  s.moving_frames = moving.size();
  std::tie(s.moving_median_ms, s.moving_p95_ms) = median_and_p95(moving);
  s.pieces = pieces.size();
  std::tie(s.piece_median_ms, s.piece_p95_ms) = median_and_p95(pieces);
  return s;
}

nlohmann::ordered_json upload_summary(const UploadTally& uploads) {
  return {{"bytes", uploads.bytes()},
          {"spans", uploads.spans()},
          {"seconds", uploads.seconds()},
          {"gb_per_s", uploads.gb_per_s()}};
}

void write_frame_stats(const std::string& path, const std::vector<FrameRecord>& frames, std::uint32_t scene_level,
                       double frame_budget_ms, const StartupTimes& startup, const UploadTally& uploads,
                       const std::vector<double>& selection_ms, const std::vector<std::uint32_t>& selection_levels,
                       const std::optional<DragEndWait>& drag_end) {
  const FrameSummary s = summarize_frames(frames, scene_level);
  nlohmann::ordered_json j;
  j["scene_level"] = scene_level;
  j["frame_budget_ms"] = frame_budget_ms;
  // The figure a user sees: the first picture as it reaches the screen, everything before it included.
  j["first_on_screen_s"] = startup.first_on_screen_s;
  j["startup"] = {{"main_s", startup.main_s},
                  {"window_open_s", startup.window_open_s},
                  {"viewer_ready_s", startup.viewer_ready_s},
                  {"first_on_screen_s", startup.first_on_screen_s}};
  j["upload"] = upload_summary(uploads);
  j["first_picture_s"] = s.first_picture_s;
  j["full_detail_s"] = s.full_detail_s;
  j["exact_s"] = s.exact_s;
  j["moving_frames"] = s.moving_frames;
  j["moving_median_ms"] = s.moving_median_ms;
  j["moving_p95_ms"] = s.moving_p95_ms;
  j["refinement_pieces"] = s.pieces;
  j["piece_median_ms"] = s.piece_median_ms;
  j["piece_p95_ms"] = s.piece_p95_ms;
  const auto [selection_median, selection_p95] = median_and_p95(selection_ms);
  j["selections"] = selection_ms.size();
  j["selection_median_ms"] = selection_median;
  j["selection_p95_ms"] = selection_p95;
  j["selection_ms"] = selection_ms;  // each selection taken into the picture, in order
  // The first selection (the regions as the window opens, or as a region first appears) also boxes the voxels it
  // touches (voxline_boxes.h): with few selections it is their p95. Those after it are the ones a drag's moves ask for.
  if (selection_ms.size() > 1) {
    const auto [later_median, later_p95] = median_and_p95({selection_ms.begin() + 1, selection_ms.end()});
    j["later_selection_median_ms"] = later_median;
    j["later_selection_p95_ms"] = later_p95;
  }
  // The level each searched (0: every streamline; a drag's searched the moving frames' level alone), and the figures
  // of those that searched every streamline.
  if (!selection_levels.empty()) {
    j["selection_level"] = selection_levels;
    std::vector<double> every;
    for (std::size_t k = 0; k < selection_ms.size() && k < selection_levels.size(); ++k)
      if (selection_levels[k] == 0) every.push_back(selection_ms[k]);
    const auto [every_median, every_p95] = median_and_p95(every);
    j["full_selections"] = every.size();
    j["full_selection_median_ms"] = every_median;
    j["full_selection_p95_ms"] = every_p95;
  }
  if (drag_end)
    j["drag_end_wait"] = {{"waited", drag_end->waited}, {"ms", drag_end->ms}, {"timed_out", drag_end->timed_out}};
  nlohmann::ordered_json list = nlohmann::ordered_json::array();
  for (const FrameRecord& f : frames) {
    list.push_back({{"level", f.level},
                    {"moving", f.moving},
                    {"work", work_name(f.work)},
                    {"completes", f.completes},
                    {"ms", f.ms},
                    {"since_start_s", f.since_start_s}});
    if (f.focus_first) list.back()["focus_level"] = 0;  // focus first: `level` is the context's
    if (f.selection) list.back()["selection"] = true;
    if (f.new_selection) list.back()["new_selection"] = true;
    if (f.work == FrameWork::PartialPiece) {
      list.back()["voxels_in"] = f.voxels_in;
      list.back()["voxels_standing_in"] = f.voxels_standing_in;
    }
  }
  j["frames"] = list;
  write_stats_json(path, j);
}

void write_stats_json(const std::string& path, const nlohmann::ordered_json& stats) {
  const std::string text = stats.dump(2) + "\n";
  AtomicOutputFile out(path);
  out.write(text.data(), text.size());
  out.commit();
}

}  // namespace vxl::app
