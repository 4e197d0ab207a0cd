#include "viewer/app/key_bindings.h"

#include <cstring>

#define GLFW_INCLUDE_NONE  // only the key codes are needed here
#include <GLFW/glfw3.h>

namespace vxl::app {

namespace {

using Kind = KeyInput::Kind;
using Shift = KeyInput::Shift;

constexpr KeyInput key(int code, Shift shift = Shift::Any) { return {Kind::Key, code, shift, nullptr}; }
constexpr KeyInput typed(const char* chars) { return {Kind::Char, 0, Shift::Any, chars}; }

constexpr bool kRepeats = true;

// Shift on a digit picks the opposite view; on a move it makes the step 10 times larger.
constexpr KeyBinding kKeys[] = {
    {KeyAction::ViewAxial, "1", "axial view", key(GLFW_KEY_1, Shift::Without)},
    {KeyAction::ViewSagittal, "2", "sagittal view (left)", key(GLFW_KEY_2, Shift::Without)},
    {KeyAction::ViewCoronal, "3", "coronal view (anterior)", key(GLFW_KEY_3, Shift::Without)},
    {KeyAction::ViewInferior, "Shift+1, 4", "inferior view", key(GLFW_KEY_1, Shift::With), key(GLFW_KEY_4)},
    {KeyAction::ViewRight, "Shift+2, 5", "right view", key(GLFW_KEY_2, Shift::With), key(GLFW_KEY_5)},
    {KeyAction::ViewPosterior, "Shift+3, 6", "posterior view", key(GLFW_KEY_3, Shift::With), key(GLFW_KEY_6)},
    {KeyAction::ToggleOrthographic, "O", "orthographic / perspective", typed("oO")},
    {KeyAction::NextMode, "M", "next transparency mode", typed("mM")},
    {KeyAction::OpacityUp, "+", "opacity x 1.5", typed("+=")},
    {KeyAction::OpacityDown, "-", "opacity / 1.5", typed("-_")},
    {KeyAction::ToggleLighting, "L", "lighting on / off", typed("lL")},
    {KeyAction::ToggleExactWhenStill, "E", "exact when still on / off (needs OpenGL 4.3)", typed("eE")},
    {KeyAction::Screenshot, "S", "screenshot", typed("sS")},
    {KeyAction::ResetCamera, "R", "reset the camera", typed("rR")},
    {KeyAction::SaveView, "V", "save the view (for --camera)", typed("vV")},
    {KeyAction::ToggleSlab, "C", "slab on / off", typed("cC")},
    {KeyAction::SlabThinner, "[", "slab thinner", typed("[")},
    {KeyAction::SlabThicker, "]", "slab thicker", typed("]")},
    {KeyAction::SlabNearer,
     "PageUp",
     "move the slab (the focus) 1 mm nearer (Shift: 10 mm)",
     key(GLFW_KEY_PAGE_UP),
     {},
     kRepeats},
    {KeyAction::SlabFarther,
     "PageDown",
     "move the slab (the focus) 1 mm farther (Shift: 10 mm)",
     key(GLFW_KEY_PAGE_DOWN),
     {},
     kRepeats},
    {KeyAction::ToggleClip1, "F1", "clip plane 1 on / off (added through the focus on x if missing)", key(GLFW_KEY_F1)},
    {KeyAction::ToggleClip2, "F2", "clip plane 2 on / off (added on y if missing)", key(GLFW_KEY_F2)},
    {KeyAction::ToggleClip3, "F3", "clip plane 3 on / off (added on z if missing)", key(GLFW_KEY_F3)},
    {KeyAction::FocusSuperior,
     "Up",
     "image: focus and axial slice 1 mm superior (Shift: 10 mm)",
     key(GLFW_KEY_UP),
     {},
     kRepeats},
    {KeyAction::FocusInferior, "Down", "image: focus and axial slice 1 mm inferior", key(GLFW_KEY_DOWN), {}, kRepeats},
    {KeyAction::FocusRight, "Right", "image: focus and sagittal slice 1 mm right", key(GLFW_KEY_RIGHT), {}, kRepeats},
    {KeyAction::FocusLeft, "Left", "image: focus and sagittal slice 1 mm left", key(GLFW_KEY_LEFT), {}, kRepeats},
    {KeyAction::FocusAnterior,
     "Home",
     "image: focus and coronal slice 1 mm anterior",
     key(GLFW_KEY_HOME),
     {},
     kRepeats},
    {KeyAction::FocusPosterior,
     "End",
     "image: focus and coronal slice 1 mm posterior",
     key(GLFW_KEY_END),
     {},
     kRepeats},
    {KeyAction::ToggleSlices, "I", "image slices shown / hidden", typed("iI")},
    {KeyAction::AddRegion, "G", "selection: a 10 mm sphere at the focus (the focus keys then move it)", typed("gG")},
    {KeyAction::RemoveRegion, "Delete", "selection: remove the active region", key(GLFW_KEY_DELETE)},
    {KeyAction::NextRegion, "Tab", "selection: the next region becomes the active one", key(GLFW_KEY_TAB)},
    {KeyAction::ToggleRegionRole, "X", "selection: the active region includes / excludes", typed("xX")},
    {KeyAction::ToggleRegionShells, "B", "selection: the regions' shells shown / hidden", typed("bB")},
    {KeyAction::RegionSmaller, ",", "selection: the active sphere / 1.25", typed(",<")},
    {KeyAction::RegionLarger, ".", "selection: the active sphere x 1.25", typed(".>")},
    {KeyAction::SaveSelection, "W", "selection: write the selected streamlines to a .tck", typed("wW")},
    {KeyAction::TogglePanel, "H", "panel collapsed / open (uncovers the picture)", typed("hH")},
    {KeyAction::Quit, "Esc, Q", "quit", key(GLFW_KEY_ESCAPE), typed("qQ")},
};

constexpr MouseGesture kMouse[] = {
    {"left drag", "orbit"},
    {"right/middle drag", "pan (or Shift+left drag)"},
    {"wheel", "zoom"},
    {"Ctrl+wheel", "move the slab (the focus)"},
    {"Shift+wheel", "selection: the active sphere's radius"},
    {"Ctrl+left drag", "selection: move the sphere under the cursor (or the active one)"},
};

bool matches_key(const KeyInput& in, int code, bool shift) {
  return in.kind == Kind::Key && in.key == code && (in.shift == Shift::Any || (in.shift == Shift::With) == shift);
}

bool matches_char(const KeyInput& in, unsigned codepoint) {
  return in.kind == Kind::Char && codepoint != 0 && codepoint < 128 &&
         std::strchr(in.chars, static_cast<int>(codepoint)) != nullptr;
}

}  // namespace

std::span<const KeyBinding> key_bindings() { return kKeys; }
std::span<const MouseGesture> mouse_gestures() { return kMouse; }

std::optional<KeyAction> action_for_key(int code, bool shift, bool repeat) {
  for (const KeyBinding& b : kKeys)
    if ((matches_key(b.input, code, shift) || matches_key(b.other, code, shift)) && (!repeat || b.repeats))
      return b.action;
  return std::nullopt;
}

std::optional<KeyAction> action_for_char(unsigned codepoint) {
  for (const KeyBinding& b : kKeys)
    if (matches_char(b.input, codepoint) || matches_char(b.other, codepoint)) return b.action;
  return std::nullopt;
}

std::string controls_as_columns() {
  constexpr std::size_t kColumn = 19;  // the widest gesture and a space
  std::string text;
  auto line = [&](const std::string& left, const char* right) {
    if (!text.empty()) text += '\n';
    text += left + std::string(left.size() < kColumn ? kColumn - left.size() : 1, ' ') + right;
  };
  for (const MouseGesture& m : kMouse) line(m.gesture, m.description);
  for (const KeyBinding& b : kKeys) line(b.keys, b.description);
  return text;
}

std::string controls_as_paragraph(std::size_t width) {
  std::string text, current;
  auto add = [&](const std::string& item) {
    if (!current.empty() && current.size() + 1 + item.size() > width) {
      text += current + '\n';
      current.clear();
    }
    current += (current.empty() ? "" : " ") + item;
  };
  add("Window, mouse:");
  for (std::size_t i = 0; i < std::size(kMouse); ++i)
    add(std::string(kMouse[i].gesture) + ": " + kMouse[i].description + (i + 1 < std::size(kMouse) ? ";" : "."));
  add("Keys:");
  for (std::size_t i = 0; i < std::size(kKeys); ++i)
    add(std::string(kKeys[i].keys) + ": " + kKeys[i].description + (i + 1 < std::size(kKeys) ? ";" : "."));
  return text + current;
}

}  // namespace vxl::app
