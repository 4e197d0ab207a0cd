// The window's set-up, its frame loop, drawing and saving (the viewer is declared in viewer_window.h).
#include "viewer/app/window_app.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <epoxy/gl.h>

#include "format/base/error.h"
#include "viewer/app/camera_file.h"
#include "viewer/app/frame_budget.h"
#include "viewer/app/frame_pacing.h"
#include "viewer/app/glfw_window.h"
#include "viewer/app/headless_render.h"
#include "viewer/app/process_clock.h"
#include "viewer/app/scene_source.h"
#include "viewer/app/viewer_window.h"
#include "viewer/platform/image_io.h"
#include "viewer/render/background_color.h"
#include "viewer/render/renderer.h"
#include "viewer/render/scene_framing.h"

namespace vxl::app {

namespace {

// A damaged file (the checks of what was uploaded failed: vxl::Error, Input) is not drawn on in another mode:
// the error ends the window, as it ends headless rendering (exit 3). Called in a handler, it rethrows there.
void rethrow_if_damaged(const std::exception& e) {
  if (const auto* error = dynamic_cast<const Error*>(&e); error != nullptr && error->kind() == ErrorKind::Input) throw;
}

}  // namespace

bool same_view(const Camera& a, const Camera& b) {
  return a.target == b.target && a.distance == b.distance && a.azimuth_deg == b.azimuth_deg &&
         a.elevation_deg == b.elevation_deg && a.fov_y_deg == b.fov_y_deg && a.orthographic == b.orthographic &&
         a.ortho_height == b.ortho_height;
}

bool same_picture(const PictureKey& a, const PictureKey& b) {
  return same_view(a.camera, b.camera) && a.settings == b.settings && a.width == b.width && a.height == b.height &&
         a.grid == b.grid && a.grid_all == b.grid_all && a.selection == b.selection;
}

ViewerWindow::ViewerWindow(const ViewerOptions& o, std::unique_ptr<ViewerSession> session, RegionEditor regions,
                           GLFWwindow* window, StartupTimes startup)
    : options_(o),
      window_(window),
      session_(std::move(session)),
      files_(session_->files()),
      regions_(std::move(regions)),
      selection_worker_(files_, session_->indexes()),
      focus_first_wanted_(session_->focus_copy_needed(SceneLayout::coarsest_level(session_->files()))),
      focus_copies_(files_),
      detail_(session_->detail()),
      startup_(startup),
      partial_rule_(o.partial_pictures),
      controller_(Camera{}, 1.0) {
  if (o.saved_show_regions) state_.show_regions = *o.saved_show_regions;  // as the saved view had them
  stats_.detail = describe_scene_detail(detail_, session_->levels_in_files());
  if (!stats_.detail.empty()) std::fprintf(stderr, "voxview: %s\n", stats_.detail.c_str());
  first_level_ = first_picture_level(level_segments(files_), detail_.level);
  moving_level_ = first_level_;
  // The command line's selection runs on the worker: the first picture does not wait for it (the panel says it is
  // coming), the focus appears when it is ready. Scripted frames without a drag still wait for it, frame by frame.
  update_selection(false, o.drag_region_mm && regions_.active());
  // Scene-wide facts (bounds, groups, value sets, voxel cubes) are the same at every level.
  Renderer& first = renderer_at(first_level_, true);
  // The tables the selection reads, asked of the disk once the first level's bytes are in (they go first).
  if (!regions_.empty()) read_ahead_selection_tables_once();
  grid_.emplace(std::span<const VxlFile* const>(files_));  // the files opened: not a focus copy drawn beside them
  controller_ = CameraController(Camera{}, std::max(1.0, glm::length(first.scene_max() - first.scene_min()) * 0.5));
  stats_.has_image = session_->image() != nullptr;
  // With regions, the options' groups are the selection's, on their way.
  check_color_options(o.inputs_name(), first, o.settings, o.from_view_file,
                      o.selecting() ? std::vector<std::string>{SceneGroups::kSelected, SceneGroups::kContext}
                                    : std::vector<std::string>{});
  GLint major = 0, minor = 0;
  glGetIntegerv(GL_MAJOR_VERSION, &major);
  glGetIntegerv(GL_MINOR_VERSION, &minor);
  GLfloat widths[2] = {1, 1};
  glGetFloatv(GL_ALIASED_LINE_WIDTH_RANGE, widths);

  state_.settings = o.settings;
  drawn_mode_ = o.settings.mode;
  state_.orthographic = o.orthographic;
  stats_.title = std::filesystem::path(o.inputs.front()).filename().string();
  if (files_.size() > 1) stats_.title += " + " + std::to_string(files_.size() - 1) + " more";
  for (const VxlFile* f : files_) {
    stats_.voxels_total += f->meta().voxel_count;
    stats_.segments_total += f->meta().segment_count;
  }
  stats_.gl_renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  stats_.gl_version = std::to_string(major) + "." + std::to_string(minor);
  stats_.exact_available = major * 10 + minor >= 43;
  scheduler_.emplace(FrameBudget(o.frame_budget_ms, detail_.level, SceneLayout::coarsest_level(files_)),
                     RestRefinement(stats_.exact_available, o.exact_when_still), detail_.level, detail_.forced,
                     first_level_);
  state_.exact_when_still = o.exact_when_still;
  stats_.frame_budget_ms = o.frame_budget_ms;
  stats_.max_line_width = std::clamp(widths[1], 1.0f, 16.0f);
  stats_.value_sets = first.value_set_names();
  for (int c = 0; c < 3; ++c) {
    stats_.bounds_min[c] = first.bounds_min()[c];
    stats_.bounds_max[c] = first.bounds_max()[c];
  }
  if (o.settings.clipping.slab_mm > 0) state_.slab_thickness = o.settings.clipping.slab_mm;

  framing_points_ = framing_points(session_->layout_at(first_level_));  // the files', without a focus copy
  controller_.set_home(home_camera(aspect(), o.orthographic));
  controller_.reset();

  glfwSetWindowUserPointer(window_, this);
  glfwSetMouseButtonCallback(window_, [](GLFWwindow* w, int b, int a, int m) { of(w).on_mouse_button(b, a, m); });
  glfwSetCursorPosCallback(window_, [](GLFWwindow* w, double x, double y) { of(w).on_cursor(x, y); });
  // Some systems turn Shift + wheel into a horizontal scroll: take whichever axis moved.
  glfwSetScrollCallback(window_, [](GLFWwindow* w, double dx, double dy) { of(w).on_scroll(dy != 0 ? dy : dx); });
  glfwSetKeyCallback(window_, [](GLFWwindow* w, int k, int, int a, int m) { of(w).on_key(k, a, m); });
  glfwSetCharCallback(window_, [](GLFWwindow* w, unsigned c) { of(w).on_char(c); });
  glfwSetFramebufferSizeCallback(window_, [](GLFWwindow* w, int, int) { of(w).events_++; });
  glfwSetWindowRefreshCallback(window_, [](GLFWwindow* w) { of(w).events_++; });
  panel_ = std::make_unique<UiPanel>(window_);
  startup_.viewer_ready_s = seconds_since_process_start();
}

double ViewerWindow::aspect() const {
  int w = 0, h = 0;
  glfwGetFramebufferSize(window_, &w, &h);
  return h > 0 && w > 0 ? double(w) / h : 1.0;
}

Camera ViewerWindow::home_camera(double aspect, bool orthographic) const {
  ViewerOptions o = options_;
  o.orthographic = orthographic;
  return initial_camera(framing_points_, o, aspect);
}

void ViewerWindow::reset_camera(double aspect) {
  // Re-frames for the current window shape; keeps the projection the user chose.
  controller_.set_home(home_camera(aspect, controller_.camera().orthographic));
  controller_.reset();
}

void ViewerWindow::set_error(const std::string& message) {
  if (stats_.error != message) std::fprintf(stderr, "voxview: %s\n", message.c_str());
  stats_.error = message;
}

bool ViewerWindow::focus_copy_fits_budget() const {
  if (options_.frame_budget_ms <= 0) return true;
  const double rate = segments_per_ms_ > 0 ? segments_per_ms_ : Renderer::kAssumedSegmentsPerMs;
  return double(session_->focus_segments()) / rate <= options_.frame_budget_ms;
}

bool ViewerWindow::focus_first_whole_at(std::uint32_t level) const {
  // The picture at rest (a script's last frame, at the scene's level) always draws it.
  return focus_first_at(level) && (level <= detail_.level || focus_copy_fits_budget());
}

Renderer& ViewerWindow::renderer_at(std::uint32_t level, bool whole) {
  // Focus first: below full detail, the context at `level` and the focus from its full-detail copy.
  drawn_focus_first_ = whole ? focus_first_whole_at(level) : focus_first_at(level);
  if (drawn_focus_first_) return session_->focus_first_renderer(level, false);
  // The first picture's level is uploaded whole at once; the others span by span as frames need them
  // (the refinement at rest spreads its level's upload over frames).
  return session_->renderer_at(level, level == first_level_);
}

double ViewerWindow::draw_scene(int width, int height, std::uint32_t level, bool moving) {
  Renderer& renderer = renderer_at(level, true);
  RenderSettings& s = state_.settings;
  if (s.mode != drawn_mode_) stats_.error.clear();  // a new choice of mode gets a fresh start
  if (render_mode_info(s.mode).needs_gl43 && !stats_.exact_available) {
    set_error(std::string("the ") + render_mode_name(s.mode) + " mode needs OpenGL 4.3; this context is " +
              stats_.gl_version + ": showing axis");
    s.mode = RenderMode::Axis;
  }
  const auto t0 = std::chrono::steady_clock::now();
  const Camera& camera = controller_.camera();
  if (!scene_target_) scene_target_.emplace(width, height);
  if (scene_target_->width() != width || scene_target_->height() != height) scene_target_->resize(width, height);
  scheduler_->abandon_pieces();  // a whole picture abandons the refinement's pieces
  const GLuint target = scene_target_->framebuffer();
  try {
    renderer.draw(camera, s, width, height, target);
  } catch (const std::exception& e) {
    rethrow_if_damaged(e);
    // A mode that cannot run here (e.g. exact out of node memory): say so and keep showing something.
    set_error(std::string(render_mode_name(s.mode)) + ": " + e.what() + ": showing axis");
    s.mode = RenderMode::Axis;
    renderer.draw(camera, s, width, height, target);
  }
  drawn_mode_ = s.mode;
  draw_overlays(renderer, width, height);
  glFinish();  // the frame time should include the GPU's work, not only its submission
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  partial_rule_.picture_shown();
  partial_spans_ = 0;
  stats_.frame_ms = stats_.frame_ms == 0 ? ms : 0.9 * stats_.frame_ms + 0.1 * ms;
  if (ms > 0 && renderer.stats().segments_drawn > 0) segments_per_ms_ = double(renderer.stats().segments_drawn) / ms;
  // At rest a coarser level is the first picture's, or one drawn at once after a change: refined next.
  show_frame_figures(renderer, level, moving ? " while the camera moves" : ", drawn at once; refining at rest");
  return ms;
}

void ViewerWindow::draw_overlays(const Renderer& renderer, int width, int height) {
  scene_target_->bind();
  const RenderSettings& s = state_.settings;
  if (state_.grid) {
    const glm::vec4 colour =
        background_is_light(s.background()) ? glm::vec4(0.1f, 0.1f, 0.1f, 0.25f) : glm::vec4(0.8f, 0.8f, 0.8f, 0.25f);
    grid_->draw(renderer, controller_.camera(), double(width) / height,
                state_.grid_all ? GridOverlay::Scope::All : GridOverlay::Scope::Drawn, colour, s.clipping);
    stats_.grid_cubes = grid_->cubes_drawn();
  }
  // Over the grid too: the letters and the colour bar stay readable.
  if (PictureAnnotations::wanted(s)) {
    if (!annotations_) annotations_.emplace();
    annotations_->draw(controller_.camera(), s, renderer, width, height);
  }
}

void ViewerWindow::show_frame_figures(const Renderer& renderer, std::uint32_t level, const std::string& coarser_why) {
  const RenderSettings& s = state_.settings;
  const FrameStats& f = renderer.stats();
  stats_.scalar_range = renderer.scalar_range(s);
  stats_.image_range = renderer.slice_range(s);
  for (int a = 0; a < 3; ++a) stats_.focus[a] = controller_.camera().target[a];
  stats_.plan_ms = f.plan_ms;
  stats_.voxels_drawn = f.voxels_drawn;
  stats_.segments_drawn = f.segments_drawn;
  stats_.frame_level = level > detail_.level ? "level " + std::to_string(level) + coarser_why
                       : level < detail_.level
                           ? "level " + std::to_string(level) + ": the visible part fits the GPU memory budget"
                           : "";
  if (drawn_focus_first_)
    stats_.frame_level =
        "focus at full detail, context at level " + std::to_string(level) + (level > detail_.level ? coarser_why : "");
}

void ViewerWindow::present(int width, int height) const {
  glBindFramebuffer(GL_READ_FRAMEBUFFER, scene_target_->framebuffer());
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
  glBlitFramebuffer(0, 0, width, height, 0, 0, width, height, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

ViewerWindow::PartialPicture ViewerWindow::partial_picture(Renderer& renderer,
                                                           std::span<const std::uint32_t> view_spans,
                                                           std::uint32_t level, RenderMode mode, double aspect) {
  PartialPicture partial;
  std::uint64_t segments_in = 0, segments_all = 0;
  for (const std::uint32_t span : view_spans) {
    const std::uint64_t segments = renderer.layout().texture_spans()[span].segments;
    segments_all += segments;
    if (!renderer.span_resident(span)) continue;
    segments_in += segments;
    ++partial.spans_in;
  }
  if (!partial_rule_.spans_arrived(partial.spans_in)) return {};
  // The level on screen, coarser (not so in the focus stage, which draws that level again), drawn by the same files'
  // renderer: not focus first's, which has others (and is drawn at any level coarser than 0 once there is a focus).
  const std::uint32_t shown = scheduler_->drawn_level();
  if (shown <= level || scheduler_->rest().stage() != RestStage::FullDetail || focus_first_at(shown) ||
      !renderer.draws_in_voxel_pieces(mode))
    return {};
  Renderer& stand_in = session_->renderer_at(shown, false);
  const double rate = segments_per_ms_ > 0 ? segments_per_ms_ : Renderer::kAssumedSegmentsPerMs;
  const double expected_ms = partial_picture_ms(segments_in, segments_all, stand_in.stats().segments_drawn, rate);
  if (!partial_rule_.wants_picture(partial.spans_in, expected_ms)) return {};
  // Under a GPU memory budget the level's upload may have evicted some of the stand-in's spans this view needs.
  for (const std::uint32_t span : stand_in.spans_for(controller_.camera(), aspect, state_.settings.clipping))
    if (!stand_in.span_resident(span)) return {};
  partial.stand_in = &stand_in;
  return partial;
}

ViewerWindow::PieceDrawn ViewerWindow::refine(int width, int height, std::uint32_t level) {
  const auto t0 = std::chrono::steady_clock::now();
  const auto elapsed_ms = [&] {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  };
  Renderer& renderer = renderer_at(level, false);
  if (!refine_target_) refine_target_.emplace(width, height);
  if (refine_target_->width() != width || refine_target_->height() != height) refine_target_->resize(width, height);
  RestRefinement& rest = scheduler_->rest();
  const bool exact_stage = rest.stage() == RestStage::Exact;
  PieceDrawn piece;
  try {
    // Each piece fits the frame budget, so that input waits no longer at rest than while moving.
    const double piece_ms =
        options_.frame_budget_ms > 0 ? options_.frame_budget_ms : std::numeric_limits<double>::infinity();
    if (!scheduler_->pieces_begun()) {
      RenderSettings s = state_.settings;
      s.mode = rest.stage_mode();
      // The level's spans this view needs come first, a piece's time at a time (the nearest first), each with its
      // per-vertex words where the settings read them (with a region: the groups).
      renderer.prepare_attributes(s);
      const double aspect = double(width) / height;
      const std::vector<std::uint32_t> view_spans =
          renderer.spans_for(controller_.camera(), aspect, state_.settings.clipping);
      PartialPicture partial;
      if (!renderer.upload_spans(view_spans, piece_ms)) {
        partial_rule_.uploaded(elapsed_ms());
        partial = partial_picture(renderer, view_spans, level, s.mode, aspect);
        if (!partial.stand_in) {
          stats_.refinement = "uploading the scene's level";
          glFinish();
          piece.ms = elapsed_ms();
          return piece;
        }
      }
      renderer.begin_pieces(controller_.camera(), s, width, height, refine_target_->framebuffer(), partial.stand_in);
      scheduler_->begin_pieces();
      partial_spans_ = partial.spans_in;
    }
    piece.partial = partial_spans_ > 0;
    piece.completes = renderer.draw_piece(piece_ms);
    if (piece.partial) {
      piece.voxels_in = renderer.stats().voxels_drawn;
      piece.voxels_standing_in = renderer.stats().voxels_waiting;
    }
  } catch (const std::exception& e) {
    rethrow_if_damaged(e);
    // Exact out of node memory, say: keep the picture on screen and stop refining it.
    set_error(std::string(exact_stage ? "exact when still" : render_mode_name(rest.stage_mode())) + ": " + e.what() +
              (exact_stage ? ": turned off" : ": showing axis"));
    if (exact_stage) {
      state_.exact_when_still = false;
      scheduler_->set_exact_when_still(false);
    } else {
      state_.settings.mode = RenderMode::Axis;  // as draw_scene does: the picture is drawn again in axis
    }
    scheduler_->abandon_pieces();
    stats_.refinement = rest.describe(0);
    piece.completes = false;
    piece.ms = elapsed_ms();
    return piece;
  }
  if (piece.completes) {
    std::swap(scene_target_, refine_target_);
    draw_overlays(renderer, width, height);
    show_frame_figures(renderer, level, ", refining at rest");
    if (piece.partial)
      stats_.frame_level = "level " + std::to_string(level) + " where its spans are in, level " +
                           std::to_string(scheduler_->drawn_level()) + " elsewhere (the rest is on its way)";
  }
  const bool focus_stage = scheduler_->focus_stage();
  if (piece.partial) {
    // A partial picture is not the stage's: once shown, the level's upload goes on.
    if (piece.completes) scheduler_->abandon_pieces();
  } else {
    scheduler_->piece_drawn(piece.completes);
  }
  stats_.refinement =
      focus_stage && !piece.completes
          ? "the focus at full detail: " + std::to_string(int(100 * renderer.pieces_progress())) + " %"
      : piece.partial ? piece.completes
                            ? "uploading the scene's level"
                            : "showing the part of level " + std::to_string(level) +
                                  " that is in: " + std::to_string(int(100 * renderer.pieces_progress())) + " %"
                      : rest.describe(piece.completes ? 0 : renderer.pieces_progress(), scheduler_->level_on_the_way());
  glFinish();
  piece.ms = elapsed_ms();
  if (piece.completes) {
    partial_rule_.picture_shown(partial_spans_);
    partial_spans_ = 0;
  }
  return piece;
}

void ViewerWindow::save_screenshot(const std::string& path, int width, int height) {
  const Image picture = read_back_buffer(width, height);
  write_picture(path, picture.width, picture.height, picture.rgba);
  stats_.status = "saved " + path;
  std::printf("voxview: screenshot %dx%d saved to %s\n", width, height, path.c_str());
  std::fflush(stdout);
}

void ViewerWindow::save_view(int width, int height) {
  const std::string path = options_.save_camera.value_or(stamped_name("voxview-view-", ".json").string());
  try {
    SavedView view{controller_.camera(), state_.settings, std::array<int, 2>{width, height}, true, {}, {}, {},
                   state_.show_regions};
    // Without regions the focus and context groups are gone: a view naming them would not replay.
    if (regions_.empty())
      std::erase_if(view.settings.group_styles, [](const GroupStyle& g) {
        return g.name == SceneGroups::kSelected || g.name == SceneGroups::kContext;
      });
    for (const EditorRegion& r : regions_.regions())
      (r.role == EditorRegion::Role::Include   ? view.include
       : r.role == EditorRegion::Role::Exclude ? view.exclude
                                               : view.ends_in)
          .push_back(r.argument());
    write_view(path, view);
    stats_.status = "view saved to " + path;
    std::printf("voxview: view saved to %s (replay: voxview FILE --camera '%s' --render OUT.png)\n", path.c_str(),
                path.c_str());
    std::fflush(stdout);
  } catch (const std::exception& e) {
    set_error(e.what());
  }
}

void ViewerWindow::save_stamped_screenshot(int width, int height) {
  try {
    save_screenshot(stamped_name("voxview-", ".png").string(), width, height);
  } catch (const std::exception& e) {
    set_error(e.what());
  }
}

void ViewerWindow::build_panel(double aspect) {
  state_.orthographic = controller_.camera().orthographic;
  const PanelRequests requests = panel_->build(state_, stats_);
  controller_.set_orthographic(state_.orthographic);
  if (requests.view) controller_.set_view((*requests.view)[0], (*requests.view)[1]);
  if (requests.reset_camera) reset_camera(aspect);
  if (requests.move_focus != 0) controller_.move_focus(requests.move_focus);
  if (requests.focus)
    for (int a = 0; a < 3; ++a) move_focus_along(a, (*requests.focus)[a] - controller_.camera().target[a]);
  if (requests.add_region) perform(KeyAction::AddRegion, false);
  if (requests.activate_region) regions_.activate(*requests.activate_region);
  if (requests.region_radius) regions_.set_radius(*requests.region_radius);
  if (requests.toggle_region) regions_.toggle_role();
  if (requests.remove_region) regions_.remove_active();
  if (requests.save_selection) save_selection();
  screenshot_requested_ |= requests.screenshot;
  save_view_requested_ |= requests.save_view;
  scheduler_->set_exact_when_still(state_.exact_when_still);
}

bool ViewerWindow::draw_picture(const PictureTask& task, const PictureKey& key, bool moving) {
  if (task.stage_skipped) stats_.refinement = scheduler_->rest().describe(0);
  if (task.work == PictureWork::Whole) {
    const double ms = draw_scene(key.width, key.height, task.level, moving);
    scheduler_->drawn_whole(state_.settings.mode, task.level, ms, focus_first_at(task.level) && !drawn_focus_first_);
    stats_.refinement = scheduler_->rest().describe(0);
    drawn_ = key;
    frames_.push_back({task.level, moving, ms, seconds_since_process_start()});
    frames_.back().focus_first = drawn_focus_first_;
    frames_.back().selection = selection_.has_value();
    frames_.back().new_selection = selection_.has_value() && key.selection != framed_generation_;
    framed_generation_ = key.selection;
    return true;
  }
  if (task.work == PictureWork::Piece) {
    // A selection or a focus copy on its way changes the picture: a refinement of this one would be drawn again,
    // and it would take the cores that work needs (it runs below the window's priority). One level's selection
    // holds no finer level's streamlines.
    if (work_in_flight() || level_selection_shown()) return false;
    const PieceDrawn piece = refine(key.width, key.height, task.level);
    frames_.push_back({task.level, false, piece.ms, seconds_since_process_start(),
                       piece.partial ? FrameWork::PartialPiece : task.frame_work, piece.completes});
    frames_.back().voxels_in = piece.voxels_in;
    frames_.back().voxels_standing_in = piece.voxels_standing_in;
    frames_.back().focus_first = drawn_focus_first_;
    frames_.back().selection = selection_.has_value();
    return true;
  }
  return false;
}

int ViewerWindow::run() {
  const bool automated = options_.frames.has_value();
  FramePacing pacing;
  bool idle_at_drag_end = false;  // a scripted drag's end waits and the last frame drew nothing
  for (long frame = 1;; ++frame) {
    const unsigned seen = events_;
    if (idle_at_drag_end) {
      // Not a busy loop: the selection and the copy run on the cores below the window's priority.
      glfwWaitEventsTimeout(0.005);
    } else {
      switch (pacing.next_wait(automated, work_in_flight())) {
        case FramePacing::Wait::None: glfwPollEvents(); break;
        // Nothing wakes the window when a selection or a focus copy is done: it looks again in a while.
        case FramePacing::Wait::Briefly: glfwWaitEventsTimeout(kWorkPollSeconds); break;
        case FramePacing::Wait::UntilInput: glfwWaitEvents(); break;  // nothing moves by itself
      }
    }
    pacing.frame_started(events_ != seen);
    // A script's frames are done after --frames; a scripted drag then waits, drawing frames, for its last
    // position's selection and focus copy (they come off the window's thread), so that its last picture and
    // --stats show them; with --until-refined it then waits, at rest, for the refinement to finish.
    const bool frames_done = automated && frame >= *options_.frames;
    const bool settled = !frames_done || !options_.drag_region_mm || drag_end_settled();
    const bool refined = drawn_ && scheduler_->rest().stage() == RestStage::Done;
    const bool closing =
        glfwWindowShouldClose(window_) || (frames_done && settled && (!options_.until_refined || refined));

    // Render at the framebuffer's size (HiDPI), take input in window units.
    int fb_w = 0, fb_h = 0, win_h = 0;
    glfwGetFramebufferSize(window_, &fb_w, &fb_h);
    glfwGetWindowSize(window_, nullptr, &win_h);
    if (fb_w <= 0 || fb_h <= 0) {  // minimised
      if (closing) break;
      continue;
    }
    controller_.set_window_height(win_h);

    build_panel(double(fb_w) / fb_h);
    if (options_.orbit_deg && !frames_done)
      controller_.set_view(controller_.camera().azimuth_deg + *options_.orbit_deg, controller_.camera().elevation_deg);

    // A changed picture is drawn whole: the first at a coarse level (at once); while the camera moves or a
    // setting changes, at the finest level that fits the frame budget; a script's last frame at the scene's
    // level. An unchanged one is refined at rest, a piece a frame (rest_refinement.h).
    const Camera& camera = controller_.camera();
    // A scripted drag moves the active region every frame, as a mouse would.
    const bool dragging = options_.drag_region_mm && !frames_done && regions_.active();
    if (dragging) regions_.move_active_by(*options_.drag_region_mm);
    // A script's window (--frames) waits for each selection, so that what it draws does not depend on timing;
    // a scripted drag does not, as a user's drag does not (its end waits above, frame by frame).
    update_selection(automated && !options_.drag_region_mm, dragging || dragging_region_);
    update_focus_copy(automated && !options_.drag_region_mm);
    state_.settings.regions = state_.show_regions ? regions_.shapes() : std::vector<RegionShape>{};
    const PictureKey key{camera, state_.settings, fb_w, fb_h, state_.grid, state_.grid_all, selection_generation_};
    const bool moving = drawn_ && !closing && (!same_view(drawn_->camera, camera) || dragging);
    const bool changed = !drawn_ || !same_picture(*drawn_, key);
    const bool scripted_last = closing && frames_done && !options_.until_refined;
    // The picture (and so what the panel should say) changed after the panel was built.
    scheduler_->set_load({session_->has_focus() && focus_copy_fits_budget(), work_in_flight()});
    PictureTask task = scheduler_->next(changed, scripted_last, closing, [&] {
      const double aspect = double(fb_w) / fb_h;
      return session_->picture_levels(&camera, aspect, state_.settings.clipping).context_level();
    });
    if (task.work == PictureWork::Whole) {
      // The level a region's drag draws at: its next selections search this level's streamlines.
      if (moving || dragging_region_) moving_level_ = task.level;
      // A selection of one level's streamlines holds that level's and the coarser ones', not a finer level's.
      if (selection_) task.level = std::max(task.level, selection_->level);
    }
    const bool drawn_now = draw_picture(task, key, moving);
    pacing.frame_ended(scheduler_->rest().stage() != RestStage::Done, drawn_now);
    idle_at_drag_end = frames_done && !settled && !drawn_now;
    present(fb_w, fb_h);
    // Screenshots show the scene alone unless the user asked for the panel too; automated ones never do.
    if (closing && options_.screenshot) save_screenshot(*options_.screenshot, fb_w, fb_h);
    // The view of the frame just drawn; scripts get it on quitting after --frames.
    if (save_view_requested_ || (closing && automated && options_.save_camera)) save_view(fb_w, fb_h);
    save_view_requested_ = false;
    if (screenshot_requested_ && !state_.panel_in_screenshot) save_stamped_screenshot(fb_w, fb_h);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glViewport(0, 0, fb_w, fb_h);
    panel_->render();
    if (screenshot_requested_ && state_.panel_in_screenshot) save_stamped_screenshot(fb_w, fb_h);
    screenshot_requested_ = false;
    glfwSwapBuffers(window_);
    if (startup_.first_on_screen_s < 0 && !frames_.empty()) {
      glFinish();  // the swap has been carried out, not only queued
      startup_.first_on_screen_s = seconds_since_process_start();
    }
    if (closing) break;
  }
  // What was drawn is checked before the window reports success: a damaged file exits 3, as headless.
  session_->check_uploaded(true);
  if (options_.stats_json)
    write_frame_stats(*options_.stats_json, frames_, detail_.level, options_.frame_budget_ms, startup_,
                      session_->uploads(), selection_ms_, selection_levels_, drag_end_);
  return 0;
}

int run_window(const ViewerOptions& o) {
  GlfwLibrary glfw;                                   // first: without a display, fail before any slow conversion
  auto session = std::make_unique<ViewerSession>(o);  // a bad file or image fails before the window opens
  RegionEditor regions(o);                            // parses the regions: a bad one fails there too
  WindowPtr window = open_window(o);
  StartupTimes startup;
  startup.main_s = seconds_before_main();
  startup.window_open_s = seconds_since_process_start();
  session->choose_detail(o);  // the driver's limits: the window's context is current
  ViewerWindow viewer(o, std::move(session), std::move(regions), window.get(), startup);
  return viewer.run();
}

}  // namespace vxl::app
