#include "viewer/platform/egl_context.h"
#include "viewer/platform/gl_driver_pinning.h"

#include <epoxy/egl.h>
#include <epoxy/gl.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <mutex>
#include <stdexcept>
#include <vector>

namespace vxl {

std::string to_string(GlVersion v) { return std::to_string(v.major) + "." + std::to_string(v.minor); }

namespace {

constexpr const char* kHint =
    "is Mesa's libegl-mesa0 / libgl1-mesa-dri installed (or the NVIDIA EGL driver)? "
    "EGL_LOG_LEVEL=debug shows what Mesa's EGL tried";

const char* egl_error_name(EGLint e) {
  switch (e) {
    case EGL_SUCCESS: return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED: return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS: return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC: return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE: return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONFIG: return "EGL_BAD_CONFIG";
    case EGL_BAD_CONTEXT: return "EGL_BAD_CONTEXT";
    case EGL_BAD_CURRENT_SURFACE: return "EGL_BAD_CURRENT_SURFACE";
    case EGL_BAD_DISPLAY: return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH: return "EGL_BAD_MATCH";
    case EGL_BAD_NATIVE_PIXMAP: return "EGL_BAD_NATIVE_PIXMAP";
    case EGL_BAD_NATIVE_WINDOW: return "EGL_BAD_NATIVE_WINDOW";
    case EGL_BAD_PARAMETER: return "EGL_BAD_PARAMETER";
    case EGL_BAD_SURFACE: return "EGL_BAD_SURFACE";
    case EGL_CONTEXT_LOST: return "EGL_CONTEXT_LOST";
    default: return "unknown EGL error";
  }
}

std::string egl_error_text(EGLint e) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "0x%04X %s", static_cast<unsigned>(e), egl_error_name(e));
  return buf;
}

[[noreturn]] void fail(const std::string& what, EGLint err) {
  throw std::runtime_error("HeadlessGlContext: " + what + " failed (eglGetError " + egl_error_text(err) + "); " +
                           kHint);
}

bool has_extension(const char* list, const char* name) {
  if (list == nullptr) return false;
  const std::string s = std::string(" ") + list + " ";
  return s.find(std::string(" ") + name + " ") != std::string::npos;
}

// EGL displays are per-process singletons per (platform, native display): eglTerminate on one
// terminates it for every user. Reference-count our own initialisations so that several
// HeadlessGlContext objects can coexist and the display is terminated by the last one.
std::mutex g_display_mutex;
std::map<EGLDisplay, int> g_display_refs;
bool g_any_context_created = false;

void acquire_display(EGLDisplay dpy, const char* platform) {
  std::lock_guard lock(g_display_mutex);
  int& refs = g_display_refs[dpy];
  if (refs == 0) {
    EGLint major = 0, minor = 0;
    if (eglInitialize(dpy, &major, &minor) != EGL_TRUE) {
      const EGLint err = eglGetError();
      g_display_refs.erase(dpy);
      fail(std::string("eglInitialize (") + platform + " display)", err);
    }
    pin_dri_drivers();
  }
  ++refs;
  g_any_context_created = true;
}

void release_display(EGLDisplay dpy) noexcept {
  std::lock_guard lock(g_display_mutex);
  auto it = g_display_refs.find(dpy);
  if (it == g_display_refs.end()) return;
  if (--it->second == 0) {
    g_display_refs.erase(it);
    eglTerminate(dpy);
    if (g_display_refs.empty()) eglReleaseThread();
  }
}

struct DisplayChoice {
  EGLDisplay display = EGL_NO_DISPLAY;
  const char* name = "";
};

// Opens (gets + initialises) a display; returns EGL_NO_DISPLAY with `errors` appended on failure.
EGLDisplay try_platform_display(EGLenum platform, void* native, const char* name, std::string& errors) {
  EGLDisplay dpy = eglGetPlatformDisplayEXT(platform, native, nullptr);
  if (dpy == EGL_NO_DISPLAY) {
    errors += std::string("; eglGetPlatformDisplayEXT(") + name + ") failed (eglGetError " +
              egl_error_text(eglGetError()) + ")";
    return EGL_NO_DISPLAY;
  }
  try {
    acquire_display(dpy, name);
  } catch (const std::exception& e) {
    errors += std::string("; ") + e.what();
    return EGL_NO_DISPLAY;
  }
  return dpy;
}

