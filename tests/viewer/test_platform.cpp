// Platform layer: headless EGL context, off-screen target, image files.
// Needs no display: the context comes from EGL surfaceless (Mesa llvmpipe without a GPU).
#include <gtest/gtest.h>

#include <epoxy/gl.h>

#include <zlib.h>

#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "format/base/error.h"
#include "viewer/platform/egl_context.h"
#include "viewer/platform/image_io.h"
#include "viewer/platform/offscreen_target.h"

namespace fs = std::filesystem;
using vxl::GlVersion;
using vxl::HeadlessGlContext;
using vxl::Image;
using vxl::OffscreenTarget;

namespace {

std::array<std::uint8_t, 4> px(const std::vector<std::uint8_t>& rgba, int width, int x, int y) {
  const std::size_t i = (static_cast<std::size_t>(y) * width + x) * 4;
  return {rgba[i], rgba[i + 1], rgba[i + 2], rgba[i + 3]};
}

using Rgba = std::array<std::uint8_t, 4>;
constexpr Rgba kBlack{0, 0, 0, 255};
constexpr Rgba kRed{255, 0, 0, 255};

GLuint compile(GLenum type, const char* src) {
  GLuint s = glCreateShader(type);
  glShaderSource(s, 1, &src, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[2048] = {};
    glGetShaderInfoLog(s, sizeof log, nullptr, log);
    glDeleteShader(s);
    throw std::runtime_error(std::string("shader compile failed: ") + log);
  }
  return s;
}

// Minimal GLSL 330 core pipeline: one triangle, flat colour.
class TriangleDrawer {
 public:
  TriangleDrawer() {
    const char* vs =
        "#version 330 core\n"
        "layout(location = 0) in vec2 pos;\n"
        "void main() { gl_Position = vec4(pos, 0.0, 1.0); }\n";
    const char* fs =
        "#version 330 core\n"
        "uniform vec4 color;\n"
        "out vec4 frag;\n"
        "void main() { frag = color; }\n";
    GLuint v = compile(GL_VERTEX_SHADER, vs);
    GLuint f = compile(GL_FRAGMENT_SHADER, fs);
    prog_ = glCreateProgram();
    glAttachShader(prog_, v);
    glAttachShader(prog_, f);
    glLinkProgram(prog_);
    glDeleteShader(v);
    glDeleteShader(f);
    GLint ok = 0;
    glGetProgramiv(prog_, GL_LINK_STATUS, &ok);
    if (!ok) throw std::runtime_error("program link failed");
    color_loc_ = glGetUniformLocation(prog_, "color");
    // Triangle in the upper half of the viewport (NDC y from 0.1 to 0.9).
    const float verts[] = {-0.5f, 0.1f, 0.5f, 0.1f, 0.0f, 0.9f};
    glGenVertexArrays(1, &vao_);
    glBindVertexArray(vao_);
    glGenBuffers(1, &vbo_);
    glBindBuffer(GL_ARRAY_BUFFER, vbo_);
    glBufferData(GL_ARRAY_BUFFER, sizeof verts, verts, GL_STATIC_DRAW);
    glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, 0, nullptr);
    glEnableVertexAttribArray(0);
    glBindVertexArray(0);
  }
  ~TriangleDrawer() {
    glDeleteBuffers(1, &vbo_);
    glDeleteVertexArrays(1, &vao_);
    glDeleteProgram(prog_);
  }
  TriangleDrawer(const TriangleDrawer&) = delete;
  TriangleDrawer& operator=(const TriangleDrawer&) = delete;

  void draw(float r, float g, float b, float a) const {
    glUseProgram(prog_);
    glUniform4f(color_loc_, r, g, b, a);
    glBindVertexArray(vao_);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glBindVertexArray(0);
    glUseProgram(0);
  }

 private:
  GLuint prog_ = 0, vao_ = 0, vbo_ = 0;
  GLint color_loc_ = -1;
};

