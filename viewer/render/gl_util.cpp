#include "viewer/render/gl_util.h"

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <utility>
#include <vector>

#if !VOXLINES_WEBGL
#include <sys/mman.h>
#include <unistd.h>
#endif

namespace vxl::gl {
namespace {

#if VOXLINES_WEBGL
const char* const kDialect = R"(#version 300 es
precision highp float;
precision highp int;
precision highp sampler2D;
precision highp usampler2D;
precision highp sampler3D;
#define BUFFER_SAMPLER usampler2D
#define FETCH_BUFFER(s, i) texelFetch(s, ivec2((i) & 4095, (i) >> 12), 0)
#define CLIP_DISTANCES 0
)";
static_assert(kBufferTextureWidthLog2 == 12, "FETCH_BUFFER's row width");
#else
const char* const kDialect = R"(
#define BUFFER_SAMPLER usamplerBuffer
#define FETCH_BUFFER(s, i) texelFetch(s, i)
#define CLIP_DISTANCES 1
)";
#endif

GLuint compile(GLenum type, const std::string& source) {
  GLuint s = glCreateShader(type);
  const std::string text = shader_source(source);
  const char* src = text.c_str();
  glShaderSource(s, 1, &src, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    GLint len = 0;
    glGetShaderiv(s, GL_INFO_LOG_LENGTH, &len);
    std::vector<char> log(static_cast<std::size_t>(len) + 1);
    glGetShaderInfoLog(s, len, nullptr, log.data());
    glDeleteShader(s);
    throw std::runtime_error(std::string("shader compilation failed: ") + log.data());
  }
  return s;
}

GLuint link(std::initializer_list<GLuint> shaders) {
  GLuint p = glCreateProgram();
  for (GLuint s : shaders) glAttachShader(p, s);
  glLinkProgram(p);
  for (GLuint s : shaders) glDeleteShader(s);
  GLint ok = 0;
  glGetProgramiv(p, GL_LINK_STATUS, &ok);
  if (!ok) {
    GLint len = 0;
    glGetProgramiv(p, GL_INFO_LOG_LENGTH, &len);
    std::vector<char> log(static_cast<std::size_t>(len) + 1);
    glGetProgramInfoLog(p, len, nullptr, log.data());
    glDeleteProgram(p);
    throw std::runtime_error(std::string("program link failed: ") + log.data());
  }
  return p;
}

// The (format, type) that glTexSubImage2D takes for a TextureBuffer's internal format, and its texel size.
struct PixelLayout {
  GLenum format, type;
  std::size_t texel_bytes;
};
PixelLayout pixel_layout(GLenum internal_format) {
  switch (internal_format) {
    case GL_RGBA32UI: return {GL_RGBA_INTEGER, GL_UNSIGNED_INT, 16};
    case GL_RG32UI: return {GL_RG_INTEGER, GL_UNSIGNED_INT, 8};
    case GL_R32UI: return {GL_RED_INTEGER, GL_UNSIGNED_INT, 4};
    case GL_R16UI: return {GL_RED_INTEGER, GL_UNSIGNED_SHORT, 2};
    case GL_R8UI: return {GL_RED_INTEGER, GL_UNSIGNED_BYTE, 1};
    case GL_R32F: return {GL_RED, GL_FLOAT, 4};
    default:
      throw std::logic_error("TextureBuffer: no pixel layout for internal format " + std::to_string(internal_format));
  }
}

#if VOXLINES_WEBGL
constexpr std::size_t kUploadBandBytes = 8u << 20;