// The EGL devices in the order they are tried: NVIDIA's (EGL_NV_device_cuda), the other hardware ones, and
// Mesa's software rasteriser (EGL_MESA_device_software) last.
struct Devices {
  std::vector<EGLDeviceEXT> nvidia, hardware, software;
};

Devices enumerate_devices(const char* client, std::string& errors) {
  Devices found;
  if (!has_extension(client, "EGL_EXT_platform_base") || !has_extension(client, "EGL_EXT_platform_device") ||
      !(has_extension(client, "EGL_EXT_device_enumeration") || has_extension(client, "EGL_EXT_device_base"))) {
    errors += "; EGL_EXT_platform_device / EGL_EXT_device_enumeration not offered";
    return found;
  }
  EGLint count = 0;
  std::array<EGLDeviceEXT, 16> devices{};
  if (eglQueryDevicesEXT(static_cast<EGLint>(devices.size()), devices.data(), &count) != EGL_TRUE) {
    errors += "; eglQueryDevicesEXT failed (eglGetError " + egl_error_text(eglGetError()) + ")";
    return found;
  }
  if (count <= 0) errors += "; eglQueryDevicesEXT found no device";
  const bool query = has_extension(client, "EGL_EXT_device_query") || has_extension(client, "EGL_EXT_device_base");
  for (EGLint i = 0; i < count; ++i) {
    const char* exts = query ? eglQueryDeviceStringEXT(devices[i], EGL_EXTENSIONS) : nullptr;
    if (has_extension(exts, "EGL_MESA_device_software"))
      found.software.push_back(devices[i]);
    else if (has_extension(exts, "EGL_NV_device_cuda"))
      found.nvidia.push_back(devices[i]);
    else
      found.hardware.push_back(devices[i]);
  }
  return found;
}

// The first of `devices` whose display initialises; EGL_NO_DISPLAY (each failure appended to `errors`) if none.
EGLDisplay try_devices(const std::vector<EGLDeviceEXT>& devices, std::string& errors) {
  for (EGLDeviceEXT device : devices) {
    EGLDisplay dpy = try_platform_display(EGL_PLATFORM_DEVICE_EXT, device, "EGL_PLATFORM_DEVICE_EXT", errors);
    if (dpy != EGL_NO_DISPLAY) return dpy;
  }
  return EGL_NO_DISPLAY;
}

DisplayChoice open_display(HeadlessGlContext::Platform platform) {
  using P = HeadlessGlContext::Platform;
  const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  if (client == nullptr && platform == P::Auto) {
    // EGL 1.4 without EGL_EXT_client_extensions: only the default display exists.
    EGLDisplay dpy = eglGetDisplay(EGL_DEFAULT_DISPLAY);
    if (dpy == EGL_NO_DISPLAY) fail("eglGetDisplay(EGL_DEFAULT_DISPLAY)", eglGetError());
    acquire_display(dpy, "default");
    return {dpy, "default"};
  }
  if (client == nullptr) fail("eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS)", eglGetError());

  const bool platform_base = has_extension(client, "EGL_EXT_platform_base");
  std::string errors;
  const Devices devices = platform == P::Surfaceless ? Devices{} : enumerate_devices(client, errors);
  // An NVIDIA GPU before Mesa's surfaceless platform: beside NVIDIA's EGL, Mesa's may answer that platform with
  // its software rasteriser.
  if (EGLDisplay dpy = try_devices(devices.nvidia, errors); dpy != EGL_NO_DISPLAY) return {dpy, "device"};
  if (platform == P::Auto || platform == P::Surfaceless) {
    if (platform_base && has_extension(client, "EGL_MESA_platform_surfaceless")) {
      EGLDisplay dpy = try_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY,
                                            "EGL_PLATFORM_SURFACELESS_MESA", errors);
      if (dpy != EGL_NO_DISPLAY) return {dpy, "surfaceless"};
    } else {
      errors += "; EGL_MESA_platform_surfaceless not offered";
    }
  }
  for (const std::vector<EGLDeviceEXT>* list : {&devices.hardware, &devices.software})
    if (EGLDisplay dpy = try_devices(*list, errors); dpy != EGL_NO_DISPLAY) return {dpy, "device"};
  if (platform == P::Auto && !platform_base) {
    EGLDisplay dpy = eglGetDisplay(EGL_DEFAULT_DISPLAY);
    if (dpy != EGL_NO_DISPLAY) {
      acquire_display(dpy, "default");
      return {dpy, "default"};
    }
    errors += "; eglGetDisplay(EGL_DEFAULT_DISPLAY) failed (eglGetError " + egl_error_text(eglGetError()) + ")";
  }
  throw std::runtime_error("HeadlessGlContext: no usable headless EGL display (client extensions: " +
                           std::string(client) + ")" + errors + "; " + kHint);
}

}  // namespace

