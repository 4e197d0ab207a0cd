// Small OpenGL helpers: shader programs, a fullscreen pass, texture-buffer objects. Need a current context.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "viewer/render/gl_api.h"

namespace vxl::gl {

// Compiles and links; throws std::runtime_error with the driver's log on failure.
// Sources start with a desktop version line ("#version 330 core"); shader_source() puts the dialect's
// prelude after it, which every shader may use: BUFFER_SAMPLER, the sampler type of a TextureBuffer (an
// unsigned one), FETCH_BUFFER(sampler, i), its texel i, and CLIP_DISTANCES, 1 where gl_ClipDistance exists.
// In the web build the version line becomes GLSL ES 3.00's, with the precisions it needs.
GLuint make_program(const std::string& vertex_source, const std::string& fragment_source);
GLuint make_compute_program(const std::string& source);
std::string shader_source(const std::string& source);

// The most texels a TextureBuffer may hold: GL_MAX_TEXTURE_BUFFER_SIZE, or in WebGL2 the rows of the
// largest 2D texture.
std::uint64_t max_buffer_texels();

// Returns once the GPU has done every command given so far (a frame in pieces times its pieces with it):
// glFinish; in WebGL2 a one-pixel read of the bound framebuffer, as a browser's finish() need not wait.
void finish_gpu_work();

// glMultiDrawArrays; in WebGL2, which has it only as an extension, one draw per range, in order.
void multi_draw(GLenum mode, const GLint* first, const GLsizei* count, GLsizei ranges);

// Where TextureBuffer::create_mapped's memory comes from. Mesa's llvmpipe keeps its "GPU memory" in this process's
// memory and takes memory it is handed (GL_AMD_pinned_memory): there, with Auto, a buffer is host memory that the
// filling threads write once and the driver neither clears nor copies. Elsewhere, and with Driver, it is the
// driver's buffer, mapped. host_memory_buffers() says which (needs a current context); tests compare the two.
enum class BufferMemory { Auto, Driver };
void set_buffer_memory(BufferMemory memory);
bool host_memory_buffers();

// A buffer object with a buffer texture viewing it (internal format e.g. GL_R32F, GL_R32UI); in WebGL2, which
// has no buffer textures, a 2D texture of kBufferTextureWidth-texel rows (`buffer` stays 0) that shaders read
// through FETCH_BUFFER.
struct TextureBuffer {
  GLuint buffer = 0, texture = 0;
  void create(GLenum internal_format, const void* data, std::size_t bytes);
  // The same filled in place: create_mapped returns `bytes` (at least 16) of memory for writing, which any thread
  // may fill — the driver's buffer, mapped, or host memory (host_memory_buffers()) — and finish_mapped makes the
  // texture of it (unmapping the driver's buffer, or handing the host memory to the driver). Throws
  // std::runtime_error when the memory cannot be had, the driver loses the contents, or the buffer holds more
  // texels than the driver's limit (max_buffer_texels; create refuses those too). (WebGL2 maps nothing: the
  // memory is the host's, copied to the texture by finish_mapped, which does nothing a second time.)
  void* create_mapped(std::size_t bytes);
  void finish_mapped(GLenum internal_format);
  // The same filled a part a call: begin_parts makes the buffer `bytes` long; each fill_part calls
  // fill(first_byte, part) to write bytes [first_byte, first_byte + part.size()) of the contents into `part`
  // (zeroed before), and says whether more parts remain. WebGL2 copies each part (8 MiB of rows at most) into the
  // texture as it is filled, so that a page's memory, which keeps its high-water mark, holds one part and not a
  // texture's whole contents, and the page takes input between parts; desktop OpenGL maps the buffer and fills it
  // as one part. What fill throws is rethrown, the buffer destroyed.
  using PartFill = std::function<void(std::uint64_t first_byte, std::span<std::uint8_t> part)>;
  void begin_parts(GLenum internal_format, std::size_t bytes);
  bool fill_part(const PartFill& fill);
  // Replaces bytes [offset, offset + bytes) of a buffer made by create (desktop OpenGL only).
  void update(std::size_t offset, const void* data, std::size_t bytes);
  void destroy();

 private:
  GLenum parts_format_ = 0;
  std::size_t parts_bytes_ = 0, next_part_ = 0;  // begin_parts' size, and where the next part starts
#if VOXLINES_WEBGL
  std::size_t mapped_bytes_ = 0;
  std::unique_ptr<std::uint8_t[]> staging_;  // what create_mapped handed out
  std::vector<std::uint8_t> part_;           // the part being filled
#else
  std::uint8_t* parts_memory_ = nullptr;  // the buffer, mapped by begin_parts
  // Host memory (host_memory_buffers()): mapped by create_mapped, handed to the driver by finish_mapped, unmapped
  // by destroy.
  void* host_memory_ = nullptr;
  std::size_t host_bytes_ = 0, mapped_bytes_ = 0;
#endif
};

// RAII-free owner of a framebuffer with colour textures, for multipass modes (and the web viewer's pictures in
// pieces).
struct RenderTarget {
  GLuint fbo = 0, color[2] = {0, 0}, depth = 0;
  int width = 0, height = 0;
  // Recreates when the size or formats change. color1_format 0 means a single colour attachment.
  void ensure(int w, int h, GLenum color0_format, GLenum color1_format, bool with_depth);
  void destroy();
};

std::string version_string();

}  // namespace vxl::gl