// Copies `bytes` (whole texels) into the bound rows texture from row `first_row` on: whole rows in bands of at most
// kUploadBandBytes (a browser copies what one call passes into memory shared with its GPU process, and a span's
// texture is up to 512 MiB), then a last row's first texels.
void upload_rows(const PixelLayout& px, std::size_t first_row, const std::uint8_t* data, std::size_t bytes) {
  const std::size_t row_bytes = kBufferTextureWidth * px.texel_bytes;
  const std::size_t rows = bytes / row_bytes, tail = (bytes - rows * row_bytes) / px.texel_bytes;
  const std::size_t band_rows = std::max<std::size_t>(1, kUploadBandBytes / row_bytes);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  for (std::size_t row = 0; row < rows; row += band_rows)
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, static_cast<GLint>(first_row + row), kBufferTextureWidth,
                    static_cast<GLsizei>(std::min(band_rows, rows - row)), px.format, px.type, data + row * row_bytes);
  if (tail > 0)
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, static_cast<GLint>(first_row + rows), static_cast<GLsizei>(tail), 1, px.format,
                    px.type, data + rows * row_bytes);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
}

// WebGL2's stand-in for a buffer texture: a 2D texture of kBufferTextureWidth-texel rows holding `bytes`
// (at least one texel), filled from `data` when given. A last row only partly filled leaves the rest zero.
GLuint make_rows_texture(GLenum internal_format, const void* data, std::size_t bytes) {
  const PixelLayout px = pixel_layout(internal_format);
  const std::size_t texels = std::max<std::size_t>(1, bytes / px.texel_bytes);
  const std::size_t rows = (texels + kBufferTextureWidth - 1) / kBufferTextureWidth;
  GLuint texture = 0;
  glGenTextures(1, &texture);
  glBindTexture(GL_TEXTURE_2D, texture);
  glTexStorage2D(GL_TEXTURE_2D, 1, internal_format, kBufferTextureWidth, static_cast<GLsizei>(rows));
  // Integer textures are complete only when sampled without filtering.
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  if (data != nullptr && bytes >= px.texel_bytes)
    upload_rows(px, 0, static_cast<const std::uint8_t*>(data), bytes / px.texel_bytes * px.texel_bytes);
  glBindTexture(GL_TEXTURE_2D, 0);
  return texture;
}
#endif

}  // namespace

std::string shader_source(const std::string& source) {
  const std::size_t line_end = source.find('\n');
  const std::string first = source.substr(0, line_end);
  if (first.rfind("#version ", 0) != 0 || first.size() < 5 || first.compare(first.size() - 5, 5, " core") != 0)
    return source;
  const std::string rest = line_end == std::string::npos ? std::string() : source.substr(line_end + 1);
  if constexpr (kWebGL)
    return kDialect + rest;
  else
    return first + kDialect + rest;
}

std::uint64_t max_buffer_texels() {
  GLint limit = 0;
#if VOXLINES_WEBGL
  glGetIntegerv(GL_MAX_TEXTURE_SIZE, &limit);
  return std::uint64_t(std::max(limit, 1)) * kBufferTextureWidth;
#else
  glGetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, &limit);
  return std::uint64_t(std::max(limit, 1));
#endif
}

void multi_draw(GLenum mode, const GLint* first, const GLsizei* count, GLsizei ranges) {
#if VOXLINES_WEBGL
  for (GLsizei i = 0; i < ranges; ++i) glDrawArrays(mode, first[i], count[i]);
#else
  glMultiDrawArrays(mode, first, count, ranges);
#endif
}

GLuint make_program(const std::string& vs, const std::string& fs) {
  return link({compile(GL_VERTEX_SHADER, vs), compile(GL_FRAGMENT_SHADER, fs)});
}

GLuint make_compute_program(const std::string& cs) {
#if VOXLINES_WEBGL
  (void)cs;
  throw std::runtime_error("compute shaders need OpenGL 4.3, which WebGL2 is not");
#else
  return link({compile(GL_COMPUTE_SHADER, cs)});
#endif
}

namespace {

BufferMemory buffer_memory = BufferMemory::Auto;

}  // namespace

void set_buffer_memory(BufferMemory memory) { buffer_memory = memory; }

