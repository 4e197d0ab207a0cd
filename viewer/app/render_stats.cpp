#include "viewer/app/render_stats.h"

#include <nlohmann/json.hpp>

#include "viewer/app/frame_log.h"

namespace vxl::app {

void write_render_stats(const std::string& path, const RenderStats& stats) {
  nlohmann::ordered_json j;
  j["gl_renderer"] = stats.gl_renderer;
  j["mode"] = stats.mode;
  j["size"] = {stats.width, stats.height};
  j["level"] = stats.level;
  j["startup"] = {{"main_s", stats.main_s},
                  {"files_open_s", stats.files_open_s},
                  {"context_s", stats.context_s},
                  {"scene_ready_s", stats.scene_ready_s}};
  j["upload"] = upload_summary(stats.uploads);
  j["first_picture_written_s"] = stats.pictures.empty() ? -1.0 : stats.pictures.front().written_s;
  nlohmann::ordered_json list = nlohmann::ordered_json::array();
  for (const RenderedPicture& p : stats.pictures)
    list.push_back({{"draw_ms", p.draw_ms},
                    {"read_back_ms", p.read_back_ms},
                    {"checks_wait_ms", p.checks_wait_ms},
                    {"write_ms", p.write_ms},
                    {"written_s", p.written_s},
                    {"voxels", p.voxels},
                    {"segments", p.segments}});
  j["pictures"] = list;
  write_stats_json(path, j);
}

}  // namespace vxl::app
