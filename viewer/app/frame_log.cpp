#include "viewer/app/frame_log.h"

#include <algorithm>
#include <cmath>

#include <nlohmann/json.hpp>

#include "format/atomic_output.h"

namespace vxl::app {

FrameSummary summarize_frames(const std::vector<FrameRecord>& frames, std::uint32_t scene_level) {
  FrameSummary s;
  std::vector<double> moving;
  for (const FrameRecord& f : frames) {
    if (s.first_picture_s < 0) s.first_picture_s = f.since_start_s;
    if (s.full_detail_s < 0 && !f.moving && f.level == scene_level) s.full_detail_s = f.since_start_s;
    if (f.moving) moving.push_back(f.ms);
  }
  s.moving_frames = moving.size();
  if (!moving.empty()) {
    std::sort(moving.begin(), moving.end());
    auto at = [&](double q) {
      return moving[std::min(moving.size() - 1, std::size_t(std::ceil(q * moving.size())) - 1)];
    };
    s.moving_median_ms = at(0.5);
    s.moving_p95_ms = at(0.95);
  }
  return s;
}

void write_frame_stats(const std::string& path, const std::vector<FrameRecord>& frames, std::uint32_t scene_level,
                       double frame_budget_ms) {
  const FrameSummary s = summarize_frames(frames, scene_level);
  nlohmann::json j;
  j["scene_level"] = scene_level;
  j["frame_budget_ms"] = frame_budget_ms;
  j["first_picture_s"] = s.first_picture_s;
  j["full_detail_s"] = s.full_detail_s;
  j["moving_frames"] = s.moving_frames;
  j["moving_median_ms"] = s.moving_median_ms;
  j["moving_p95_ms"] = s.moving_p95_ms;
  nlohmann::json list = nlohmann::json::array();
  for (const FrameRecord& f : frames)
    list.push_back({{"level", f.level}, {"moving", f.moving}, {"ms", f.ms}, {"since_start_s", f.since_start_s}});
  j["frames"] = list;
  const std::string text = j.dump(2) + "\n";
  AtomicOutputFile out(path);
  out.write(text.data(), text.size());
  out.commit();
}

}  // namespace vxl::app
