#include "viewer/app/region_editor.h"

#include <algorithm>
#include <cstdio>
#include <utility>

namespace vxl::app {

std::string EditorRegion::argument() const {
  if (!centre) return text;
  char s[160];
  std::snprintf(s, sizeof s, "%.3f,%.3f,%.3f,%.3f", (*centre)[0], (*centre)[1], (*centre)[2], radius);
  return s;
}

const char* EditorRegion::role_name() const {
  return role == Role::Include ? "include" : role == Role::Exclude ? "exclude" : "ends in";
}

RegionEditor::RegionEditor(const ViewerOptions& o) {
  auto add = [&](const std::vector<std::string>& texts, EditorRegion::Role role) {
    for (const std::string& t : texts) {
      EditorRegion r;
      r.role = role;
      r.text = t;
      regions_.push_back(std::move(r));
    }
  };
  add(o.include, EditorRegion::Role::Include);
  add(o.exclude, EditorRegion::Role::Exclude);
  add(o.ends_in, EditorRegion::Role::EndsIn);
  parse_all();
  if (!regions_.empty()) active_ = regions_.size() - 1;
}

// Masks and boxes are parsed once; a sphere given on the command line becomes an editable one.
void RegionEditor::parse_all() {
  parsed_.clear();
  for (EditorRegion& r : regions_) {
    Region region = parse_region(r.text);
    if (region.shape() == Region::Shape::Sphere) {
      float v[4];
      if (std::sscanf(r.text.c_str(), "%f,%f,%f,%f", &v[0], &v[1], &v[2], &v[3]) == 4) {
        r.centre = std::array<double, 3>{v[0], v[1], v[2]};
        r.radius = v[3];
        parsed_.emplace_back();
        continue;
      }
    }
    if (region.shape() == Region::Shape::Box) {
      std::array<double, 6> c{};
      if (std::sscanf(r.text.c_str(), "box:%lf,%lf,%lf,%lf,%lf,%lf", &c[0], &c[1], &c[2], &c[3], &c[4], &c[5]) == 6)
        r.box = c;
    }
    parsed_.emplace_back(std::move(region));
  }
}

void RegionEditor::add_sphere(const std::array<double, 3>& centre, double radius) {
  EditorRegion r;  // fields by name: a brace list would have to spell out every later member
  r.role = EditorRegion::Role::Include;
  r.centre = centre;
  r.radius = radius;
  regions_.push_back(std::move(r));
  parsed_.emplace_back();
  active_ = regions_.size() - 1;
  ++revision_;
}

void RegionEditor::remove_active() {
  if (!active_) return;
  regions_.erase(regions_.begin() + std::ptrdiff_t(*active_));
  parsed_.erase(parsed_.begin() + std::ptrdiff_t(*active_));
  if (regions_.empty())
    active_.reset();
  else
    active_ = std::min(*active_, regions_.size() - 1);
  ++revision_;
}

void RegionEditor::activate(std::size_t index) {
  if (index < regions_.size()) active_ = index;
}

void RegionEditor::activate_next() {
  if (!regions_.empty()) active_ = active_ ? (*active_ + 1) % regions_.size() : 0;
}

void RegionEditor::toggle_role() {
  if (!active_) return;
  EditorRegion& r = regions_[*active_];
  r.role = r.role == EditorRegion::Role::Include ? EditorRegion::Role::Exclude : EditorRegion::Role::Include;
  ++revision_;
}

void RegionEditor::scale_radius(double factor) {
  if (active_ && regions_[*active_].centre) set_radius(regions_[*active_].radius * factor);
}

void RegionEditor::set_radius(double radius) {
  if (!active_ || !regions_[*active_].centre) return;
  regions_[*active_].radius = std::max(0.0, radius);
  ++revision_;
}

void RegionEditor::move_active_to(const std::array<double, 3>& centre) {
  if (!active_ || !regions_[*active_].centre || *regions_[*active_].centre == centre) return;
  regions_[*active_].centre = centre;
  ++revision_;
}

void RegionEditor::move_active_by(const std::array<double, 3>& offset) {
  if (!active_ || !regions_[*active_].centre) return;
  const std::array<double, 3>& c = *regions_[*active_].centre;
  move_active_to({c[0] + offset[0], c[1] + offset[1], c[2] + offset[2]});
}

std::vector<RegionShape> RegionEditor::shapes() const {
  std::vector<RegionShape> out;
  for (std::size_t i = 0; i < regions_.size(); ++i) {
    const EditorRegion& r = regions_[i];
    RegionShape s;
    s.role = r.role == EditorRegion::Role::Include   ? RegionShape::Role::Include
             : r.role == EditorRegion::Role::Exclude ? RegionShape::Role::Exclude
                                                     : RegionShape::Role::EndsIn;
    s.active = active_ == i;
    if (r.centre) {
      s.kind = RegionShape::Kind::Sphere;
      s.centre = {(*r.centre)[0], (*r.centre)[1], (*r.centre)[2]};
      s.radius = r.radius;
    } else if (r.box) {
      const std::array<double, 6>& b = *r.box;
      s.kind = RegionShape::Kind::Box;
      s.lo = {b[0], b[1], b[2]};
      s.hi = {b[3], b[4], b[5]};
    } else {
      continue;  // a mask
    }
    out.push_back(s);
  }
  return out;
}

SelectionCriteria RegionEditor::criteria() const {
  SelectionCriteria c;
  // In the order select_streamlines counts them: includes, ends-in, excludes.
  for (EditorRegion::Role role : {EditorRegion::Role::Include, EditorRegion::Role::EndsIn, EditorRegion::Role::Exclude})
    for (std::size_t i = 0; i < regions_.size(); ++i) {
      if (regions_[i].role != role) continue;
      Region r = parsed_[i] ? *parsed_[i] : parse_region(regions_[i].argument());
      (role == EditorRegion::Role::Include   ? c.include
       : role == EditorRegion::Role::Exclude ? c.exclude
                                             : c.ends_in)
          .push_back(std::move(r));
    }
  return c;
}

void RegionEditor::set_counts(const std::vector<std::uint64_t>& per_region) {
  std::size_t k = 0;
  for (EditorRegion::Role role : {EditorRegion::Role::Include, EditorRegion::Role::EndsIn, EditorRegion::Role::Exclude})
    for (EditorRegion& r : regions_)
      if (r.role == role && k < per_region.size()) r.streamlines = per_region[k++];
}

}  // namespace vxl::app
