#include "viewer/app/ui_panel.h"

#include <algorithm>
#include <cstdio>

#define GLFW_INCLUDE_NONE  // epoxy provides the GL declarations
#include <GLFW/glfw3.h>
#include <imgui.h>
#include <imgui_impl_glfw.h>
#include <imgui_impl_opengl3.h>

#include "viewer/app/key_bindings.h"
#include "viewer/render/camera.h"

namespace vxl::app {

namespace {

// "1234567" -> "1.23 M": the counts span six orders of magnitude, exact digits would not be read.
std::string count_text(std::uint64_t n) {
  char buf[32];
  if (n >= 1000000)
    std::snprintf(buf, sizeof buf, "%.2f M", n / 1e6);
  else if (n >= 10000)
    std::snprintf(buf, sizeof buf, "%.1f k", n / 1e3);
  else
    std::snprintf(buf, sizeof buf, "%llu", static_cast<unsigned long long>(n));
  return buf;
}

void view_button(const char* label, const char* view, PanelRequests& out) {
  if (ImGui::Button(label)) out.view = parse_view(view);
}

// Colour mode, fixed colour, value set, colour map and range, and each group's colour and opacity.
void colour_controls(PanelState& state, const PanelStats& stats) {
  RenderSettings& s = state.settings;
  int colour = static_cast<int>(s.color);
  ImGui::AlignTextToFramePadding();
  ImGui::TextUnformatted("Colour");
  ImGui::SameLine();
  ImGui::RadioButton("direction", &colour, 0);
  ImGui::SameLine();
  ImGui::RadioButton("fixed", &colour, 1);
  ImGui::SameLine();
  // Picking a colour means the user wants it shown.
  if (ImGui::ColorEdit3("##fixed colour", &s.fixed_color.x, ImGuiColorEditFlags_NoInputs)) colour = 1;
  ImGui::TextUnformatted("      ");
  ImGui::SameLine();
  ImGui::BeginDisabled(stats.value_sets.empty());
  ImGui::RadioButton("scalar", &colour, 2);
  ImGui::EndDisabled();
  ImGui::SameLine();
  ImGui::RadioButton("group", &colour, 3);
  s.color = static_cast<ColorMode>(colour);

  if (s.color == ColorMode::Scalar && !stats.value_sets.empty()) {
    const std::string current = s.scalar.empty() ? stats.value_sets.front() : s.scalar;
    if (ImGui::BeginCombo("Values", current.c_str())) {
      for (const std::string& name : stats.value_sets)
        if (ImGui::Selectable(name.c_str(), name == current)) s.scalar = name;
      ImGui::EndCombo();
    }
    if (ImGui::BeginCombo("Colour map", colormap_name(s.colormap))) {
      for (Colormap m : {Colormap::Grey, Colormap::Hot, Colormap::Viridis})
        if (ImGui::Selectable(colormap_name(m), m == s.colormap)) s.colormap = m;
      ImGui::EndCombo();
    }
    bool automatic = !s.range.has_value();
    if (ImGui::Checkbox("auto range", &automatic)) {
      if (automatic)
        s.range.reset();
      else
        s.range = stats.scalar_range;
    }
    ImGui::SameLine();
    ImGui::BeginDisabled(automatic);
    std::array<float, 2> r = s.range.value_or(stats.scalar_range);
    const float speed = std::max(1e-6f, (r[1] - r[0]) / 200.0f);
    ImGui::PushItemWidth(110);
    if (ImGui::DragFloatRange2("##range", &r[0], &r[1], speed, 0.0f, 0.0f, "%.4g", "%.4g") && r[1] > r[0]) s.range = r;
    ImGui::PopItemWidth();
    ImGui::EndDisabled();
  }
  if (stats.groups.size() > 1 || s.color == ColorMode::Group) {
    if (ImGui::CollapsingHeader("Groups", ImGuiTreeNodeFlags_DefaultOpen)) {
      for (std::size_t g = 0; g < stats.groups.size(); ++g) {
        const auto& [name, count] = stats.groups[g];
        ImGui::PushID(static_cast<int>(g));
        glm::vec4 c = s.group_color(name, g);
        if (ImGui::ColorEdit3("##colour", &c.x, ImGuiColorEditFlags_NoInputs)) s.style_of(name).color = glm::vec3(c);
        ImGui::SameLine();
        ImGui::PushItemWidth(90);
        if (ImGui::SliderFloat("##opacity", &c.w, 0.0f, 1.0f, "%.2f", ImGuiSliderFlags_AlwaysClamp))
          s.style_of(name).opacity = c.w;
        ImGui::PopItemWidth();
        ImGui::SameLine();
        ImGui::Text("%s (%s)", name.c_str(), count_text(count).c_str());
        ImGui::PopID();
      }
    }
  }
}

// The selection's regions: each with its role and how many streamlines it holds; the active one's radius
// (a sphere) and role can be changed, and it can be removed; a sphere can be added at the focus; the
// regions' shells shown or hidden.
void selection_controls(PanelState& state, const PanelStats& stats, PanelRequests& out) {
  if (!ImGui::CollapsingHeader("Selection", ImGuiTreeNodeFlags_DefaultOpen)) return;
  out.add_region = ImGui::Button("Add sphere at focus");
  if (!stats.regions.empty()) {
    ImGui::SameLine();
    out.save_selection = ImGui::Button("Save selection");
    ImGui::SameLine();
    ImGui::Checkbox("Shells", &state.show_regions);  // the regions drawn around the lines (B)
  }
  for (std::size_t i = 0; i < stats.regions.size(); ++i) {
    const PanelStats::Region& r = stats.regions[i];
    ImGui::PushID(static_cast<int>(i));
    const std::string label = r.role + " " + r.argument + " (" + count_text(r.streamlines) + ")";
    if (ImGui::Selectable(label.c_str(), r.active)) out.activate_region = i;
    ImGui::PopID();
  }
  for (const PanelStats::Region& r : stats.regions) {
    if (!r.active) continue;
    if (r.sphere) {
      float radius = static_cast<float>(r.radius);
      ImGui::PushItemWidth(110);
      if (ImGui::DragFloat("radius (mm)", &radius, 0.1f, 0.0f, 200.0f, "%.1f")) out.region_radius = radius;
      ImGui::PopItemWidth();
      ImGui::SameLine();
    }
    out.toggle_region = ImGui::Button(r.role == "include" ? "Make exclude" : "Make include");
    ImGui::SameLine();
    out.remove_region = ImGui::Button("Remove");
  }
  if (!stats.selection.empty()) ImGui::TextUnformatted(stats.selection.c_str());
}

// Slab (thickness, move) and up to three clip planes (on/off, side and axis, position within the bounds).
void clipping_controls(PanelState& state, const PanelStats& stats, PanelRequests& out) {
  Clipping& c = state.settings.clipping;
  ImGui::Separator();
  bool slab = c.slab_mm > 0;
  if (ImGui::Checkbox("Slab", &slab)) c.slab_mm = slab ? state.slab_thickness : 0.0;
  ImGui::SameLine();
  ImGui::PushItemWidth(110);
  float thickness = static_cast<float>(state.slab_thickness);
  if (ImGui::DragFloat("mm##slab", &thickness, 0.1f, 0.1f, 1000.0f, "%.1f", ImGuiSliderFlags_AlwaysClamp)) {
    state.slab_thickness = thickness;
    if (c.slab_mm > 0) c.slab_mm = thickness;
  }
  ImGui::PopItemWidth();
  ImGui::SameLine();
  ImGui::BeginDisabled(c.slab_mm <= 0);
  if (ImGui::ArrowButton("##nearer", ImGuiDir_Left)) out.move_focus = -1.0;
  ImGui::SameLine();
  if (ImGui::ArrowButton("##farther", ImGuiDir_Right)) out.move_focus = 1.0;
  ImGui::SameLine();
  ImGui::TextUnformatted("move");
  ImGui::EndDisabled();

  static const char* const kSides[] = {"x >=", "y >=", "z >=", "x <=", "y <=", "z <="};
  for (std::size_t i = 0; i < c.planes.size(); ++i) {
    AxisClip& p = c.planes[i];
    ImGui::PushID(static_cast<int>(i));
    ImGui::Checkbox("##on", &p.enabled);
    ImGui::SameLine();
    ImGui::PushItemWidth(60);
    int side = p.axis + (p.keep_above ? 0 : 3);
    if (ImGui::Combo("##side", &side, kSides, 6)) {
      p.axis = side % 3;
      p.keep_above = side < 3;
    }
    ImGui::PopItemWidth();
    ImGui::SameLine();
    ImGui::PushItemWidth(150);
    float pos = static_cast<float>(p.position);
    const float lo = static_cast<float>(stats.bounds_min[p.axis]), hi = static_cast<float>(stats.bounds_max[p.axis]);
    if (ImGui::SliderFloat("mm##pos", &pos, lo, hi, "%.1f")) p.position = pos;
    ImGui::PopItemWidth();
    ImGui::SameLine();
    const bool remove = ImGui::SmallButton("x");
    ImGui::PopID();
    if (remove) {
      c.planes.erase(c.planes.begin() + static_cast<std::ptrdiff_t>(i));
      break;
    }
  }
  if (c.planes.size() < Clipping::kMaxPlanes && ImGui::Button("Add clip plane")) {
    AxisClip p;
    p.axis = static_cast<int>(c.planes.size());  // x, then y, then z, through the scene's centre
    p.position = (stats.bounds_min[p.axis] + stats.bounds_max[p.axis]) / 2;
    c.planes.push_back(p);
  }
}

// The anatomical image's slices: which are shown, where they cross (the focus), the grey range.
void image_controls(PanelState& state, const PanelStats& stats, PanelRequests& out) {
  if (!stats.has_image) return;
  SliceSettings& sl = state.settings.slices;
  ImGui::Separator();
  ImGui::AlignTextToFramePadding();
  ImGui::TextUnformatted("Slices");
  ImGui::SameLine();
  ImGui::Checkbox("axial", &sl.axial);
  ImGui::SameLine();
  ImGui::Checkbox("coronal", &sl.coronal);
  ImGui::SameLine();
  ImGui::Checkbox("sagittal", &sl.sagittal);
  ImGui::SameLine();
  ImGui::Checkbox("view", &sl.view_plane);
  float focus[3] = {static_cast<float>(stats.focus[0]), static_cast<float>(stats.focus[1]),
                    static_cast<float>(stats.focus[2])};
  if (ImGui::DragFloat3("Focus mm", focus, 0.5f, 0.0f, 0.0f, "%.1f"))
    out.focus = std::array<double, 3>{focus[0], focus[1], focus[2]};
  bool automatic = !sl.range;
  if (ImGui::Checkbox("auto grey", &automatic)) {
    if (automatic)
      sl.range.reset();
    else
      sl.range = stats.image_range;
  }
  ImGui::SameLine();
  ImGui::BeginDisabled(automatic);
  std::array<float, 2> r = sl.range.value_or(stats.image_range);
  ImGui::PushItemWidth(150);
  const float step = std::max(1e-3f, (r[1] - r[0]) / 200.0f);
  if (ImGui::DragFloat2("range##image", r.data(), step, 0.0f, 0.0f, "%.4g") && r[1] > r[0]) sl.range = r;
  ImGui::PopItemWidth();
  ImGui::EndDisabled();
}

// The transparency mode (each described when hovered), opacity, line width, colour, lighting, background,
// orientation labels, colour bar and the voxel grid.
void look_controls(PanelState& state, const PanelStats& stats) {
  RenderSettings& s = state.settings;
  if (ImGui::BeginCombo("Mode", render_mode_name(s.mode))) {
    for (const RenderModeInfo& m : render_modes()) {
      const bool selected = m.mode == s.mode;
      std::string label = m.name;
      if (m.needs_gl43 && !stats.exact_available) label += " (needs GL 4.3)";
      if (ImGui::Selectable(label.c_str(), selected)) s.mode = m.mode;
      if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", m.description);
      if (selected) ImGui::SetItemDefaultFocus();
    }
    ImGui::EndCombo();
  }
  ImGui::SliderFloat("Opacity", &s.opacity, 0.001f, 1.0f, "%.3f",
                     ImGuiSliderFlags_Logarithmic | ImGuiSliderFlags_AlwaysClamp);
  ImGui::SliderFloat("Line width", &s.line_width, 1.0f, stats.max_line_width, "%.1f px", ImGuiSliderFlags_AlwaysClamp);

  colour_controls(state, stats);
  ImGui::Checkbox("Lighting", &s.lighting);
  ImGui::SameLine();
  ImGui::BeginDisabled(!stats.exact_available);
  ImGui::Checkbox("Exact when still", &state.exact_when_still);
  if (ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled))
    ImGui::SetTooltip("at rest, basic and axis go on to the exact picture, run by run (needs OpenGL 4.3)");
  ImGui::EndDisabled();