bool host_memory_buffers() {
#if VOXLINES_WEBGL
  return false;  // every buffer is a texture the browser copies
#else
  // llvmpipe's glBufferData clears a new buffer on the GL thread before the fill writes it (the 1M set uploads in
  // about half the time without it); memory of our own is written once, by the threads that fill it. On a GPU the
  // driver's buffers are the GPU's, and pinned memory would be read across the bus every frame. Asked of the current
  // context each time (microseconds, once a buffer): a process may make contexts of other drivers.
  if (buffer_memory != BufferMemory::Auto) return false;
  const char* name = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  const std::string renderer = name ? name : "";
  return renderer.find("llvmpipe") != std::string::npos && epoxy_has_gl_extension("GL_AMD_pinned_memory");
#endif
}

#if VOXLINES_WEBGL

void TextureBuffer::create(GLenum internal_format, const void* data, std::size_t bytes) {
  texture = make_rows_texture(internal_format, data, bytes);
}

void* TextureBuffer::create_mapped(std::size_t bytes) {
  mapped_bytes_ = std::max<std::size_t>(bytes, 16);
  staging_ = std::make_unique<std::uint8_t[]>(mapped_bytes_);
  return staging_.get();
}

void TextureBuffer::finish_mapped(GLenum internal_format) {
  if (!staging_) return;  // finished already
  texture = make_rows_texture(internal_format, staging_.get(), mapped_bytes_);
  staging_.reset();
}

void TextureBuffer::begin_parts(GLenum internal_format, std::size_t bytes) {
  texture = make_rows_texture(internal_format, nullptr, bytes);
  parts_format_ = internal_format;
  parts_bytes_ = bytes;
  next_part_ = 0;
}

bool TextureBuffer::fill_part(const PartFill& fill) {
  if (!texture || next_part_ >= parts_bytes_) return false;
  const PixelLayout px = pixel_layout(parts_format_);
  const std::size_t row_bytes = kBufferTextureWidth * px.texel_bytes;
  const std::size_t part_bytes = std::max<std::size_t>(1, kUploadBandBytes / row_bytes) * row_bytes;
  const std::size_t first = next_part_;
  try {
    part_.assign(std::min(part_bytes, parts_bytes_ - first), 0);
    fill(first, part_);
  } catch (...) {
    destroy();
    throw;
  }
  glBindTexture(GL_TEXTURE_2D, texture);
  upload_rows(px, first / row_bytes, part_.data(), part_.size());
  glBindTexture(GL_TEXTURE_2D, 0);
  next_part_ = first + part_.size();
  if (next_part_ < parts_bytes_) return true;
  std::vector<std::uint8_t>().swap(part_);
  return false;
}

void TextureBuffer::update(std::size_t, const void*, std::size_t) {
  throw std::runtime_error("updating a buffer texture in place needs desktop OpenGL");
}

void TextureBuffer::destroy() {
  if (texture) glDeleteTextures(1, &texture);
  texture = buffer = 0;
  staging_.reset();
  std::vector<std::uint8_t>().swap(part_);
  parts_bytes_ = next_part_ = 0;
}

#else

namespace {

// A buffer texture reads zeros past the driver's limit (GL_MAX_TEXTURE_BUFFER_SIZE texels): a larger one is
// refused, naming the sizes, so that nothing draws from it wrongly.
void check_within_limit(GLenum internal_format, std::size_t bytes) {
  const std::uint64_t texels = bytes / pixel_layout(internal_format).texel_bytes, limit = max_buffer_texels();
  if (texels > limit)
    throw std::runtime_error("a GPU buffer of " + std::to_string(texels) +
                             " texels is more than this driver's limit of " + std::to_string(limit) +
                             " (GL_MAX_TEXTURE_BUFFER_SIZE); for a span's buffers, a smaller --span-texels "
                             "keeps them within it");
}

}  // namespace

void TextureBuffer::create(GLenum internal_format, const void* data, std::size_t bytes) {
  check_within_limit(internal_format, bytes);
  glGenBuffers(1, &buffer);
  glBindBuffer(GL_TEXTURE_BUFFER, buffer);
  // A zero-sized buffer texture is not portable: keep at least one texel.
  glBufferData(GL_TEXTURE_BUFFER, static_cast<GLsizeiptr>(bytes > 0 ? bytes : 16), bytes > 0 ? data : nullptr,
               GL_STATIC_DRAW);
  glGenTextures(1, &texture);
  glBindTexture(GL_TEXTURE_BUFFER, texture);
  glTexBuffer(GL_TEXTURE_BUFFER, internal_format, buffer);
  glBindTexture(GL_TEXTURE_BUFFER, 0);
  glBindBuffer(GL_TEXTURE_BUFFER, 0);
}

