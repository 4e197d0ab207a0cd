#include "viewer/app/glfw_window.h"

#include <algorithm>
#include <array>
#include <ctime>
#include <stdexcept>
#include <vector>

#include <epoxy/gl.h>

#include "viewer/app/window_size.h"
#include "viewer/platform/gl_driver_pinning.h"

namespace vxl::app {

namespace {

const char* const kHeadlessHint = "use --render OUT.png for headless rendering";

std::string g_glfw_error;  // GLFW reports errors through a callback; kept for the exception's message
void remember_glfw_error(int, const char* text) { g_glfw_error = text ? text : "unknown GLFW error"; }

}  // namespace

GlfwLibrary::GlfwLibrary() {
  glfwSetErrorCallback(remember_glfw_error);
  if (!glfwInit())
    throw std::runtime_error("cannot open a window (no display?): " + g_glfw_error + "; " + kHeadlessHint);
}

GlfwLibrary::~GlfwLibrary() { glfwTerminate(); }

void WindowDeleter::operator()(GLFWwindow* w) const { glfwDestroyWindow(w); }

WindowPtr open_window(const ViewerOptions& o) {
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  // Not forward-compatible: that would forbid line widths above 1.
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_FALSE);
  glfwWindowHint(GLFW_DEPTH_BITS, 24);  // the opaque mode depth-tests in the default framebuffer
  std::string title = "voxview -";
  for (const std::string& in : o.inputs) title += " " + std::filesystem::path(in).filename().string();
  // The default size is for a large screen: on a smaller one (a 1280x800 laptop) it is scaled down to fit.
  // A size given by --size or a saved view is kept.
  std::array<int, 2> size{o.width, o.height};
  if (!o.size_given) {
    int x = 0, y = 0, area_w = 0, area_h = 0;
    if (GLFWmonitor* monitor = glfwGetPrimaryMonitor()) glfwGetMonitorWorkarea(monitor, &x, &y, &area_w, &area_h);
    size = fit_to_work_area(o.width, o.height, area_w, area_h);
  }
  GLFWwindow* w = glfwCreateWindow(size[0], size[1], title.c_str(), nullptr, nullptr);
  if (!w) throw std::runtime_error("cannot open an OpenGL 3.3 core window: " + g_glfw_error + "; " + kHeadlessHint);
  glfwMakeContextCurrent(w);
  glfwSwapInterval(1);
  pin_dri_drivers();  // see gl_driver_pinning.h: Mesa's GLX path loads the same driver
  return WindowPtr(w);
}

Image read_back_buffer(int width, int height) {
  Image img;
  img.width = width;
  img.height = height;
  img.rgba.resize(static_cast<std::size_t>(width) * height * 4);
  std::vector<std::uint8_t> rows(img.rgba.size());
  glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
  glReadBuffer(GL_BACK);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, rows.data());
  const std::size_t stride = static_cast<std::size_t>(width) * 4;
  for (int y = 0; y < height; ++y)
    std::copy_n(rows.data() + (height - 1 - y) * stride, stride, img.rgba.data() + y * stride);
  // A window's picture is opaque whatever the framebuffer kept in alpha (it may have no alpha at all).
  for (std::size_t i = 3; i < img.rgba.size(); i += 4) img.rgba[i] = 255;
  return img;
}

std::filesystem::path stamped_name(const std::string& prefix, const std::string& extension) {
  std::time_t now = std::time(nullptr);
  std::tm local{};
  localtime_r(&now, &local);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y%m%d-%H%M%S", &local);
  std::filesystem::path p = std::filesystem::current_path() / (prefix + stamp + extension);
  for (int n = 2; std::filesystem::exists(p); ++n)
    p = std::filesystem::current_path() / (prefix + stamp + "-" + std::to_string(n) + extension);
  return p;
}

}  // namespace vxl::app
