// The viewer's tables of keys and of transparency modes: every entry reachable, none bound twice, and the
// help built from them lists them all.
#include <set>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include "viewer/app/key_bindings.h"
#include "viewer/render/render_settings.h"

namespace vxl {
namespace {

using app::action_for_char;
using app::action_for_key;
using app::KeyAction;
using app::KeyInput;

TEST(KeyBindings, KeysAndCharactersMapToTheirActions) {
  EXPECT_EQ(action_for_key(GLFW_KEY_1, false, false), KeyAction::ViewAxial);
  EXPECT_EQ(action_for_key(GLFW_KEY_1, true, false), KeyAction::ViewInferior);
  EXPECT_EQ(action_for_key(GLFW_KEY_4, false, false), KeyAction::ViewInferior);
  EXPECT_EQ(action_for_key(GLFW_KEY_4, true, false), KeyAction::ViewInferior);
  EXPECT_EQ(action_for_key(GLFW_KEY_3, true, false), KeyAction::ViewPosterior);
  EXPECT_EQ(action_for_key(GLFW_KEY_ESCAPE, false, false), KeyAction::Quit);
  EXPECT_EQ(action_for_key(GLFW_KEY_F2, false, false), KeyAction::ToggleClip2);
  EXPECT_EQ(action_for_key(GLFW_KEY_HOME, true, false), KeyAction::FocusAnterior);
  // Held keys repeat the moves only.
  EXPECT_EQ(action_for_key(GLFW_KEY_PAGE_UP, false, true), KeyAction::SlabNearer);
  EXPECT_EQ(action_for_key(GLFW_KEY_DOWN, false, true), KeyAction::FocusInferior);
  EXPECT_FALSE(action_for_key(GLFW_KEY_F1, false, true));
  EXPECT_FALSE(action_for_key(GLFW_KEY_1, false, true));
  // Letters are typed characters (they follow the keyboard layout), not key codes.
  EXPECT_FALSE(action_for_key(GLFW_KEY_O, false, false));
  EXPECT_EQ(action_for_char('o'), KeyAction::ToggleOrthographic);
  EXPECT_EQ(action_for_char('O'), KeyAction::ToggleOrthographic);
  EXPECT_EQ(action_for_char('='), KeyAction::OpacityUp);
  EXPECT_EQ(action_for_char('_'), KeyAction::OpacityDown);
  EXPECT_EQ(action_for_char(']'), KeyAction::SlabThicker);
  EXPECT_EQ(action_for_char('q'), KeyAction::Quit);
  EXPECT_EQ(action_for_char('x'), KeyAction::ToggleRegionRole);
  EXPECT_EQ(action_for_char('g'), KeyAction::AddRegion);
  EXPECT_EQ(action_for_char('h'), KeyAction::TogglePanel);
  EXPECT_EQ(action_for_char('H'), KeyAction::TogglePanel);
  EXPECT_EQ(action_for_char('b'), KeyAction::ToggleRegionShells);
  EXPECT_FALSE(action_for_char('z'));
  EXPECT_FALSE(action_for_char('!'));
  EXPECT_FALSE(action_for_char(0x263A));
}

TEST(KeyBindings, EveryActionHasOneRowAndEveryInputOneAction) {
  std::set<KeyAction> seen;
  for (const app::KeyBinding& b : app::key_bindings()) {
    EXPECT_TRUE(seen.insert(b.action).second) << b.keys << " repeats an action";
    EXPECT_NE(b.input.kind, KeyInput::Kind::None) << b.keys;
    // Each input reaches its own row's action, so no earlier row shadows it.
    for (const KeyInput& in : {b.input, b.other}) {
      if (in.kind == KeyInput::Kind::Key) {
        const bool shift = in.shift == KeyInput::Shift::With;
        EXPECT_EQ(action_for_key(in.key, shift, false), b.action) << b.keys;
      } else if (in.kind == KeyInput::Kind::Char) {
        for (const char* c = in.chars; *c; ++c) EXPECT_EQ(action_for_char(*c), b.action) << b.keys;
      }
    }
  }
  EXPECT_EQ(seen.size(), static_cast<std::size_t>(KeyAction::Quit) + 1);
}

TEST(KeyBindings, HelpListsEveryGestureAndKey) {
  const std::string columns = app::controls_as_columns();
  const std::string paragraph = app::controls_as_paragraph(80);
  for (const app::MouseGesture& m : app::mouse_gestures()) {
    EXPECT_NE(columns.find(m.gesture), std::string::npos) << m.gesture;
    EXPECT_NE(paragraph.find(std::string(m.gesture) + ": " + m.description), std::string::npos) << m.gesture;
  }
  for (const app::KeyBinding& b : app::key_bindings()) {
    EXPECT_NE(columns.find(b.description), std::string::npos) << b.keys;
    EXPECT_NE(paragraph.find(std::string(b.keys) + ": " + b.description), std::string::npos) << b.keys;
  }
  std::istringstream lines(paragraph);
  for (std::string line; std::getline(lines, line);) EXPECT_LE(line.size(), 80u) << line;
}

TEST(RenderModeTable, NamesParseBackInEnumOrder) {
  const auto modes = render_modes();
  ASSERT_EQ(modes.size(), 8u);
  ASSERT_EQ(render_mode_names().size(), modes.size());
  for (std::size_t i = 0; i < modes.size(); ++i) {
    EXPECT_EQ(static_cast<std::size_t>(modes[i].mode), i);
    EXPECT_EQ(parse_render_mode(modes[i].name), modes[i].mode);
    EXPECT_STREQ(render_mode_name(modes[i].mode), modes[i].name);
    EXPECT_EQ(render_mode_names()[i], modes[i].name);
    EXPECT_GT(std::string(modes[i].description).size(), 10u);
  }
  EXPECT_EQ(render_mode_names().front(), "opaque");
  EXPECT_EQ(render_mode_names().back(), "exact");
  EXPECT_FALSE(parse_render_mode("fancy"));
}

// The per-mode facts the window, the refinement at rest and the panel read from the table.
TEST(RenderModeTable, EachModesFactsAreInItsEntry) {
  for (const RenderModeInfo& m : render_modes()) EXPECT_EQ(render_mode_info(m.mode).mode, m.mode);
  for (const RenderModeInfo& m : render_modes()) {
    EXPECT_EQ(m.needs_gl43, m.mode == RenderMode::Exact) << m.name;
    EXPECT_EQ(m.refines_to_exact, m.mode == RenderMode::Basic || m.mode == RenderMode::Axis) << m.name;
  }
  EXPECT_EQ(render_mode_info(RenderMode::Axis).plan_order, PlanOrder::Nearest);
  EXPECT_EQ(render_mode_info(RenderMode::Segsort).plan_order, PlanOrder::Block);  // it sorts the segments itself
  EXPECT_EQ(render_mode_info(RenderMode::Basic).plan_order, PlanOrder::Block);
  EXPECT_EQ(render_mode_info(RenderMode::Exact).plan_order, PlanOrder::Visibility);
  for (RenderMode m : {RenderMode::Opaque, RenderMode::Unsorted, RenderMode::Additive, RenderMode::Wboit})
    EXPECT_EQ(render_mode_info(m).plan_order, PlanOrder::Any) << render_mode_name(m);
}

}  // namespace
}  // namespace vxl
