// One transparency mode's drawing (docs/rendering.md): a ModePass per RenderMode, made from the one table
// of them (mode_table.cpp), each in its own file. The renderer starts a frame (attributes, slices, neutral
// GL state), hands it to the mode's pass, then draws the front halves of the region shells.
#pragma once

#include <memory>

#include "viewer/render/modes/pass_host.h"

namespace vxl {

// How a mode draws a frame in pieces (Renderer::begin_pieces).
enum class PieceKind {
  Whole,   // the first piece draws the whole frame (modes that blend in no order, or whose CPU sort is the cost)
  Voxels,  // runs of the plan's voxels, back to front, each piece in the mode's line state
  Own,     // the mode's own begin / step / progress (exact: runs of composited voxels)
};

class ModePass {
 public:
  virtual ~ModePass() = default;
  virtual RenderMode mode() const = 0;
  // A whole frame into frame.fbo: the base (host.clear_to_base) and the lines.
  virtual void draw(PassHost& host, const FrameView& frame) = 0;

  virtual PieceKind piece_kind() const { return PieceKind::Whole; }
  // PieceKind::Voxels: the order the mode plans its voxels in, with what that order keeps in `plan` set
  // (axis: its order hysteresis), as draw() plans them; and the GL state each piece sets again (a window
  // draws other things between pieces).
  virtual PlanOrder plan_order(const RenderSettings& settings, FramePlan& plan) const;
  virtual void piece_state() const {}
  // PieceKind::Own: starts the frame (its base included), then draws it for about `max_ms` a step until
  // step() returns true; progress() is the share of the frame drawn.
  virtual void begin(PassHost& host, const FrameView& frame);
  virtual bool step(double max_ms);
  virtual double progress() const { return 1; }
};

// Plans `frame` in `order` into host.frame_plan() (plan_and_count) and draws it with `program` bound for
// `settings`: the lines of the modes that draw the frame plan once.
void draw_planned_lines(PassHost& host, const FrameView& frame, GLuint program, const RenderSettings& settings,
                        PlanOrder order);

// The pass of `mode`, from the table of every mode's pass. Made when first used: exact's needs OpenGL 4.3.
std::unique_ptr<ModePass> make_mode_pass(RenderMode mode);

}  // namespace vxl
