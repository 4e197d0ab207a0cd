// The GLFW side of voxview's window: the library, a window with an OpenGL 3.3 core context, its back buffer
// read back, and the stamped names of what the window saves.
#pragma once

#include <filesystem>
#include <memory>
#include <string>

#define GLFW_INCLUDE_NONE  // epoxy provides the GL declarations
#include <GLFW/glfw3.h>

#include "viewer/app/viewer_options.h"
#include "viewer/platform/image_io.h"

namespace vxl::app {

// glfwInit / glfwTerminate. Without an X server glfwInit fails, which is the common case (ssh, CI).
struct GlfwLibrary {
  GlfwLibrary();
  ~GlfwLibrary();
  GlfwLibrary(const GlfwLibrary&) = delete;
  GlfwLibrary& operator=(const GlfwLibrary&) = delete;
};

struct WindowDeleter {
  void operator()(GLFWwindow* w) const;
};
using WindowPtr = std::unique_ptr<GLFWwindow, WindowDeleter>;

// The window for `o` (its inputs in the title, its size fitted to the screen unless given), its context current.
WindowPtr open_window(const ViewerOptions& o);

// The default framebuffer's back buffer as RGBA8 rows top to bottom (GL counts rows from the bottom).
Image read_back_buffer(int width, int height);

// voxview-YYYYMMDD-HHMMSS.png (or .json, ...) in the current directory, with a suffix when taken twice in
// a second.
std::filesystem::path stamped_name(const std::string& prefix, const std::string& extension);

}  // namespace vxl::app
