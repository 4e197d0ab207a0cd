#include "viewer/app/camera_file.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "format/base/atomic_output.h"
#include "format/base/error.h"
#include "format/base/json_limits.h"
#include "viewer/render/background_color.h"

namespace vxl::app {

namespace {

using nlohmann::json;

constexpr int kVersion = 1;

// A float as the shortest decimal that reads back as the same float (0.3f is written 0.3, not
// 0.30000001192092896), so that hand-edited files stay readable.
double shortest(float f) {
  char buf[32];
  auto r = std::to_chars(buf, buf + sizeof buf, f);
  *r.ptr = '\0';
  return std::strtod(buf, nullptr);
}

std::string shortest_text(double d) {
  char buf[32];
  auto r = std::to_chars(buf, buf + sizeof buf, d);
  return std::string(buf, r.ptr);
}

json vec(const glm::dvec3& v) { return json::array({v.x, v.y, v.z}); }
json vec(const glm::vec3& v) { return json::array({shortest(v.x), shortest(v.y), shortest(v.z)}); }

// Reads keys of one object, each error naming the file and the dotted key.
class Reader {
 public:
  Reader(const json& object, std::string path, std::string prefix)
      : o_(object), path_(std::move(path)), prefix_(std::move(prefix)) {}

  [[noreturn]] void fail(const std::string& key, const std::string& expected) const {
    fail_input(path_, std::nullopt, prefix_ + key + ": expected " + expected);
  }
  const json* find(const std::string& key) const {
    auto it = o_.find(key);
    return it == o_.end() ? nullptr : &*it;
  }
  void number(const std::string& key, double& out) const {
    if (const json* v = find(key)) {
      if (!v->is_number() || !std::isfinite(v->get<double>())) fail(key, "a finite number");
      out = v->get<double>();
    }
  }
  void number(const std::string& key, float& out) const {
    double d = out;
    number(key, d);
    out = static_cast<float>(d);
  }
  void boolean(const std::string& key, bool& out) const {
    if (const json* v = find(key)) {
      if (!v->is_boolean()) fail(key, "true or false");
      out = v->get<bool>();
    }
  }
  const std::string* text(const std::string& key) const {
    const json* v = find(key);
    if (!v) return nullptr;
    if (!v->is_string()) fail(key, "a string");
    return v->get_ptr<const std::string*>();
  }
  template <typename Vec>
  void triple(const std::string& key, Vec& out) const {
    if (const json* v = find(key)) {
      if (!v->is_array() || v->size() != 3) fail(key, "an array of 3 numbers");
      for (int i = 0; i < 3; ++i) {
        if (!(*v)[i].is_number() || !std::isfinite((*v)[i].get<double>())) fail(key, "an array of 3 finite numbers");
        out[i] = static_cast<typename Vec::value_type>((*v)[i].get<double>());
      }
    }
  }
  Reader object(const std::string& key) const {
    const json* v = find(key);
    static const json empty = json::object();
    if (!v) return Reader(empty, path_, prefix_ + key + ".");
    if (!v->is_object()) fail(key, "an object");
    return Reader(*v, path_, prefix_ + key + ".");
  }
  const std::string& path() const { return path_; }
  const std::string& prefix() const { return prefix_; }