void* TextureBuffer::create_mapped(std::size_t bytes) {
  const std::size_t size = std::max<std::size_t>(bytes, 16);
  if (host_memory_buffers()) {
    const auto page = static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
    const std::size_t whole_pages = (size + page - 1) / page * page;
    void* memory = mmap(nullptr, whole_pages, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (memory == MAP_FAILED)
      throw std::runtime_error("could not allocate a buffer of " + std::to_string(size) + " bytes");
    host_memory_ = memory;
    host_bytes_ = whole_pages;
    mapped_bytes_ = size;
    return memory;
  }
  mapped_bytes_ = size;
  glGenBuffers(1, &buffer);
  glBindBuffer(GL_TEXTURE_BUFFER, buffer);
  glBufferData(GL_TEXTURE_BUFFER, static_cast<GLsizeiptr>(size), nullptr, GL_STATIC_DRAW);
  // Invalidated: the driver need not keep (or copy) what the buffer held.
  void* memory = glMapBufferRange(GL_TEXTURE_BUFFER, 0, static_cast<GLsizeiptr>(size),
                                  GL_MAP_WRITE_BIT | GL_MAP_INVALIDATE_BUFFER_BIT);
  glBindBuffer(GL_TEXTURE_BUFFER, 0);
  if (memory == nullptr) {
    destroy();
    throw std::runtime_error("the driver could not map a buffer of " + std::to_string(size) + " bytes for writing");
  }
  return memory;
}

void TextureBuffer::finish_mapped(GLenum internal_format) {
  if (host_memory_ && buffer) return;  // finished already
  try {
    check_within_limit(internal_format, mapped_bytes_);
  } catch (...) {
    if (!host_memory_) {  // the driver's buffer, still mapped
      glBindBuffer(GL_TEXTURE_BUFFER, buffer);
      glUnmapBuffer(GL_TEXTURE_BUFFER);
      glBindBuffer(GL_TEXTURE_BUFFER, 0);
    }
    destroy();
    throw;
  }
  if (host_memory_) {
    glGenBuffers(1, &buffer);
    glBindBuffer(GL_EXTERNAL_VIRTUAL_MEMORY_BUFFER_AMD, buffer);
    glBufferData(GL_EXTERNAL_VIRTUAL_MEMORY_BUFFER_AMD, static_cast<GLsizeiptr>(mapped_bytes_), host_memory_,
                 GL_STATIC_DRAW);
    glBindBuffer(GL_EXTERNAL_VIRTUAL_MEMORY_BUFFER_AMD, 0);
    glBindBuffer(GL_TEXTURE_BUFFER, buffer);
    GLint64 taken = 0;
    glGetBufferParameteri64v(GL_TEXTURE_BUFFER, GL_BUFFER_SIZE, &taken);
    if (taken != static_cast<GLint64>(mapped_bytes_)) {  // the driver refused the memory: it gets a copy instead
      glGetError();                                      // the refusal's GL_INVALID_OPERATION, answered here
      glBufferData(GL_TEXTURE_BUFFER, static_cast<GLsizeiptr>(mapped_bytes_), host_memory_, GL_STATIC_DRAW);
      munmap(host_memory_, host_bytes_);
      host_memory_ = nullptr;
    }
  } else {
    glBindBuffer(GL_TEXTURE_BUFFER, buffer);
    const GLboolean kept = glUnmapBuffer(GL_TEXTURE_BUFFER);
    if (kept == GL_FALSE) {
      glBindBuffer(GL_TEXTURE_BUFFER, 0);
      destroy();
      throw std::runtime_error("the driver lost a buffer's contents while it was being filled");
    }
  }
  glGenTextures(1, &texture);
  glBindTexture(GL_TEXTURE_BUFFER, texture);
  glTexBuffer(GL_TEXTURE_BUFFER, internal_format, buffer);
  glBindTexture(GL_TEXTURE_BUFFER, 0);
  glBindBuffer(GL_TEXTURE_BUFFER, 0);
}

void TextureBuffer::begin_parts(GLenum internal_format, std::size_t bytes) {
  parts_memory_ = static_cast<std::uint8_t*>(create_mapped(bytes));
  parts_format_ = internal_format;
  parts_bytes_ = bytes;
  next_part_ = 0;
}

bool TextureBuffer::fill_part(const PartFill& fill) {
  if (!parts_memory_) return false;
  std::uint8_t* memory = std::exchange(parts_memory_, nullptr);
  try {
    std::memset(memory, 0, parts_bytes_);
    fill(0, {memory, parts_bytes_});
  } catch (...) {
    try {
      finish_mapped(parts_format_);
    } catch (const std::exception&) {  // the contents are dropped anyway
    }
    destroy();
    throw;
  }
  finish_mapped(parts_format_);
  return false;
}

void TextureBuffer::update(std::size_t offset, const void* data, std::size_t bytes) {
  glBindBuffer(GL_TEXTURE_BUFFER, buffer);
  glBufferSubData(GL_TEXTURE_BUFFER, static_cast<GLintptr>(offset), static_cast<GLsizeiptr>(bytes), data);
  glBindBuffer(GL_TEXTURE_BUFFER, 0);
}

void TextureBuffer::destroy() {
  parts_memory_ = nullptr;  // unmapped with the buffer
  if (texture) glDeleteTextures(1, &texture);
  if (buffer) glDeleteBuffers(1, &buffer);
  if (host_memory_) {
    if (buffer) glFinish();  // draws still queued may read the memory
    munmap(host_memory_, host_bytes_);
    host_memory_ = nullptr;
  }
  texture = buffer = 0;
}

#endif

void finish_gpu_work() {
  if constexpr (kWebGL) {
    std::uint8_t pixel[4];
    glReadPixels(0, 0, 1, 1, GL_RGBA, GL_UNSIGNED_BYTE, pixel);
  } else {
    glFinish();
  }
}

void RenderTarget::ensure(int w, int h, GLenum f0, GLenum f1, bool with_depth) {
  if (fbo && w == width && h == height) return;
  destroy();
  width = w;
  height = h;
  glGenFramebuffers(1, &fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  GLenum formats[2] = {f0, f1};
  GLenum buffers[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
  int n = f1 ? 2 : 1;
  for (int i = 0; i < n; ++i) {
    glGenTextures(1, &color[i]);
    glBindTexture(GL_TEXTURE_2D, color[i]);
    // OpenGL ES (WebGL2) takes only the type that matches the format.
    const GLenum type = formats[i] == GL_RGBA8 ? GL_UNSIGNED_BYTE : GL_FLOAT;
    glTexImage2D(GL_TEXTURE_2D, 0, static_cast<GLint>(formats[i]), w, h, 0, GL_RGBA, type, nullptr);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glFramebufferTexture2D(GL_FRAMEBUFFER, buffers[i], GL_TEXTURE_2D, color[i], 0);
  }
  glDrawBuffers(n, buffers);
  if (with_depth) {
    glGenRenderbuffers(1, &depth);
    glBindRenderbuffer(GL_RENDERBUFFER, depth);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, w, h);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth);
  }
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw std::runtime_error("incomplete framebuffer for a multipass transparency mode or a picture in pieces");
}

void RenderTarget::destroy() {
  if (fbo) glDeleteFramebuffers(1, &fbo);
  for (GLuint& c : color)
    if (c) glDeleteTextures(1, &c), c = 0;
  if (depth) glDeleteRenderbuffers(1, &depth);
  fbo = depth = 0;
  width = height = 0;
}

std::string version_string() {
  const char* v = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  const char* r = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  return std::string(v ? v : "?") + " / " + (r ? r : "?");
}

}  // namespace vxl::gl
