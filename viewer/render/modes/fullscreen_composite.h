// The last step of the modes that draw their lines into targets of their own (wboit, additive): a
// fullscreen triangle of `program` over the bound framebuffer, reading the named 2D textures.
#pragma once

#include <initializer_list>
#include <utility>

#include "viewer/render/gl_util.h"

namespace vxl {

// vao: an empty vertex array (core profile draws need one); the triangle comes from gl_VertexID.
void draw_fullscreen_composite(GLuint program, GLuint vao,
                               std::initializer_list<std::pair<const char*, GLuint>> textures);

}  // namespace vxl