 private:
  const json& o_;
  std::string path_, prefix_;
};

void read_camera(const Reader& r, Camera& c) {
  r.triple("target", c.target);
  r.number("distance", c.distance);
  r.number("azimuth_deg", c.azimuth_deg);
  r.number("elevation_deg", c.elevation_deg);
  r.number("fov_y_deg", c.fov_y_deg);
  r.boolean("orthographic", c.orthographic);
  r.number("ortho_height", c.ortho_height);
  using L = ViewLimits;
  const std::string mm = "mm in [" + shortest_text(L::kMinMm) + ", " + shortest_text(L::kMaxMm) + "]";
  for (int i = 0; i < 3; ++i)
    if (!(std::abs(c.target[i]) <= L::kMaxMm))
      r.fail("target", "coordinates within +-" + shortest_text(L::kMaxMm) + " mm");
  if (!(c.distance >= L::kMinMm && c.distance <= L::kMaxMm)) r.fail("distance", mm);
  if (!(c.ortho_height >= L::kMinMm && c.ortho_height <= L::kMaxMm)) r.fail("ortho_height", mm);
  if (!(c.fov_y_deg >= L::kMinFovDeg && c.fov_y_deg <= L::kMaxFovDeg))
    r.fail("fov_y_deg", "degrees in [" + shortest_text(L::kMinFovDeg) + ", " + shortest_text(L::kMaxFovDeg) + "]");
  if (!(std::abs(c.azimuth_deg) <= L::kMaxAzimuthDeg))
    r.fail("azimuth_deg", "degrees within +-" + shortest_text(L::kMaxAzimuthDeg));
  if (std::abs(c.elevation_deg) > 90) r.fail("elevation_deg", "degrees in [-90, 90]");
}

void read_settings(const Reader& r, RenderSettings& s) {
  if (const std::string* mode = r.text("mode")) {
    auto m = parse_render_mode(*mode);
    if (!m) {
      std::string names;
      for (const std::string& name : render_mode_names()) names += (names.empty() ? "" : ", ") + name;
      r.fail("mode", "one of " + names);
    }
    s.mode = *m;
  }
  r.number("opacity", s.opacity);
  if (!(s.opacity >= 0.001f && s.opacity <= 1.0f)) r.fail("opacity", "a number in [0.001, 1]");
  if (const std::string* color = r.text("color")) {
    auto c = parse_color_mode(*color);
    if (!c) r.fail("color", "direction, fixed, scalar or group");
    s.color = *c;
  }
  r.triple("fixed_color", s.fixed_color);
  if (const std::string* map = r.text("colormap")) {
    auto m = parse_colormap(*map);
    if (!m) r.fail("colormap", "grey, hot or viridis");
    s.colormap = *m;
  }
  if (const std::string* scalar = r.text("scalar")) s.scalar = *scalar;
  if (const json* range = r.find("range")) {
    if (range->is_null()) {
      s.range.reset();
    } else {
      if (!range->is_array() || range->size() != 2 || !(*range)[0].is_number() || !(*range)[1].is_number() ||
          !((*range)[0].get<double>() < (*range)[1].get<double>()))
        r.fail("range", "[min, max] with min < max, or null (the values' own range)");
      s.range = std::array<float, 2>{(*range)[0].get<float>(), (*range)[1].get<float>()};
    }
  }
  if (const json* groups = r.find("groups")) {
    if (!groups->is_array()) r.fail("groups", "an array of {\"name\", \"color\", \"opacity\"}");
    s.group_styles.clear();
    for (std::size_t i = 0; i < groups->size(); ++i) {
      const std::string key = "groups[" + std::to_string(i) + "]";
      if (!(*groups)[i].is_object()) r.fail(key, "an object {\"name\", \"color\", \"opacity\"}");
      Reader g((*groups)[i], r.path(), r.prefix() + key + ".");
      GroupStyle style;
      const std::string* name = g.text("name");
      if (!name) g.fail("name", "the group's name");
      style.name = *name;
      if (const std::string* color = g.text("color")) {
        style.color = parse_hex_color(*color);
        if (!style.color) g.fail("color", "#RRGGBB");
      }
      g.number("opacity", style.opacity);
      if (!(style.opacity >= 0.0f && style.opacity <= 1.0f)) g.fail("opacity", "a factor in [0, 1]");
      s.group_styles.push_back(style);
    }
  }
  r.number("line_width", s.line_width);
  if (!(s.line_width >= 1.0f && s.line_width <= 16.0f)) r.fail("line_width", "pixels in [1, 16]");
  if (const std::string* bg = r.text("background")) {
    const auto colour = parse_background_color(*bg);
    if (!colour) r.fail("background", background_color_forms());
    s.background_color = *colour;
  }
  r.boolean("lighting", s.lighting);
  r.boolean("orientation_labels", s.orientation_labels);
  r.boolean("colorbar", s.colorbar);
  r.number("order_hysteresis", s.order_hysteresis);
  r.number("slab_mm", s.clipping.slab_mm);
  if (!slab_is_drawable(s.clipping.slab_mm)) r.fail("slab_mm", slab_range_text() + " (0: no slab)");
  if (const json* clip = r.find("clip")) {
    if (!clip->is_array() || clip->size() > Clipping::kMaxPlanes) r.fail("clip", "an array of at most 3 planes");
    s.clipping.planes.clear();
    for (std::size_t i = 0; i < clip->size(); ++i) {
      const std::string key = "clip[" + std::to_string(i) + "]";
      if (!(*clip)[i].is_object()) r.fail(key, "an object {\"plane\": \"AXIS,POS\", \"enabled\": true}");
      Reader p((*clip)[i], r.path(), r.prefix() + key + ".");
      const std::string* text = p.text("plane");
      std::optional<AxisClip> plane = text ? parse_axis_clip(*text) : std::nullopt;
      if (!plane) p.fail("plane", "AXIS,POS with AXIS one of x y z -x -y -z (e.g. \"-z,12.5\")");
      p.boolean("enabled", plane->enabled);
      s.clipping.planes.push_back(*plane);
    }
  }
}

}  // namespace

bool slab_is_drawable(double mm) { return mm == 0 || (mm >= ViewLimits::kMinMm && mm <= ViewLimits::kMaxMm); }

std::string slab_range_text() {
  return "a thickness in [" + shortest_text(ViewLimits::kMinMm) + ", " + shortest_text(ViewLimits::kMaxMm) + "] mm";
}

std::string view_json(const SavedView& v) {
  const Camera& c = v.camera;
  const RenderSettings& s = v.settings;
  json j;
  j["voxview_view"] = kVersion;
  if (v.size) j["size"] = {(*v.size)[0], (*v.size)[1]};
  j["camera"] = {{"target", vec(c.target)},          {"distance", c.distance},   {"azimuth_deg", c.azimuth_deg},
                 {"elevation_deg", c.elevation_deg}, {"fov_y_deg", c.fov_y_deg}, {"orthographic", c.orthographic},
                 {"ortho_height", c.ortho_height}};
  json clip = json::array();
  for (const AxisClip& p : s.clipping.planes) clip.push_back({{"plane", axis_clip_text(p)}, {"enabled", p.enabled}});
  json groups = json::array();
  for (const GroupStyle& g : s.group_styles) {
    json entry = {{"name", g.name}, {"opacity", shortest(g.opacity)}};
    if (g.color) entry["color"] = hex_color(*g.color);
    groups.push_back(entry);
  }
  j["settings"] = {{"mode", render_mode_name(s.mode)},
                   {"opacity", shortest(s.opacity)},
                   {"color", color_mode_name(s.color)},
                   {"fixed_color", vec(s.fixed_color)},
                   {"colormap", colormap_name(s.colormap)},
                   {"scalar", s.scalar},
                   {"range", s.range ? json::array({shortest((*s.range)[0]), shortest((*s.range)[1])}) : json(nullptr)},
                   {"groups", groups},
                   {"line_width", shortest(s.line_width)},
                   {"background", background_color_text(s.background_color)},
                   {"lighting", s.lighting},
                   {"orientation_labels", s.orientation_labels},
                   {"colorbar", s.colorbar},
                   {"order_hysteresis", shortest(s.order_hysteresis)},
                   {"slab_mm", s.clipping.slab_mm},
                   {"clip", clip}};
  if (!v.include.empty() || !v.exclude.empty() || !v.ends_in.empty())
    j["selection"] = {{"include", v.include},
                      {"exclude", v.exclude},
                      {"ends_in", v.ends_in},
                      {"show_regions", v.show_regions.value_or(false)}};
  return j.dump(2) + "\n";
}

SavedView parse_view_json(const std::string& text, const std::string& path, const SavedView& defaults) {
  json j = parse_json(text, path, 0, "view file");
  if (j.is_discarded() || !j.is_object()) fail_input(path, std::nullopt, "not a JSON object (a voxview view file)");
  const Reader top(j, path, "");
  const json* version = top.find("voxview_view");
  if (!version || !version->is_number_integer())
    fail_input(path, std::nullopt, "not a voxview view file (no \"voxview_view\": 1; write one with --save-camera)");
  if (version->get<long long>() != kVersion)
    throw Error(ErrorKind::Unsupported, path, std::nullopt,
                "view file version " + version->dump() + " (this voxview reads version 1)");
  SavedView v = defaults;
  if (const json* size = top.find("size")) {
    if (!size->is_array() || size->size() != 2 || !(*size)[0].is_number_integer() || !(*size)[1].is_number_integer())
      top.fail("size", "[width, height] in pixels");
    const long long w = (*size)[0].get<long long>(), h = (*size)[1].get<long long>();
    if (w < 1 || h < 1 || w > 16384 || h > 16384) top.fail("size", "[width, height], each 1..16384");
    v.size = std::array<int, 2>{static_cast<int>(w), static_cast<int>(h)};
  }
  v.has_camera = top.find("camera") != nullptr;
  read_camera(top.object("camera"), v.camera);
  read_settings(top.object("settings"), v.settings);
  if (const json* selection = top.find("selection")) {
    if (!selection->is_object())
      top.fail("selection", "an object {\"include\": [...], \"exclude\": [...], \"ends_in\": [...]}");
    const Reader r(*selection, path, "selection.");
    for (auto [key, list] :
         {std::pair{"include", &v.include}, std::pair{"exclude", &v.exclude}, std::pair{"ends_in", &v.ends_in}}) {
      const json* regions = r.find(key);
      if (!regions) continue;
      if (!regions->is_array() ||
          !std::all_of(regions->begin(), regions->end(), [](const json& x) { return x.is_string(); }))
        r.fail(key, "an array of regions as voxlines select takes them (\"X,Y,Z,R\", \"box:...\", \"FILE.nii.gz\")");
      list->clear();
      for (const json& x : *regions) list->push_back(x.get<std::string>());
    }
    if (const json* shown = r.find("show_regions")) {
      if (!shown->is_boolean()) r.fail("show_regions", "true or false");
      v.show_regions = shown->get<bool>();
    }
  }
  return v;
}

SavedView read_view(const std::string& path, const SavedView& defaults) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail_input(path, std::nullopt, "cannot open the view file");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) fail_input(path, std::nullopt, "cannot read the view file");
  return parse_view_json(text.str(), path, defaults);
}

void write_view(const std::string& path, const SavedView& view) {
  const std::string text = view_json(view);
  AtomicOutputFile out(path);
  out.write(text.data(), text.size());
  out.commit();
}

}  // namespace vxl::app
