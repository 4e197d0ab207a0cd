// The selection regions of the voxview window: those of the command line (--include, --exclude, --ends-in)
// and the spheres added in the window, one of them active (moved with the focus, resized, switched between
// include and exclude, removed). Pure logic, no GL and no ImGui: the window and the panel call it, the
// tests drive it directly.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "converter/selection/streamline_selection.h"
#include "viewer/app/viewer_options.h"
#include "viewer/render/region_shapes.h"

namespace vxl::app {

struct EditorRegion {
  enum class Role { Include, Exclude, EndsIn };
  Role role = Role::Include;
  std::string text;                             // the argument as given (masks, boxes and given spheres)
  std::optional<std::array<double, 3>> centre;  // a sphere the window can move and resize
  double radius = 0;
  std::uint64_t streamlines = 0;             // streamlines with a point in it, at the last selection
  std::optional<std::array<double, 6>> box;  // a box's corners X0,Y0,Z0,X1,Y1,Z1 (drawn, not edited)
  // The region as `voxlines select` takes it: X,Y,Z,R for a sphere, else the text.
  std::string argument() const;
  const char* role_name() const;
};

class RegionEditor {
 public:
  explicit RegionEditor(const ViewerOptions& options);

  const std::vector<EditorRegion>& regions() const { return regions_; }
  std::optional<std::size_t> active() const { return active_; }
  bool empty() const { return regions_.empty(); }
  // Changes with every edit: the selection is computed again when it differs from the last one used.
  std::uint64_t revision() const { return revision_; }

  void add_sphere(const std::array<double, 3>& centre, double radius = 10.0);
  void remove_active();
  void activate(std::size_t index);
  void activate_next();
  void toggle_role();  // the active region: include <-> exclude (ends-in becomes exclude)
  // The radius factor of one key press (, and .) or one wheel step with Shift.
  static constexpr double kRadiusStep = 1.25;
  void scale_radius(double factor);                          // the active sphere
  void set_radius(double radius);                            // the active sphere; at least 0
  void move_active_to(const std::array<double, 3>& centre);  // the active sphere, if it is one
  void move_active_by(const std::array<double, 3>& offset);  // the active sphere, if it is one

  // The spheres and boxes as the renderer draws them (region_shapes.h), the active one marked; masks have
  // no shape to draw and are left out.
  std::vector<RegionShape> shapes() const;

  // The regions as selection criteria (parsed; throws vxl::Error naming a bad one), and back, each region's
  // count from the selection's per-region counts.
  SelectionCriteria criteria() const;
  void set_counts(const std::vector<std::uint64_t>& per_region);

 private:
  void parse_all();
  std::vector<EditorRegion> regions_;
  std::vector<std::optional<Region>> parsed_;  // per region, when it is not a sphere (masks are read once)
  std::optional<std::size_t> active_;
  std::uint64_t revision_ = 0;
};

}  // namespace vxl::app
