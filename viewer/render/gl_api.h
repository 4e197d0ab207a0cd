// The OpenGL API the renderer is written against: desktop OpenGL 3.3 core (4.3 for `exact`) through libepoxy,
// or, in the web build (Emscripten), WebGL2: OpenGL ES 3.0 less mapped buffers, with no buffer textures, no
// clip distances and no compute shaders. What differs is bridged in gl_util (buffer textures as 2D textures,
// each shader's dialect) so that the rest of the renderer is one code for both.
#pragma once

#if defined(__EMSCRIPTEN__)
#define VOXLINES_WEBGL 1
#include <GLES3/gl3.h>
// OpenGL ES spells it with a float.
inline void glClearDepth(double depth) { glClearDepthf(static_cast<GLfloat>(depth)); }
#else
#define VOXLINES_WEBGL 0
#include <epoxy/gl.h>
#endif

namespace vxl::gl {

inline constexpr bool kWebGL = VOXLINES_WEBGL != 0;

// The texture target a TextureBuffer's texture binds to.
#if VOXLINES_WEBGL
inline constexpr GLenum kBufferTextureTarget = GL_TEXTURE_2D;
#else
inline constexpr GLenum kBufferTextureTarget = GL_TEXTURE_BUFFER;
#endif

// WebGL2 stands a 2D texture of rows this wide (a power of two) in for a buffer texture: texel i is at
// (i mod width, i / width).
inline constexpr int kBufferTextureWidthLog2 = 12;
inline constexpr int kBufferTextureWidth = 1 << kBufferTextureWidthLog2;

}  // namespace vxl::gl