// Renders the red triangle on black into a 64x64 target and returns the pixels (top-down).
std::vector<std::uint8_t> render_triangle(OffscreenTarget& target) {
  TriangleDrawer tri;
  target.bind();
  glDisable(GL_DEPTH_TEST);
  glClearColor(0, 0, 0, 1);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  tri.draw(1, 0, 0, 1);
  glFinish();
  return target.read_rgba();
}

// Inside/outside checks for render_triangle on 64x64: the triangle covers rows ~3..28 from the
// top, columns ~16..48 at its base. The vertically mirrored spot stays black (checks the flip).
void expect_triangle_pixels(const std::vector<std::uint8_t>& p) {
  ASSERT_EQ(p.size(), 64u * 64u * 4u);
  EXPECT_EQ(px(p, 64, 32, 20), kRed) << "inside (upper half)";
  EXPECT_EQ(px(p, 64, 32, 26), kRed) << "inside near the base";
  EXPECT_EQ(px(p, 64, 32, 64 - 1 - 20), kBlack) << "mirror of an inside pixel: rows not flipped?";
  EXPECT_EQ(px(p, 64, 2, 2), kBlack) << "top-left corner";
  EXPECT_EQ(px(p, 64, 61, 61), kBlack) << "bottom-right corner";
  EXPECT_EQ(px(p, 64, 10, 20), kBlack) << "left of the triangle";
}

std::string gl_string(GLenum e) {
  const auto* s = reinterpret_cast<const char*>(glGetString(e));
  return s ? s : "";
}

class TempDir {
 public:
  TempDir() {
    const fs::path base = fs::temp_directory_path();
    for (int i = 0;; ++i) {
      path_ = base / ("vxl_platform_test_" + std::to_string(::getpid()) + "_" + std::to_string(i));
      if (fs::create_directory(path_)) break;
    }
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }
  std::vector<std::string> entries() const {
    std::vector<std::string> out;
    for (const auto& e : fs::directory_iterator(path_)) out.push_back(e.path().filename().string());
    return out;
  }

 private:
  fs::path path_;
};

Image test_pattern(int w, int h) {
  Image img{w, h, std::vector<std::uint8_t>(static_cast<std::size_t>(w) * h * 4)};
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      std::uint8_t* p = img.pixel(x, y);
      p[0] = static_cast<std::uint8_t>((x * 255) / (w - 1));
      p[1] = static_cast<std::uint8_t>(100 + (y * 7) % 100);  // <= 199
      p[2] = static_cast<std::uint8_t>((x * 31 + y * 17) % 256);
      p[3] = static_cast<std::uint8_t>((x + y) % 4 == 0 ? 0 : (x + y) % 4 == 1 ? 128 : (x + y) % 4 == 2 ? 37 : 255);
    }
  return img;
}

// A 3-channel 8-bit PNG written by hand (signature, IHDR, one IDAT of zlib's deflate, IEND; zlib's CRC-32): what
// the project writes is always RGBA, and the test program links no image library (OpenImageIO's libraries would
// cost each of its tests half a second to start).
void write_rgb_png_by_hand(const std::string& path, std::uint32_t w, std::uint32_t h,
                           const std::vector<std::uint8_t>& rgb) {
  std::vector<std::uint8_t> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  auto be32 = [](std::vector<std::uint8_t>& out, std::uint32_t v) {
    for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<std::uint8_t>(v >> shift));
  };
  auto chunk = [&](const char* type, const std::vector<std::uint8_t>& data) {
    be32(png, static_cast<std::uint32_t>(data.size()));
    const std::size_t start = png.size();
    png.insert(png.end(), type, type + 4);
    png.insert(png.end(), data.begin(), data.end());
    be32(png, static_cast<std::uint32_t>(crc32(0, png.data() + start, static_cast<uInt>(png.size() - start))));
  };
  std::vector<std::uint8_t> header;
  be32(header, w);
  be32(header, h);
  header.insert(header.end(), {8, 2, 0, 0, 0});  // 8 bits, RGB, deflate, filter method 0, not interlaced
  chunk("IHDR", header);
  std::vector<std::uint8_t> rows;
  for (std::uint32_t y = 0; y < h; ++y) {
    rows.push_back(0);  // filter: none
    rows.insert(rows.end(), rgb.begin() + std::ptrdiff_t(y * w * 3), rgb.begin() + std::ptrdiff_t((y + 1) * w * 3));
  }
  uLongf size = compressBound(static_cast<uLong>(rows.size()));
  std::vector<std::uint8_t> deflated(size);
  ASSERT_EQ(compress(deflated.data(), &size, rows.data(), static_cast<uLong>(rows.size())), Z_OK);
  deflated.resize(size);
  chunk("IDAT", deflated);
  chunk("IEND", {});
  std::FILE* f = std::fopen(path.c_str(), "wb");
  ASSERT_NE(f, nullptr);
  ASSERT_EQ(std::fwrite(png.data(), 1, png.size(), f), png.size());
  ASSERT_EQ(std::fclose(f), 0);
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// HeadlessGlContext