  // Black and white at a click, any colour through the picker.
  ImGui::AlignTextToFramePadding();
  ImGui::TextUnformatted("Background");
  ImGui::SameLine();
  if (ImGui::Button("black")) s.background_color = glm::vec3(0.0f);
  ImGui::SameLine();
  if (ImGui::Button("white")) s.background_color = glm::vec3(1.0f);
  ImGui::SameLine();
  ImGui::ColorEdit3("##background colour", &s.background_color.x, ImGuiColorEditFlags_NoInputs);

  ImGui::Checkbox("Orientation labels", &s.orientation_labels);
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("L/R, P/A, I/S at the picture's edges and an axes triad");
  ImGui::SameLine();
  ImGui::BeginDisabled(s.color != ColorMode::Scalar);
  ImGui::Checkbox("Colour bar", &s.colorbar);
  ImGui::EndDisabled();

  ImGui::Checkbox("Voxel grid", &state.grid);
  ImGui::SameLine();
  ImGui::BeginDisabled(!state.grid);
  int grid_scope = state.grid_all ? 1 : 0;
  ImGui::RadioButton("drawn", &grid_scope, 0);
  ImGui::SameLine();
  ImGui::RadioButton("all", &grid_scope, 1);
  state.grid_all = grid_scope == 1;
  ImGui::EndDisabled();
}

// View presets, projection, camera reset, screenshot and saving the view.
void view_controls(PanelState& state, PanelRequests& out) {
  ImGui::Separator();
  ImGui::AlignTextToFramePadding();
  ImGui::TextUnformatted("View");
  ImGui::SameLine();
  view_button("Axial", "axial", out);
  ImGui::SameLine();
  view_button("Sagittal", "sagittal", out);
  ImGui::SameLine();
  view_button("Coronal", "coronal", out);
  ImGui::TextUnformatted("    ");
  ImGui::SameLine();
  view_button("Inferior", "inferior", out);
  ImGui::SameLine();
  view_button("Right", "right", out);
  ImGui::SameLine();
  view_button("Posterior", "posterior", out);
  int projection = state.orthographic ? 1 : 0;
  ImGui::RadioButton("perspective", &projection, 0);
  ImGui::SameLine();
  ImGui::RadioButton("orthographic", &projection, 1);
  state.orthographic = projection == 1;
  ImGui::SameLine();
  out.reset_camera = ImGui::Button("Reset");

  out.screenshot = ImGui::Button("Screenshot");
  ImGui::SameLine();
  ImGui::Checkbox("with panel", &state.panel_in_screenshot);
  ImGui::SameLine();
  out.save_view = ImGui::Button("Save view");
}

// Frame time, counts, the GL driver, the last error and status, and the keys (key_bindings.h).
void frame_information(const PanelState& state, const PanelStats& stats) {
  ImGui::Separator();
  ImGui::Text("Frame      %.2f ms", stats.frame_ms);
  ImGui::Text("Plan (CPU) %.3f ms", stats.plan_ms);
  ImGui::Text("Voxels     %s / %s", count_text(stats.voxels_drawn).c_str(), count_text(stats.voxels_total).c_str());
  ImGui::Text("Segments   %s / %s", count_text(stats.segments_drawn).c_str(), count_text(stats.segments_total).c_str());
  if (state.grid) ImGui::Text("Grid cubes %s", count_text(stats.grid_cubes).c_str());
  ImGui::PushTextWrapPos(ImGui::GetCursorPosX() + 330);
  ImGui::TextDisabled("%s, GL %s", stats.gl_renderer.c_str(), stats.gl_version.c_str());
  if (!stats.detail.empty()) ImGui::TextWrapped("%s", stats.detail.c_str());
  if (!stats.frame_level.empty()) ImGui::TextWrapped("Drawing %s", stats.frame_level.c_str());
  if (stats.frame_budget_ms > 0)
    ImGui::TextDisabled("Frame budget %.0f ms", stats.frame_budget_ms);
  else
    ImGui::TextDisabled("No frame budget: always full detail");
  if (!stats.refinement.empty()) ImGui::TextWrapped("At rest: %s", stats.refinement.c_str());
  if (!stats.error.empty()) ImGui::TextColored(ImVec4(1.0f, 0.4f, 0.35f, 1.0f), "%s", stats.error.c_str());
  if (!stats.status.empty()) ImGui::TextUnformatted(stats.status.c_str());
  ImGui::PopTextWrapPos();

  static const std::string controls = controls_as_columns();
  if (ImGui::CollapsingHeader("Keys and mouse")) ImGui::TextUnformatted(controls.c_str());
}

// The window's own key callback, installed before the panel's (one panel per process).
GLFWkeyfun window_keys = nullptr;

// Tab selects the next region (key_bindings.cpp). ImGui would take it as well, to move the keyboard focus into the
// panel, which would then keep every key until Escape: so Tab goes to the window's callback alone, and every other
// key to ImGui's, which passes it on to the window's.
void keys_for_panel_and_window(GLFWwindow* window, int key, int scancode, int action, int mods) {
  if (key == GLFW_KEY_TAB) {
    if (window_keys) window_keys(window, key, scancode, action, mods);
    return;
  }
  ImGui_ImplGlfw_KeyCallback(window, key, scancode, action, mods);
}

}  // namespace

