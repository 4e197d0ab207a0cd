// The voxview window's keys and mouse gestures: one table that the window's input handling, the panel's
// "Keys and mouse" list and `voxview --help` all read, so that they cannot disagree.
#pragma once

#include <optional>
#include <span>
#include <string>

namespace vxl::app {

// What a key does; the window (window_app.cpp) carries it out.
enum class KeyAction {
  ViewAxial,
  ViewSagittal,
  ViewCoronal,
  ViewInferior,
  ViewRight,
  ViewPosterior,
  ToggleOrthographic,
  NextMode,
  OpacityUp,
  OpacityDown,
  ToggleLighting,
  ToggleExactWhenStill,
  Screenshot,
  ResetCamera,
  SaveView,
  ToggleSlab,
  SlabThinner,
  SlabThicker,
  SlabNearer,  // moves the focus, and the slab with it, along the view direction
  SlabFarther,
  ToggleClip1,
  ToggleClip2,
  ToggleClip3,
  FocusSuperior,  // moves the focus (and the axial slice) along S/I
  FocusInferior,
  FocusRight,  // ... along R/L (the sagittal slice)
  FocusLeft,
  FocusAnterior,  // ... along A/P (the coronal slice)
  FocusPosterior,
  ToggleSlices,
  AddRegion,  // a sphere at the focus; the focus keys then move it
  RemoveRegion,
  NextRegion,
  ToggleRegionRole,
  ToggleRegionShells,
  RegionSmaller,
  RegionLarger,
  SaveSelection,
  TogglePanel,  // the panel collapsed to its title bar / open: it covers part of the picture
  Quit,
};

// One way to trigger an action. Keys bound to a place on the keyboard (Esc, digits, F keys, arrows) are
// GLFW key codes; keys bound to a character (letters, + - [ ]) follow the user's layout and are typed
// characters.
struct KeyInput {
  enum class Kind { None, Key, Char };
  enum class Shift { Any, Without, With };
  Kind kind = Kind::None;
  int key = 0;                  // GLFW_KEY_*, for Kind::Key
  Shift shift = Shift::Any;     // for Kind::Key
  const char* chars = nullptr;  // for Kind::Char: every character that triggers it ("oO")
};

struct KeyBinding {
  KeyAction action;
  const char* keys;         // how the help names the keys
  const char* description;  // what they do
  KeyInput input;
  KeyInput other = {};   // a second way to the same action, if any
  bool repeats = false;  // a held key repeats the action (the moves only); typed characters always repeat
};

std::span<const KeyBinding> key_bindings();

// The action of a key event (GLFW_KEY_*; `repeat`: a held key's repeat) and of a typed character.
std::optional<KeyAction> action_for_key(int key, bool shift, bool repeat);
std::optional<KeyAction> action_for_char(unsigned codepoint);

// Mouse gestures, for the help only: the window's mouse callbacks handle them.
struct MouseGesture {
  const char* gesture;
  const char* description;
};
std::span<const MouseGesture> mouse_gestures();

// The gestures and keys as two columns, one per line (the panel), and as one paragraph wrapped at `width`
// columns (`voxview --help`).
std::string controls_as_columns();
std::string controls_as_paragraph(std::size_t width);

}  // namespace vxl::app
