// When the window may sleep until the next input event (glfwWaitEvents), when it must look again in a while and
// when it must draw another frame by itself. Pure logic, so that "the panel tells the truth without input" is testable
// without a window.
//
// The panel is built at the start of a frame, before the frame's refinement piece is drawn: the piece that
// completes the refinement changes what the panel should say after the panel was built. Without one more
// frame the window would then sleep showing the previous piece's percentage until the user moved.
#pragma once

namespace vxl::app {

class FramePacing {
 public:
  // Frames drawn after the last input event: ImGui needs one to show hover and clicks.
  static constexpr int kFramesAfterInput = 2;

  // At the start of a frame: whether input arrived since the previous one.
  void frame_started(bool input_arrived) {
    settle_ = input_arrived ? kFramesAfterInput : (settle_ > 0 ? settle_ - 1 : 0);
  }
  // At the end of a frame: `refining`, the refinement at rest has more pieces to draw; `panel_stale`, what
  // the panel shows changed after it was built this frame (a picture or a refinement piece was drawn).
  void frame_ended(bool refining, bool panel_stale) {
    if ((refining || panel_stale) && settle_ < 1) settle_ = 1;
  }
  // Whether the next frame may wait for input instead of drawing at once.
  bool may_wait() const { return settle_ == 0; }

  // How the next frame waits: not at all (input settling, a refinement piece, a script), a while (`work_in_flight`:
  // a selection or focus copy made off the window's thread, whose end no event announces), or until input.
  enum class Wait { None, Briefly, UntilInput };
  Wait next_wait(bool scripted, bool work_in_flight) const {
    if (scripted || !may_wait()) return Wait::None;
    return work_in_flight ? Wait::Briefly : Wait::UntilInput;
  }

 private:
  int settle_ = kFramesAfterInput;  // frames still to draw without input
};

}  // namespace vxl::app