UiPanel::UiPanel(GLFWwindow* window) {
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGuiIO& io = ImGui::GetIO();
  io.IniFilename = nullptr;  // leave no imgui.ini behind in the user's directory
  ImGui::StyleColorsDark();
  window_keys = glfwSetKeyCallback(window, nullptr);
  glfwSetKeyCallback(window, window_keys);
  ImGui_ImplGlfw_InitForOpenGL(window, true);  // ImGui's callbacks, each passing the event on to the window's
  glfwSetKeyCallback(window, keys_for_panel_and_window);
  ImGui_ImplOpenGL3_Init("#version 330 core");
}

UiPanel::~UiPanel() {
  ImGui_ImplOpenGL3_Shutdown();
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
}

bool UiPanel::takes_mouse_at(double x, double y) const {
  if (popup_open_ || ImGui::IsAnyItemActive()) return true;
  return x >= x0_ && x < x1_ && y >= y0_ && y < y1_;
}
bool UiPanel::wants_keyboard() const { return ImGui::GetIO().WantCaptureKeyboard; }

PanelRequests UiPanel::build(PanelState& state, const PanelStats& stats) {
  ImGui_ImplOpenGL3_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  ImGui::NewFrame();
  PanelRequests out;

  ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowBgAlpha(0.8f);
  // "###" keeps the window's identity apart from its title; ImGui's built-in font is ASCII only.
  const std::string title = "voxview: " + stats.title + "###panel";
  if (state.panel_collapsed != collapsed_) ImGui::SetNextWindowCollapsed(state.panel_collapsed, ImGuiCond_Always);
  if (ImGui::Begin(title.c_str(), nullptr, ImGuiWindowFlags_AlwaysAutoResize)) {
    ImGui::PushItemWidth(170);
    look_controls(state, stats);
    clipping_controls(state, stats, out);
    image_controls(state, stats, out);
    selection_controls(state, stats, out);
    view_controls(state, out);
    frame_information(state, stats);
    ImGui::PopItemWidth();
  }
  // The title bar's arrow collapses it too: the state follows whichever did.
  state.panel_collapsed = collapsed_ = ImGui::IsWindowCollapsed();
  const ImVec2 pos = ImGui::GetWindowPos(), size = ImGui::GetWindowSize();
  x0_ = pos.x;
  y0_ = pos.y;
  x1_ = pos.x + size.x;
  y1_ = pos.y + size.y;
  ImGui::End();
  popup_open_ = ImGui::IsPopupOpen("", ImGuiPopupFlags_AnyPopupId | ImGuiPopupFlags_AnyPopupLevel);
  return out;
}

void UiPanel::render() {
  ImGui::Render();
  ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
}

}  // namespace vxl::app