TEST(PlatformContext, CreatesCoreContextWithoutDisplay) {
  HeadlessGlContext ctx;
  std::printf(
      "[ platform ] OpenGL %d.%d core via EGL %s (%s) | GL_VERSION \"%s\" | GL_RENDERER \"%s\" | "
      "GL_VENDOR \"%s\" | GLSL %s | compute %s\n",
      ctx.major(), ctx.minor(), ctx.platform_name().c_str(), ctx.egl_vendor().c_str(), ctx.version_string().c_str(),
      ctx.renderer().c_str(), ctx.vendor().c_str(), gl_string(GL_SHADING_LANGUAGE_VERSION).c_str(),
      ctx.has_compute() ? "yes" : "no");
  EXPECT_TRUE(ctx.is_current());
  EXPECT_TRUE(ctx.core_profile());
  EXPECT_GE(ctx.version(), (GlVersion{3, 3}));
  EXPECT_FALSE(ctx.renderer().empty());
  EXPECT_EQ(ctx.has_compute(), ctx.version() >= (GlVersion{4, 3}));
  GLint profile = 0;
  glGetIntegerv(GL_CONTEXT_PROFILE_MASK, &profile);
  EXPECT_TRUE(profile & GL_CONTEXT_CORE_PROFILE_BIT);
  EXPECT_EQ(glGetError(), static_cast<GLenum>(GL_NO_ERROR));
  ctx.release_current();
  EXPECT_FALSE(ctx.is_current());
  ctx.make_current();
  EXPECT_TRUE(ctx.is_current());
}

TEST(PlatformContext, DevicePlatformAlsoWorks) {
  // The fallback path used when EGL_PLATFORM_SURFACELESS_MESA is missing.
  std::unique_ptr<HeadlessGlContext> ctx;
  try {
    HeadlessGlContext::Options o;
    o.platform = HeadlessGlContext::Platform::Device;
    ctx = std::make_unique<HeadlessGlContext>(o);
  } catch (const std::runtime_error& e) {
    if (std::string(e.what()).find("not offered") != std::string::npos ||
        std::string(e.what()).find("no device") != std::string::npos)
      GTEST_SKIP() << e.what();
    throw;
  }
  std::printf("[ platform ] device platform: OpenGL %d.%d, %s\n", ctx->major(), ctx->minor(), ctx->renderer().c_str());
  EXPECT_EQ(ctx->platform_name(), "device");
  EXPECT_GE(ctx->version(), (GlVersion{3, 3}));
  OffscreenTarget t(64, 64);
  expect_triangle_pixels(render_triangle(t));
}

TEST(PlatformContext, TwoContextsCoexistAndTerminateCleanly) {
  HeadlessGlContext a;
  {
    HeadlessGlContext b;
    EXPECT_TRUE(b.is_current());
    EXPECT_FALSE(a.is_current());
    OffscreenTarget tb(8, 8);
    tb.bind();
    glClearColor(0, 1, 0, 1);
    glClear(GL_COLOR_BUFFER_BIT);
    EXPECT_EQ(px(tb.read_rgba(), 8, 3, 3), (Rgba{0, 255, 0, 255}));
  }  // b goes while a lives: the shared EGL display must stay initialised
  EXPECT_FALSE(a.is_current());
  a.make_current();
  OffscreenTarget ta(8, 8);
  ta.bind();
  glClearColor(0, 0, 1, 1);
  glClear(GL_COLOR_BUFFER_BIT);
  EXPECT_EQ(px(ta.read_rgba(), 8, 5, 5), (Rgba{0, 0, 255, 255}));
  EXPECT_EQ(glGetError(), static_cast<GLenum>(GL_NO_ERROR));
}

