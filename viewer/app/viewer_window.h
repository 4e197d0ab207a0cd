// The window's viewer: one open window on one scene. Internal to the window's sources, which share it:
// window_app.cpp (set-up, the frame loop, drawing, saving), window_input.cpp (mouse, keys and their
// actions) and window_selection.cpp (the regions' selection).
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#define GLFW_INCLUDE_NONE  // epoxy provides the GL declarations
#include <GLFW/glfw3.h>

#include "viewer/app/camera_controller.h"
#include "viewer/app/focus_copy_worker.h"
#include "viewer/app/frame_log.h"
#include "viewer/app/key_bindings.h"
#include "viewer/app/partial_pictures.h"
#include "viewer/app/picture_annotations.h"
#include "viewer/app/picture_scheduler.h"
#include "viewer/app/region_editor.h"
#include "viewer/app/scene_selection.h"
#include "viewer/app/selection_worker.h"
#include "viewer/app/ui_panel.h"
#include "viewer/app/viewer_options.h"
#include "viewer/app/viewer_session.h"
#include "viewer/platform/offscreen_target.h"
#include "viewer/render/grid_overlay.h"

namespace vxl::app {

// What a picture on screen depends on: when none of it changes, the window refines the picture instead of
// drawing it again.
struct PictureKey {
  Camera camera;
  RenderSettings settings;
  int width = 0, height = 0;
  bool grid = false, grid_all = false;
  std::uint64_t selection = 0;  // the selection the picture was drawn with (its generation; the regions' shells
                                // are in the settings)
};
// Whether two cameras show the same view (what the frame budget calls "not moving"), and two pictures.
bool same_view(const Camera& a, const Camera& b);
bool same_picture(const PictureKey& a, const PictureKey& b);

// One open window on one scene: GL objects, camera, panel, input. Callbacks reach it through the GLFW
// user pointer.
class ViewerWindow {
 public:
  // `session`: the scene, its level of detail already chosen (ViewerSession::choose_detail); its renderers
  // go with the window, before the GL context.
  // `regions`: the selection's regions (region_editor.h), edited in the window.
  ViewerWindow(const ViewerOptions& o, std::unique_ptr<ViewerSession> session, RegionEditor regions, GLFWwindow* window,
               StartupTimes startup);
  int run();

 private:
  static ViewerWindow& of(GLFWwindow* w) { return *static_cast<ViewerWindow*>(glfwGetWindowUserPointer(w)); }
  void on_mouse_button(int button, int action, int mods);
  void on_cursor(double x, double y);
  void begin_region_drag(double x, double y);
  void on_scroll(double steps);
  void on_key(int key, int action, int mods);
  void on_char(unsigned codepoint);
  // Carries out a key's action (key_bindings.h); `shift` makes a move 10 times larger.
  void perform(KeyAction action, bool shift);
  void toggle_slices();
  void toggle_clip_plane(std::size_t i);
  void move_focus_along(int axis, double mm);
  // Asks for a new selection when the regions changed, or the level it should search did, and takes the newest
  // finished one into the picture (selection_worker.h); with `wait`, the one the regions ask for now. While a
  // region is `dragging`, the selection searches only the streamlines of the level the moving frames draw
  // (selection_level): their pictures need no more; once it stops, every streamline.
  void update_selection(bool wait, bool dragging);
  // The level a selection searches: while a region is dragged, the moving frames' (where every file has it and its
  // voxlines of it are small); else 0.
  std::uint32_t selection_level(bool dragging) const;
  // The selection shown searched one level's streamlines alone: a picture may not be drawn finer, nothing is
  // refined, and a selection of every streamline is still to come (or on its way).
  bool level_selection_shown() const { return selection_ && selection_->level > 0; }
  void read_ahead_selection_tables_once();
  // Hands the focus and context to every renderer (without a selection: the files' own groups again), and
  // asks for the selection's focus copy (focus first, focus_copy_worker.h).
  void apply_selection(std::optional<SceneSelection> selection);
  // Takes the newest focus copy of the current selection into the picture; with `wait`, the one asked for.
  void update_focus_copy(bool wait);
  // A scripted drag's end (--drag-region, after --frames): whether the last position's selection and focus copy
  // are in the picture, or the wait for them has reached its limit (then said). The first call starts the wait;
  // the frames go on meanwhile, so the window stays responsive. Records the wait for --stats.
  bool drag_end_settled();
  // Whether a selection or a focus copy is being made or waits to be taken into the picture: an idle window then
  // looks for it every kWorkPollSeconds instead of sleeping until the next input (FramePacing::next_wait).
  // One level's selection shown counts once the user's drag is over (the selection of every streamline is then due);
  // while the mouse holds a region still there is nothing to look for.
  bool work_in_flight() const {
    return selection_revision_ != regions_.revision() || selection_worker_.busy() || focus_copies_.busy() ||
           (level_selection_shown() && !dragging_region_);
  }
  static constexpr double kWorkPollSeconds = 0.02;
  // Whether a picture at `level` draws the focus from its full-detail copy (focus first).
  bool focus_first_at(std::uint32_t level) const { return level > 0 && session_->has_focus(); }
  // The same for a picture drawn whole, which must keep to the frame budget: below the scene's level, only where
  // the copy's lines fit the budget at the rate the last whole picture was drawn at. Else the focus is drawn from
  // the context's level, as while dragging, and the refinement at rest (in pieces) brings the copy in: on a
  // software rasteriser a large focus copy drawn whole froze the window for seconds (9M segments: 4 s).
  bool focus_first_whole_at(std::uint32_t level) const;
  // Whether the focus copy's lines fit the frame budget at the last whole picture's rate.
  bool focus_copy_fits_budget() const;
  double segments_per_ms_ = 0;      // the last whole picture's drawing rate (0: none measured yet)
  bool drawn_focus_first_ = false;  // the last picture drawn (whole or its last piece) drew the focus first
  // Writes the selected streamlines of every file to a stamped .tck (a key or the panel).
  void save_selection();

