#pragma once
// Headless OpenGL core-profile context through EGL (no window, no X server, no Wayland).
//
// Display selection (Options::platform == Auto), the first that initialises:
//   1. EGL_PLATFORM_DEVICE_EXT with an NVIDIA device (EGL_NV_device_cuda): beside NVIDIA's EGL, Mesa's may
//      answer the surfaceless platform with its software rasteriser,
//   2. EGL_PLATFORM_SURFACELESS_MESA (Mesa; also NVIDIA's EGL),
//   3. EGL_PLATFORM_DEVICE_EXT with each other enumerated device (EGL_EXT_device_enumeration), Mesa's
//      software device (EGL_MESA_device_software) last,
//   4. eglGetDisplay(EGL_DEFAULT_DISPLAY), only when EGL_EXT_platform_base is missing.
// Context: OpenGL core profile, highest of 4.6, 4.5, 4.3, 3.3 (capped by Options::max_version),
// without a config (EGL_KHR_no_config_context) and without a surface (EGL_KHR_surfaceless_context);
// each has a fallback (eglChooseConfig / a 1x1 pbuffer) for EGL implementations lacking them.
// Rendering goes into an FBO (see OffscreenTarget).
//
// Epoxy is the GL/EGL loader: call eglGetPlatformDisplayEXT, never eglGetPlatformDisplay (epoxy
// aborts on the latter when it cannot resolve it).
//
// All failures throw std::runtime_error naming the failing EGL call and eglGetError() in hex.

#include <compare>
#include <optional>
#include <string>

namespace vxl {

struct GlVersion {
  int major = 0;
  int minor = 0;
  friend constexpr auto operator<=>(const GlVersion&, const GlVersion&) = default;
};

std::string to_string(GlVersion v);  // "4.5"

class HeadlessGlContext {
 public:
  enum class Platform {
    Auto,         // an NVIDIA device, surfaceless, the other devices, then the default display
    Surfaceless,  // EGL_PLATFORM_SURFACELESS_MESA only
    Device,       // EGL_PLATFORM_DEVICE_EXT only: each device in Auto's order until one initialises
  };

  struct Options {
    // Highest core version to ask for; nullopt = the highest available of 4.6/4.5/4.3/3.3.
    // Drivers may legally hand out a *newer* compatible version than requested (Mesa and
    // NVIDIA do: asking for 3.3 core gives 4.5 / 4.6). See enforce_max_version.
    std::optional<GlVersion> max_version;
    // When max_version is set and the driver returns a newer version: throw (true) or keep the
    // newer context (false; has_compute() then still honours max_version). On Mesa a true 3.3
    // context needs limit_mesa_gl_version({3, 3}) before the first context of the process.
    bool enforce_max_version = true;
    Platform platform = Platform::Auto;
    bool debug = false;  // EGL_CONTEXT_OPENGL_DEBUG
  };

  HeadlessGlContext();  // = HeadlessGlContext(Options{})
  explicit HeadlessGlContext(const Options& options);
  ~HeadlessGlContext();
  HeadlessGlContext(const HeadlessGlContext&) = delete;
  HeadlessGlContext& operator=(const HeadlessGlContext&) = delete;
  HeadlessGlContext(HeadlessGlContext&&) = delete;
  HeadlessGlContext& operator=(HeadlessGlContext&&) = delete;

  // The constructor leaves the new context current on the calling thread.
  void make_current() const;
  void release_current() const;  // no context current on this thread afterwards
  bool is_current() const;

  // Actual version reported by GL (GL_MAJOR_VERSION / GL_MINOR_VERSION).
  int major() const { return version_.major; }
  int minor() const { return version_.minor; }
  GlVersion version() const { return version_; }
  // The version passed to eglCreateContext (<= max_version when set).
  GlVersion requested_version() const { return requested_; }
  bool core_profile() const { return core_; }  // always true (checked at creation)
  // Compute shaders + SSBOs usable: GL >= 4.3 and max_version (if any) >= 4.3.
  bool has_compute() const;

  std::string renderer() const { return renderer_; }              // GL_RENDERER
  std::string vendor() const { return vendor_; }                  // GL_VENDOR
  std::string version_string() const { return version_string_; }  // GL_VERSION
  std::string egl_vendor() const { return egl_vendor_; }          // EGL_VENDOR
  std::string platform_name() const { return platform_name_; }    // "surfaceless", "device", "default"

  // Mesa reads MESA_GL_VERSION_OVERRIDE / MESA_GLSL_VERSION_OVERRIDE once per process, when the
  // first context is created. This sets both (e.g. "3.3" and "330") so that later contexts are
  // true 3.3 core contexts. Process-wide and sticky: use it in a dedicated process (a test child,
  // a `--gl-max-version` start-up option). Returns false when a HeadlessGlContext was already
  // created in this process (then the limit probably has no effect). No effect on non-Mesa drivers.
  static bool limit_mesa_gl_version(GlVersion v);

 private:
  void* display_ = nullptr;  // EGLDisplay
  void* context_ = nullptr;  // EGLContext
  void* surface_ = nullptr;  // EGLSurface: EGL_NO_SURFACE unless a pbuffer fallback was needed
  GlVersion version_{};
  GlVersion requested_{};
  std::optional<GlVersion> max_version_;
  bool core_ = false;
  std::string renderer_, vendor_, version_string_, egl_vendor_, platform_name_;

  void destroy() noexcept;
};

}  // namespace vxl