TEST(PlatformContext, MaxVersionIsHonouredOrReported) {
  if (std::getenv("MESA_GL_VERSION_OVERRIDE") != nullptr) GTEST_SKIP() << "MESA_GL_VERSION_OVERRIDE is set";
  HeadlessGlContext::Options o;
  o.max_version = GlVersion{3, 3};
  o.enforce_max_version = false;
  {
    HeadlessGlContext ctx(o);
    EXPECT_EQ(ctx.requested_version(), (GlVersion{3, 3}));
    EXPECT_GE(ctx.version(), (GlVersion{3, 3}));
    EXPECT_FALSE(ctx.has_compute()) << "max_version 3.3 must hide compute even on a newer context";
    std::printf("[ platform ] asked for 3.3 core, driver gave %s\n", ctx.version_string().c_str());
    if (ctx.version() == (GlVersion{3, 3})) return;  // a driver that honours the request exactly
  }
  // The driver upgrades (Mesa, NVIDIA): with enforcement on, the constructor must say so clearly.
  o.enforce_max_version = true;
  try {
    HeadlessGlContext ctx(o);
    FAIL() << "expected a max_version error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("MESA_GL_VERSION_OVERRIDE"), std::string::npos) << e.what();
  }
  o.max_version = GlVersion{3, 2};
  EXPECT_THROW(HeadlessGlContext{o}, std::runtime_error);
}