  Camera home_camera(double aspect, bool orthographic) const;
  void reset_camera(double aspect);
  double aspect() const;
  void set_error(const std::string& message);
  // Draws the scene whole at `level` of detail into scene_target_; returns the frame's time in ms. moving: the
  // camera moves (what the panel says of a level coarser than the scene's).
  double draw_scene(int width, int height, std::uint32_t level, bool moving);
  // Draws the next piece of the refinement at rest (rest_refinement.h) into refine_target_, or uploads more of its
  // level; once a picture is complete it becomes scene_target_'s. While the level uploads, the picture may be a
  // partial one (partial_pictures.h), which leaves the stage under way.
  struct PieceDrawn {
    double ms = 0;                                        // the piece's time (or the upload's), GPU work included
    bool completes = false;                               // a picture is complete and on screen
    bool partial = false;                                 // the piece is a partial picture's
    std::uint64_t voxels_in = 0, voxels_standing_in = 0;  // a partial picture's, drawn from either level
  };
  PieceDrawn refine(int width, int height, std::uint32_t level);
  // Whether to draw a partial picture now (partial_pictures.h) of `renderer`'s `view_spans` (the refinement's level,
  // drawn in `mode`, uploading): its stand-in, the renderer of the picture on screen, and the view's spans in. No
  // stand-in where none is wanted yet, or none can be drawn: another stage, focus first, a mode not drawn in pieces of
  // voxels, or a stand-in whose spans for this view are not all resident.
  struct PartialPicture {
    Renderer* stand_in = nullptr;
    std::uint64_t spans_in = 0;
  };
  PartialPicture partial_picture(Renderer& renderer, std::span<const std::uint32_t> view_spans, std::uint32_t level,
                                 RenderMode mode, double aspect);
  // The grid overlay and the annotations (picture_annotations.h) over scene_target_'s picture, when they are on.
  void draw_overlays(const Renderer& renderer, int width, int height);
  // The panel's figures of a complete picture drawn by `renderer` at `level`. coarser_why: what the panel adds to
  // a level coarser than the scene's (" while the camera moves", ", refining at rest").
  void show_frame_figures(const Renderer& renderer, std::uint32_t level, const std::string& coarser_why);
  // scene_target_ into the window's back buffer.
  void present(int width, int height) const;
  // The renderer of the scene's level, or of a coarser one (made on first use, for the frame budget); `whole`: for a
  // picture drawn whole (focus_first_whole_at), else for the refinement's pieces. Records in drawn_focus_first_
  // whether it draws the focus first.
  Renderer& renderer_at(std::uint32_t level, bool whole);
  void save_screenshot(const std::string& path, int width, int height);
  // save_screenshot to a stamped name in the current directory; a failure is shown, not thrown.
  void save_stamped_screenshot(int width, int height);
  // Writes the current view (camera, settings, size) to --save-camera's path or a stamped name.
  void save_view(int width, int height);
  // Builds the panel for this frame and carries out what it asks (`aspect`: the framebuffer's).
  void build_panel(double aspect);
  // Carries out the scheduler's task for the picture `key` describes; true when something was drawn.
  bool draw_picture(const PictureTask& task, const PictureKey& key, bool moving);