HeadlessGlContext::HeadlessGlContext() : HeadlessGlContext(Options{}) {}

HeadlessGlContext::HeadlessGlContext(const Options& options) : max_version_(options.max_version) {
  const DisplayChoice choice = open_display(options.platform);
  EGLDisplay dpy = choice.display;
  display_ = dpy;
  platform_name_ = choice.name;
  try {
    const char* vendor = eglQueryString(dpy, EGL_VENDOR);
    egl_vendor_ = vendor ? vendor : "";
    const char* exts = eglQueryString(dpy, EGL_EXTENSIONS);
    EGLint egl_major = 1, egl_minor = 4;
    eglInitialize(dpy, &egl_major, &egl_minor);  // already initialised: only returns the version
    if (egl_major == 1 && egl_minor < 5 && !has_extension(exts, "EGL_KHR_create_context"))
      throw std::runtime_error("HeadlessGlContext: EGL " + std::to_string(egl_major) + "." + std::to_string(egl_minor) +
                               " without EGL_KHR_create_context cannot create a core-profile context; " + kHint);

    if (eglBindAPI(EGL_OPENGL_API) != EGL_TRUE) fail("eglBindAPI(EGL_OPENGL_API)", eglGetError());

    const bool no_config =
        has_extension(exts, "EGL_KHR_no_config_context") || has_extension(exts, "EGL_MESA_configless_context");
    const bool surfaceless = has_extension(exts, "EGL_KHR_surfaceless_context");
    EGLConfig config = EGL_NO_CONFIG_KHR;
    if (!no_config || !surfaceless) {
      const EGLint attribs[] = {EGL_RENDERABLE_TYPE,
                                EGL_OPENGL_BIT,
                                EGL_SURFACE_TYPE,
                                surfaceless ? 0 : EGL_PBUFFER_BIT,
                                EGL_RED_SIZE,
                                8,
                                EGL_GREEN_SIZE,
                                8,
                                EGL_BLUE_SIZE,
                                8,
                                EGL_ALPHA_SIZE,
                                8,
                                EGL_NONE};
      EGLint n = 0;
      if (eglChooseConfig(dpy, attribs, &config, 1, &n) != EGL_TRUE) fail("eglChooseConfig", eglGetError());
      if (n < 1)
        throw std::runtime_error("HeadlessGlContext: eglChooseConfig found no OpenGL config; " + std::string(kHint));
    }

    static constexpr std::array<GlVersion, 4> kCandidates{{{4, 6}, {4, 5}, {4, 3}, {3, 3}}};
    std::string tried;
    EGLint last_error = EGL_SUCCESS;
    EGLContext ctx = EGL_NO_CONTEXT;
    for (const GlVersion v : kCandidates) {
      if (options.max_version && v > *options.max_version) continue;
      std::vector<EGLint> attribs{EGL_CONTEXT_MAJOR_VERSION,       v.major,
                                  EGL_CONTEXT_MINOR_VERSION,       v.minor,
                                  EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT};
      if (options.debug) attribs.insert(attribs.end(), {EGL_CONTEXT_OPENGL_DEBUG, EGL_TRUE});
      attribs.push_back(EGL_NONE);
      ctx = eglCreateContext(dpy, config, EGL_NO_CONTEXT, attribs.data());
      tried += (tried.empty() ? "" : ", ") + to_string(v);
      if (ctx != EGL_NO_CONTEXT) {
        requested_ = v;
        break;
      }
      last_error = eglGetError();
    }
    if (ctx == EGL_NO_CONTEXT) {
      if (tried.empty())
        throw std::runtime_error("HeadlessGlContext: max_version " + to_string(*options.max_version) +
                                 " is below OpenGL 3.3 core, the lowest version supported");
      fail("eglCreateContext (OpenGL core " + tried + ", " +
               (config == EGL_NO_CONFIG_KHR ? "EGL_NO_CONFIG_KHR" : "chosen config") + ")",
           last_error);
    }
    context_ = ctx;

    EGLSurface surface = EGL_NO_SURFACE;
    if (!surfaceless) {
      const EGLint pb[] = {EGL_WIDTH, 1, EGL_HEIGHT, 1, EGL_NONE};
      surface = eglCreatePbufferSurface(dpy, config, pb);
      if (surface == EGL_NO_SURFACE) fail("eglCreatePbufferSurface (no EGL_KHR_surfaceless_context)", eglGetError());
      surface_ = surface;
    }
    if (eglMakeCurrent(dpy, surface, surface, ctx) != EGL_TRUE)
      fail(surface == EGL_NO_SURFACE ? "eglMakeCurrent(EGL_NO_SURFACE)" : "eglMakeCurrent(pbuffer)", eglGetError());

    GLint major = 0, minor = 0, profile = 0;
    glGetIntegerv(GL_MAJOR_VERSION, &major);
    glGetIntegerv(GL_MINOR_VERSION, &minor);
    glGetIntegerv(GL_CONTEXT_PROFILE_MASK, &profile);
    version_ = {major, minor};
    core_ = (profile & GL_CONTEXT_CORE_PROFILE_BIT) != 0;
    auto str = [](GLenum name) {
      const auto* s = reinterpret_cast<const char*>(glGetString(name));
      return std::string(s ? s : "");
    };
    renderer_ = str(GL_RENDERER);
    vendor_ = str(GL_VENDOR);
    version_string_ = str(GL_VERSION);

    if (version_ < GlVersion{3, 3} || !core_)
      throw std::runtime_error("HeadlessGlContext: got OpenGL \"" + version_string_ + "\" (" + to_string(version_) +
                               (core_ ? " core" : " non-core") + "), need a 3.3+ core profile; renderer: " + renderer_);
    if (options.max_version && options.enforce_max_version && version_ > *options.max_version)
      throw std::runtime_error("HeadlessGlContext: asked for OpenGL " + to_string(requested_) + " core (max_version " +
                               to_string(*options.max_version) + ") but the driver returned " + to_string(version_) +
                               " (\"" + version_string_ + "\", " + renderer_ +
                               "); drivers may return any newer compatible version. With Mesa call "
                               "HeadlessGlContext::limit_mesa_gl_version() (MESA_GL_VERSION_OVERRIDE=" +
                               to_string(*options.max_version) +
                               ", MESA_GLSL_VERSION_OVERRIDE) before the first context of the "
                               "process, or set Options::enforce_max_version = false");
  } catch (...) {
    destroy();
    throw;
  }
}