// Runs PlatformGl33Child.* in a fresh process (Mesa reads its version override once per process)
// with no DISPLAY / WAYLAND_DISPLAY at all.
TEST(PlatformContext, ProductPathOnPureGl33CoreContext) {
  char exe[4096] = {};
  const ssize_t n = ::readlink("/proc/self/exe", exe, sizeof exe - 1);
  ASSERT_GT(n, 0);
  const std::string cmd = "env -u DISPLAY -u WAYLAND_DISPLAY VXL_PLATFORM_GL33_CHILD=1 '" + std::string(exe) +
                          "' --gtest_filter='PlatformGl33Child.*' --gtest_color=no 2>&1";
  FILE* pipe = ::popen(cmd.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::string output;
  char buf[4096];
  while (std::fgets(buf, sizeof buf, pipe) != nullptr) output += buf;
  const int status = ::pclose(pipe);
  ASSERT_TRUE(WIFEXITED(status)) << output;
  ASSERT_EQ(WEXITSTATUS(status), 0) << output;
  if (output.find("[  SKIPPED ]") != std::string::npos) GTEST_SKIP() << output;
  EXPECT_NE(output.find("[  PASSED  ] 1 test"), std::string::npos) << output;
  const auto line = output.find("[ platform ]");
  if (line != std::string::npos) std::printf("%s", output.substr(line, output.find('\n', line) - line + 1).c_str());
}

TEST(PlatformGl33Child, RendersOnCore33) {
  if (std::getenv("VXL_PLATFORM_GL33_CHILD") == nullptr)
    GTEST_SKIP() << "runs only as the child process of PlatformContext.ProductPathOnPureGl33CoreContext";
  ASSERT_EQ(std::getenv("DISPLAY"), nullptr);
  EXPECT_TRUE(HeadlessGlContext::limit_mesa_gl_version({3, 3}));
  HeadlessGlContext::Options o;
  o.max_version = GlVersion{3, 3};
  std::unique_ptr<HeadlessGlContext> ctx;
  try {
    ctx = std::make_unique<HeadlessGlContext>(o);
  } catch (const std::runtime_error& e) {
    // Drivers other than Mesa cannot be capped below their native version.
    if (std::string(e.what()).find("driver returned") != std::string::npos) GTEST_SKIP() << e.what();
    throw;
  }
  std::printf("[ platform ] pure 3.3: GL_VERSION \"%s\", GLSL %s, %s\n", ctx->version_string().c_str(),
              gl_string(GL_SHADING_LANGUAGE_VERSION).c_str(), ctx->renderer().c_str());
  EXPECT_EQ(ctx->version(), (GlVersion{3, 3}));
  EXPECT_FALSE(ctx->has_compute());
  EXPECT_EQ(gl_string(GL_SHADING_LANGUAGE_VERSION).rfind("3.30", 0), 0u);
  {
    OffscreenTarget t(64, 64);
    expect_triangle_pixels(render_triangle(t));
    OffscreenTarget ms(64, 64, 4);
    expect_triangle_pixels(render_triangle(ms));
  }
  EXPECT_EQ(glGetError(), static_cast<GLenum>(GL_NO_ERROR));
}

// ---------------------------------------------------------------------------------------------
// OffscreenTarget

class PlatformTarget : public ::testing::Test {
 protected:
  HeadlessGlContext ctx_;
};

TEST_F(PlatformTarget, ClearAndReadBack) {
  OffscreenTarget t(37, 23);  // odd sizes
  EXPECT_EQ(t.width(), 37);
  EXPECT_EQ(t.height(), 23);
  EXPECT_NE(t.framebuffer(), 0u);
  EXPECT_NE(t.color_texture(), 0u);
  t.bind();
  glClearColor(0.2f, 0.4f, 0.6f, 1.0f);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT | GL_STENCIL_BUFFER_BIT);
  // Paint the top 5 rows (GL's scissor origin is bottom-left) another colour.
  glEnable(GL_SCISSOR_TEST);
  glScissor(0, 23 - 5, 37, 5);
  glClearColor(1.0f, 1.0f, 0.0f, 0.5f);
  glClear(GL_COLOR_BUFFER_BIT);
  glDisable(GL_SCISSOR_TEST);
  const auto p = t.read_rgba();
  ASSERT_EQ(p.size(), 37u * 23u * 4u);
  for (int y = 0; y < 23; ++y)
    for (int x = 0; x < 37; ++x) {
      const Rgba want = y < 5 ? Rgba{255, 255, 0, 128} : Rgba{51, 102, 153, 255};
      ASSERT_EQ(px(p, 37, x, y), want) << "x " << x << " y " << y;
    }
  EXPECT_EQ(glGetError(), static_cast<GLenum>(GL_NO_ERROR));
}

TEST_F(PlatformTarget, TriangleInsideAndOutside) {
  OffscreenTarget t(64, 64);
  expect_triangle_pixels(render_triangle(t));
  // Depth buffer works: a farther triangle does not overwrite a nearer clear-depth test.
  GLint depth_bits = 0, stencil_bits = 0;
  t.bind();
  glGetFramebufferAttachmentParameteriv(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_FRAMEBUFFER_ATTACHMENT_DEPTH_SIZE,
                                        &depth_bits);
  glGetFramebufferAttachmentParameteriv(GL_FRAMEBUFFER, GL_STENCIL_ATTACHMENT, GL_FRAMEBUFFER_ATTACHMENT_STENCIL_SIZE,
                                        &stencil_bits);
  EXPECT_GE(depth_bits, 24);
  EXPECT_GE(stencil_bits, 8);
  TriangleDrawer tri;
  glEnable(GL_DEPTH_TEST);
  glClearDepth(0.25);  // triangle at z = 0 -> depth 0.5: fails GL_LESS everywhere
  glClear(GL_DEPTH_BUFFER_BIT);
  tri.draw(0, 1, 0, 1);
  glDisable(GL_DEPTH_TEST);
  glClearDepth(1.0);
  EXPECT_EQ(px(t.read_rgba(), 64, 32, 20), kRed);
  EXPECT_EQ(glGetError(), static_cast<GLenum>(GL_NO_ERROR));
}