  const ViewerOptions& options_;
  GLFWwindow* window_;
  std::unique_ptr<ViewerSession> session_;  // the files, the image, the level of detail, the renderers
  const std::vector<const VxlFile*>& files_;
  RegionEditor regions_;
  std::optional<SceneSelection> selection_;          // the newest finished; the regions may have moved since
  std::optional<std::uint64_t> selection_revision_;  // the regions' revision last asked for
  std::uint32_t selection_level_asked_ = 0;          // the level it searched (0: every streamline)
  std::uint32_t moving_level_ = 0;                 // the level of the last moving frame asked for (first: the first's)
  std::optional<std::uint64_t> cleared_revision_;  // all regions removed at this revision: older selections are stale
  std::uint64_t selection_generation_ = 0;         // counts the selections taken into the picture
  std::uint64_t framed_generation_ = 0;            // the selection generation of the last frame drawn whole
  SelectionWorker selection_worker_;
  // Focus first: copies of the selection for pictures coarser than full detail (none with --level, or
  // when the files hold no coarser level).
  bool focus_first_wanted_ = false;
  FocusCopyWorker focus_copies_;
  std::vector<double> selection_ms_;             // each selection's run time, for --stats
  std::vector<std::uint32_t> selection_levels_;  // and the level it searched (0: every streamline)
  // A scripted drag's end waits at most this long for its selection and focus copy (a large selection's copy
  // takes seconds on two cores).
  static constexpr std::chrono::seconds kDragEndWaitLimit{60};
  std::optional<std::chrono::steady_clock::time_point> drag_end_since_;  // the drag's frames done
  std::optional<DragEndWait> drag_end_;                                  // the wait over, for --stats
  const SceneDetail& detail_;  // the level of detail drawn at rest, and the span size
  std::uint32_t first_level_ = 0;
  std::vector<FrameRecord> frames_;            // for --stats
  StartupTimes startup_;                       // for --stats
  std::optional<PictureKey> drawn_;            // what the picture on screen shows (none before the first)
  std::optional<PictureScheduler> scheduler_;  // what each frame draws (made once the GL version is known)
  std::optional<GridOverlay> grid_;
  std::optional<PictureAnnotations> annotations_;  // made when first wanted
  // The scene is drawn here and blitted to the window: it blends in float like headless rendering, so
  // faint layers add up beyond 8-bit rounding and the window shows what --render writes.
  std::optional<OffscreenTarget> scene_target_;
  std::optional<OffscreenTarget> refine_target_;  // the refinement's picture until it is complete
  PartialPictureRule partial_rule_;               // when to show a level's spans while they upload
  std::uint64_t partial_spans_ = 0;  // the pieces under way draw a partial picture of this many of the view's spans
  CameraController controller_;
  std::vector<glm::dvec3> framing_points_;  // what the home view fills the window with (scene_framing.h)
  std::unique_ptr<UiPanel> panel_;          // created after our callbacks, which ImGui then chains to
  PanelState state_;
  PanelStats stats_;
  int drag_button_ = -1;
  bool selection_tables_asked_ = false;  // read_ahead_selection_tables_once
  bool dragging_region_ = false;         // Ctrl + left drag: the active sphere follows the cursor
  glm::dvec2 region_cursor_{0.0};        // the cursor at the drag's last move
  bool screenshot_requested_ = false;
  bool save_view_requested_ = false;
  RenderMode drawn_mode_ =
      RenderMode::Axis;          // the mode of the last frame, to clear a mode's error once another is chosen
  unsigned events_ = 0;          // input events seen, to keep drawing while something happens
  SliceSettings hidden_slices_;  // which slices I brings back
};

}  // namespace vxl::app
