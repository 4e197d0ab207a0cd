#include "viewer/app/picture_annotations.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include <imgui.h>
#include <imgui_impl_opengl3.h>

#include "viewer/render/background_color.h"
#include "viewer/render/colormap.h"
#include "viewer/render/renderer.h"

namespace vxl::app {

namespace {

constexpr glm::dvec3 kAxes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
constexpr ImU32 kAxisColours[3] = {IM_COL32(255, 64, 64, 255), IM_COL32(64, 230, 64, 255), IM_COL32(90, 130, 255, 255)};

ImU32 colour_u32(const glm::vec3& c) {
  const glm::vec3 v = glm::clamp(c, 0.0f, 1.0f);
  return ImGui::ColorConvertFloat4ToU32(ImVec4(v.r, v.g, v.b, 1.0f));
}

// Makes `context` current for its lifetime, then the one before (the window's panel) again.
class ImGuiContextScope {
 public:
  explicit ImGuiContextScope(ImGuiContext* context) : previous_(ImGui::GetCurrentContext()) {
    ImGui::SetCurrentContext(context);
  }
  ~ImGuiContextScope() { ImGui::SetCurrentContext(previous_); }
  ImGuiContextScope(const ImGuiContextScope&) = delete;
  ImGuiContextScope& operator=(const ImGuiContextScope&) = delete;