TEST_F(PlatformTarget, ResizeReallocates) {
  OffscreenTarget t(16, 16);
  t.resize(50, 40);
  EXPECT_EQ(t.width(), 50);
  EXPECT_EQ(t.height(), 40);
  t.bind();
  GLint vp[4] = {};
  glGetIntegerv(GL_VIEWPORT, vp);
  EXPECT_EQ(vp[2], 50);
  EXPECT_EQ(vp[3], 40);
  glClearColor(1, 0, 1, 1);
  glClear(GL_COLOR_BUFFER_BIT);
  const auto p = t.read_rgba();
  ASSERT_EQ(p.size(), 50u * 40u * 4u);
  EXPECT_EQ(px(p, 50, 49, 39), (Rgba{255, 0, 255, 255}));
  EXPECT_EQ(px(p, 50, 0, 0), (Rgba{255, 0, 255, 255}));
  EXPECT_THROW(t.resize(0, 10), std::invalid_argument);
  EXPECT_THROW(OffscreenTarget(-1, 4), std::invalid_argument);
  EXPECT_EQ(glGetError(), static_cast<GLenum>(GL_NO_ERROR));
}

TEST_F(PlatformTarget, MultisampledResolves) {
  GLint max_samples = 0;
  glGetIntegerv(GL_MAX_SAMPLES, &max_samples);
  if (max_samples < 4) GTEST_SKIP() << "GL_MAX_SAMPLES " << max_samples;
  OffscreenTarget t(64, 64, 4);
  EXPECT_EQ(t.samples(), 4);
  const auto p = render_triangle(t);
  expect_triangle_pixels(p);
  int partial = 0;  // antialiased edge pixels
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      const auto r = px(p, 64, x, y)[0];
      partial += r > 0 && r < 255;
    }
  EXPECT_GT(partial, 10);
  EXPECT_THROW(OffscreenTarget(8, 8, max_samples + 1), std::runtime_error);
  EXPECT_EQ(glGetError(), static_cast<GLenum>(GL_NO_ERROR));
}

TEST_F(PlatformTarget, ReadRestoresState) {
  OffscreenTarget a(8, 8), b(8, 8);
  b.bind();
  glPixelStorei(GL_PACK_ALIGNMENT, 8);
  (void)a.read_rgba();
  GLint draw = 0, read = 0, align = 0;
  glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &draw);
  glGetIntegerv(GL_READ_FRAMEBUFFER_BINDING, &read);
  glGetIntegerv(GL_PACK_ALIGNMENT, &align);
  EXPECT_EQ(static_cast<GLuint>(draw), b.framebuffer());
  EXPECT_EQ(static_cast<GLuint>(read), b.framebuffer());
  EXPECT_EQ(align, 8);
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  OffscreenTarget moved(std::move(a));
  EXPECT_EQ(a.framebuffer(), 0u);  // NOLINT(bugprone-use-after-move): moved-from is empty
  EXPECT_NE(moved.framebuffer(), 0u);
  EXPECT_EQ(glGetError(), static_cast<GLenum>(GL_NO_ERROR));
}

// ---------------------------------------------------------------------------------------------
// image_io

TEST(PlatformImageIo, PngRoundTripIsExactWithStraightAlpha) {
  TempDir dir;
  const Image img = test_pattern(33, 17);
  const std::string path = (dir.path() / "pattern.png").string();
  vxl::write_png(path, img);
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"pattern.png"}) << "temporary file left behind";
  const Image back = vxl::read_image(path);
  ASSERT_EQ(back.width, 33);
  ASSERT_EQ(back.height, 17);
  EXPECT_TRUE(back.rgba == img.rgba) << "bytes changed (alpha premultiplied?)";
  const vxl::ImageDiff d = vxl::compare_images(img, back);
  EXPECT_EQ(d.rms_error, 0.0);
  EXPECT_EQ(d.mean_error, 0.0);
  EXPECT_EQ(d.max_error, 0.0);
  EXPECT_EQ(d.differing_pixels, 0u);
  EXPECT_TRUE(std::isinf(d.psnr));
}