HeadlessGlContext::~HeadlessGlContext() { destroy(); }

void HeadlessGlContext::destroy() noexcept {
  if (display_ == nullptr) return;
  EGLDisplay dpy = display_;
  if (context_ != nullptr) {
    if (eglGetCurrentContext() == context_) eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(dpy, context_);
    context_ = nullptr;
  }
  if (surface_ != nullptr) {
    eglDestroySurface(dpy, surface_);
    surface_ = nullptr;
  }
  release_display(dpy);
  display_ = nullptr;
}

void HeadlessGlContext::make_current() const {
  if (eglMakeCurrent(display_, surface_, surface_, context_) != EGL_TRUE) fail("eglMakeCurrent", eglGetError());
}

void HeadlessGlContext::release_current() const {
  if (is_current() && eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT) != EGL_TRUE)
    fail("eglMakeCurrent(EGL_NO_CONTEXT)", eglGetError());
}

bool HeadlessGlContext::is_current() const { return context_ != nullptr && eglGetCurrentContext() == context_; }

bool HeadlessGlContext::has_compute() const {
  constexpr GlVersion k43{4, 3};
  return version_ >= k43 && (!max_version_ || *max_version_ >= k43);
}

bool HeadlessGlContext::limit_mesa_gl_version(GlVersion v) {
  const std::string gl = to_string(v);
  const std::string glsl = std::to_string(v.major * 100 + v.minor * 10);
  setenv("MESA_GL_VERSION_OVERRIDE", gl.c_str(), 1);
  setenv("MESA_GLSL_VERSION_OVERRIDE", glsl.c_str(), 1);
  std::lock_guard lock(g_display_mutex);
  return !g_any_context_created;
}

}  // namespace vxl