 private:
  ImGuiContext* previous_;
};

PixelBox box_of(ImVec2 pos, ImVec2 size) { return {pos.x, pos.y, pos.x + size.x, pos.y + size.y}; }

PixelBox united(const PixelBox& a, const PixelBox& b) {
  return {std::min(a.x0, b.x0), std::min(a.y0, b.y0), std::max(a.x1, b.x1), std::max(a.y1, b.y1)};
}

std::string number_text(float v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

}  // namespace

char anatomical_letter(const glm::dvec3& d) {
  const glm::dvec3 a = glm::abs(d);
  if (a.x >= a.y && a.x >= a.z) return d.x >= 0 ? 'R' : 'L';
  if (a.y >= a.z) return d.y >= 0 ? 'A' : 'P';
  return d.z >= 0 ? 'S' : 'I';
}

EdgeLetters edge_letters(const Camera& camera) {
  const glm::dvec3 right = camera.right(), up = camera.up();
  return {anatomical_letter(right), anatomical_letter(-right), anatomical_letter(up), anatomical_letter(-up)};
}

PictureAnnotations::PictureAnnotations() {
  // With none current, CreateContext makes the new context current; the scope then restores the caller's.
  ImGuiContextScope scope(nullptr);
  context_ = ImGui::CreateContext();
  ImGuiIO& io = ImGui::GetIO();
  io.IniFilename = nullptr;
  io.LogFilename = nullptr;
  // The built-in font is a pixel font drawn at 13 px: its multiples stay sharp.
  for (std::size_t k = 0; k < fonts_.size(); ++k) {
    ImFontConfig config;
    config.SizePixels = 13.0f * float(k + 1);
    fonts_[k] = io.Fonts->AddFontDefault(&config);
  }
  ImGui_ImplOpenGL3_Init("#version 330 core");
}

PictureAnnotations::~PictureAnnotations() {
  ImGuiContextScope scope(context_);  // restores the caller's context afterwards
  ImGui_ImplOpenGL3_Shutdown();
  ImGui::DestroyContext(context_);
}

bool PictureAnnotations::wanted(const RenderSettings& s) {
  return s.orientation_labels || (s.colorbar && s.color == ColorMode::Scalar);
}

void PictureAnnotations::draw(const Camera& camera, const RenderSettings& s, const Renderer& renderer, int width,
                              int height) {
  layout_ = AnnotationLayout{};
  if (!wanted(s) || width < 1 || height < 1) return;
  ImGuiContextScope scope(context_);
  ImGuiIO& io = ImGui::GetIO();
  io.DisplaySize = ImVec2(float(width), float(height));
  io.DisplayFramebufferScale = ImVec2(1, 1);
  io.DeltaTime = 1.0f / 60.0f;
  ImGui_ImplOpenGL3_NewFrame();
  ImGui::NewFrame();
  ImDrawList& dl = *ImGui::GetForegroundDrawList();

  // Text a 512-pixel picture shows at 13 px, larger pictures at a multiple.
  const int scale = std::clamp(int(std::lround(std::min(width, height) / 512.0)), 1, int(fonts_.size()));
  ImFont* font = fonts_[scale - 1];
  const float text_px = 13.0f * float(scale), margin = std::round(text_px * 0.5f);
  layout_.text_px = text_px;
  const glm::vec3 ink_rgb = background_is_light(s.background()) ? glm::vec3(0.05f) : glm::vec3(0.95f);
  const ImU32 ink = colour_u32(ink_rgb);
  auto text_size = [&](const std::string& text) { return font->CalcTextSizeA(text_px, 1e9f, 0, text.c_str()); };
  auto text_at = [&](ImVec2 pos, const std::string& text, ImU32 colour) {
    pos = ImVec2(std::round(pos.x), std::round(pos.y));  // whole pixels: the pixel font stays sharp
    dl.AddText(font, text_px, pos, colour, text.c_str());
    return box_of(pos, text_size(text));
  };

  // The colour bar first: the right edge's letter then stands to its left.
  float right_edge = float(width) - margin;
  if (s.colorbar && s.color == ColorMode::Scalar) {
    const std::array<float, 2> range = renderer.scalar_range(s);
    const float bar_w = std::round(text_px * 0.9f);
    const PixelBox bar{right_edge - bar_w, std::round(height * 0.25f), right_edge, std::round(height * 0.75f)};
    // Each of the colour map's 32 intervals as one quad whose ends carry the table's samples: the bar
    // interpolates them linearly, as the line shader does.
    const auto& samples = colormap_samples(s.colormap);
    const float step = (bar.y1 - bar.y0) / float(kColormapSamples - 1);
    for (int i = 0; i + 1 < kColormapSamples; ++i) {
      const ImU32 low = colour_u32(samples[i]), high = colour_u32(samples[i + 1]);
      const float y_low = bar.y1 - step * float(i), y_high = bar.y1 - step * float(i + 1);
      dl.AddRectFilledMultiColor(ImVec2(bar.x0, y_high), ImVec2(bar.x1, y_low), high, high, low, low);
    }
    dl.AddRect(ImVec2(bar.x0 - 1, bar.y0 - 1), ImVec2(bar.x1 + 1, bar.y1 + 1), ink, 0, 0, 1.0f);
    layout_.colorbar = bar;
    PixelBox texts{bar.x0 - 2, bar.y0 - 2, bar.x1 + 2, bar.y1 + 2};
    const std::string max_text = number_text(range[1]), min_text = number_text(range[0]);
    const std::string name = renderer.scalar_name(s);
    const float gap = std::round(text_px * 0.25f);
    const ImVec2 max_size = text_size(max_text), min_size = text_size(min_text), name_size = text_size(name);
    const float max_y = bar.y0 - 1 - gap - max_size.y;
    texts = united(texts, text_at(ImVec2(right_edge - max_size.x, max_y), max_text, ink));
    texts = united(texts, text_at(ImVec2(right_edge - name_size.x, max_y - name_size.y), name, ink));
    texts = united(texts, text_at(ImVec2(right_edge - min_size.x, bar.y1 + 1 + gap), min_text, ink));
    layout_.colorbar_texts = texts;
    right_edge = bar.x0 - 1 - margin;
  }

  if (s.orientation_labels) {
    const EdgeLetters letters = edge_letters(camera);
    const std::string right(1, letters.right), left(1, letters.left), top(1, letters.top), bottom(1, letters.bottom);
    const ImVec2 size = text_size(right);  // one letter of a monospaced font
    const float mid_x = float(width) * 0.5f - size.x * 0.5f, mid_y = float(height) * 0.5f - size.y * 0.5f;
    layout_.edge_labels[0] = text_at(ImVec2(right_edge - size.x, mid_y), right, ink);
    layout_.edge_labels[1] = text_at(ImVec2(margin, mid_y), left, ink);
    layout_.edge_labels[2] = text_at(ImVec2(mid_x, margin), top, ink);
    layout_.edge_labels[3] = text_at(ImVec2(mid_x, float(height) - margin - size.y), bottom, ink);

    // The triad: each world axis as the screen shows it (screen y grows downwards), farthest first so that
    // the axis nearest the viewer is on top.
    const float arm = std::max(text_px * 1.5f, std::round(float(std::min(width, height)) * 0.05f));
    const float reach = arm + 1.25f * size.y;  // the letters beyond the tips
    const ImVec2 centre(margin + reach, float(height) - margin - reach);
    const glm::dvec3 right_dir = camera.right(), up_dir = camera.up(), forward = camera.forward();
    int order[3] = {0, 1, 2};
    std::sort(order, order + 3,
              [&](int a, int b) { return glm::dot(kAxes[a], forward) > glm::dot(kAxes[b], forward); });
    const float thickness = std::max(2.0f, text_px / 6.0f);
    for (int i : order) {
      const ImVec2 v(float(glm::dot(kAxes[i], right_dir)), float(-glm::dot(kAxes[i], up_dir)));
      const ImVec2 tip(centre.x + arm * v.x, centre.y + arm * v.y);
      dl.AddLine(centre, tip, kAxisColours[i], thickness);
      const float length = std::sqrt(v.x * v.x + v.y * v.y);
      const ImVec2 out = length > 1e-3f ? ImVec2(v.x / length, v.y / length) : ImVec2(0, 0);
      const std::string letter(1, "RAS"[i]);
      const ImVec2 at(tip.x + out.x * size.y * 0.6f - size.x * 0.5f, tip.y + out.y * size.y * 0.6f - size.y * 0.5f);
      text_at(at, letter, kAxisColours[i]);
    }
    layout_.triad = {centre.x - reach - 1, centre.y - reach - 1, centre.x + reach + 1, centre.y + reach + 1};
  }

  ImGui::Render();
  ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
}

}  // namespace vxl::app