TEST(PlatformImageIo, ModifiedCopyGivesExpectedErrors) {
  TempDir dir;
  const Image img = test_pattern(16, 16);  // 256 pixels, 1024 channel values
  const std::string path = (dir.path() / "a.png").string();
  vxl::write_png(path, img);
  const Image back = vxl::read_image(path);

  // One channel of one pixel off by the full range.
  Image one = back;
  ASSERT_EQ(one.pixel(0, 5)[0], 0);  // red ramps from 0 at x = 0
  one.pixel(0, 5)[0] = 255;
  vxl::ImageDiff d = vxl::compare_images(img, one);
  EXPECT_NEAR(d.rms_error, std::sqrt(1.0 / 1024.0), 1e-6);  // 1/32
  EXPECT_NEAR(d.mean_error, 1.0 / 1024.0, 1e-7);
  EXPECT_NEAR(d.max_error, 1.0, 1e-6);
  EXPECT_NEAR(d.psnr, 20.0 * std::log10(32.0), 1e-3);
  EXPECT_EQ(d.differing_pixels, 1u);
  EXPECT_EQ(d.max_x, 0);
  EXPECT_EQ(d.max_y, 5);
  EXPECT_EQ(d.max_channel, 0);

  // Green + 10 everywhere: a quarter of all channel values off by 10/255.
  Image green = back;
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) green.pixel(x, y)[1] = static_cast<std::uint8_t>(green.pixel(x, y)[1] + 10);
  d = vxl::compare_images(img, green);
  EXPECT_NEAR(d.rms_error, (10.0 / 255.0) * 0.5, 1e-6);
  EXPECT_NEAR(d.mean_error, (10.0 / 255.0) * 0.25, 1e-6);
  EXPECT_NEAR(d.max_error, 10.0 / 255.0, 1e-6);
  EXPECT_EQ(d.differing_pixels, 256u);

  Image smaller = test_pattern(8, 16);
  EXPECT_THROW(vxl::compare_images(img, smaller), std::runtime_error);
}

TEST(PlatformImageIo, WriteFailuresLeaveNothingAndNameThePath) {
  TempDir dir;
  const Image img = test_pattern(4, 4);
  auto expect_fail = [&](const std::string& path, int w, int h, const std::vector<std::uint8_t>& rgba) {
    try {
      vxl::write_png(path, w, h, rgba);
      ADD_FAILURE() << "no exception for " << path;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
  };
  expect_fail((dir.path() / "missing_dir" / "x.png").string(), 4, 4, img.rgba);
  expect_fail(dir.path().string(), 4, 4, img.rgba);                  // a directory
  expect_fail((dir.path() / "short.png").string(), 5, 4, img.rgba);  // buffer too small
  expect_fail((dir.path() / "zero.png").string(), 0, 4, {});
  EXPECT_TRUE(dir.entries().empty()) << dir.entries().front();

  // Overwriting replaces the old file in one step.
  const std::string path = (dir.path() / "same.png").string();
  vxl::write_png(path, img);
  Image other = test_pattern(4, 4);
  other.pixel(0, 0)[2] ^= 0xff;
  vxl::write_png(path, other);
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"same.png"});
  EXPECT_TRUE(vxl::read_image(path).rgba == other.rgba);
  // A failed overwrite keeps the previous file.
  expect_fail(path, 5, 5, img.rgba);
  EXPECT_TRUE(vxl::read_image(path).rgba == other.rgba);
}

// The output rule (format/base/output_path.h): a FIFO or a device is refused as an output error and left as it
// was, a symbolic link is followed and kept, a missing folder is an output error (voxview exit 5).
TEST(PlatformImageIo, WritePngRefusesFifosAndDevicesAndFollowsLinks) {
  TempDir dir;
  const Image img = test_pattern(4, 4);
  const std::string fifo = (dir.path() / "fifo.png").string(), null_link = (dir.path() / "null.png").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  fs::create_symlink("/dev/null", null_link);
  for (const std::string& path : {fifo, null_link, (dir.path() / "missing" / "x.png").string()}) {
    try {
      vxl::write_png(path, img);
      ADD_FAILURE() << "no exception for " << path;
    } catch (const vxl::Error& e) {
      EXPECT_EQ(e.kind(), vxl::ErrorKind::Output) << e.what();
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
  }
  EXPECT_TRUE(fs::is_fifo(fs::symlink_status(fifo)));
  EXPECT_TRUE(fs::is_symlink(fs::symlink_status(null_link)));
  EXPECT_TRUE(fs::is_character_file(fs::symlink_status("/dev/null")));
  EXPECT_EQ(dir.entries().size(), 2u) << "a temporary file left";

  fs::create_directory(dir.path() / "sub");
  const std::string link = (dir.path() / "link.png").string();
  fs::create_symlink("sub/real.png", link);
  vxl::write_png(link, img);
  EXPECT_TRUE(fs::is_symlink(fs::symlink_status(link)));
  EXPECT_TRUE(vxl::read_image((dir.path() / "sub" / "real.png").string()).rgba == img.rgba);
}

TEST(PlatformImageIo, ReadErrorsAndRgbFiles) {
  TempDir dir;
  const std::string missing = (dir.path() / "nope.png").string();
  try {
    (void)vxl::read_image(missing);
    ADD_FAILURE() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos) << e.what();
  }
  const std::string garbage = (dir.path() / "garbage.png").string();
  {
    std::FILE* f = std::fopen(garbage.c_str(), "wb");
    std::fputs("not a png", f);
    std::fclose(f);
  }
  EXPECT_THROW((void)vxl::read_image(garbage), std::runtime_error);

  // A 3-channel file gets alpha 255.
  const std::string rgb = (dir.path() / "rgb.png").string();
  ASSERT_NO_FATAL_FAILURE(write_rgb_png_by_hand(rgb, 2, 1, {10, 20, 30, 40, 50, 60}));
  const Image img = vxl::read_image(rgb);
  ASSERT_EQ(img.width, 2);
  ASSERT_EQ(img.height, 1);
  EXPECT_EQ(img.rgba, (std::vector<std::uint8_t>{10, 20, 30, 255, 40, 50, 60, 255}));
}

// --size 16384x8192 (or a view file's "size") is beyond what the driver holds, though within its per-side
// limit: the driver caps a buffer's bytes below it. Both limits are an Unsupported error (exit 4) that says
// what fits, not exit 70 with "framebuffer incomplete".
TEST_F(PlatformTarget, SizesTheDriverCannotHoldAreUnsupportedAndSayWhatFits) {
  GLint max_tex = 0;
  glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_tex);
  try {
    OffscreenTarget t(max_tex + 1, 16);
    ADD_FAILURE() << "no error";
  } catch (const vxl::Error& e) {
    EXPECT_EQ(e.kind(), vxl::ErrorKind::Unsupported) << e.what();
    EXPECT_NE(std::string(e.what()).find("limit of "), std::string::npos) << e.what();
  }
  // llvmpipe cannot allocate the 2 GiB float colour buffer of 16384x8192. A driver that can passes; one
  // that cannot must say so as an Unsupported error.
  try {
    OffscreenTarget t(std::min(16384, max_tex), std::min(8192, max_tex));
    std::printf("[ platform ] %dx%d allocates on this driver\n", t.width(), t.height());
  } catch (const vxl::Error& e) {
    EXPECT_EQ(e.kind(), vxl::ErrorKind::Unsupported) << e.what();
    EXPECT_NE(std::string(e.what()).find("the largest of this shape it allocates is "), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find("is none"), std::string::npos) << e.what();
  }
  OffscreenTarget small(8, 8);  // the context is still usable
  EXPECT_EQ(small.read_rgba().size(), 8u * 8u * 4u);
}

TEST_F(PlatformTarget, RenderedImageSurvivesPng) {
  TempDir dir;
  OffscreenTarget t(64, 64);
  const auto p = render_triangle(t);
  const std::string path = (dir.path() / "triangle.png").string();
  vxl::write_png(path, 64, 64, p);
  const Image back = vxl::read_image(path);
  EXPECT_EQ(back.rgba, p);
  EXPECT_EQ(vxl::compare_images(back, Image{64, 64, p}).differing_pixels, 0u);
  EXPECT_EQ(back.pixel(32, 20)[0], 255);  // top-down in the file too
  EXPECT_EQ(back.pixel(32, 43)[0], 0);
}
