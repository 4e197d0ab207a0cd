// Loads the picture module (picture_module.h) on first use, once per process, and keeps it loaded.
#pragma once

#include "viewer/platform/picture_module.h"

namespace vxl::pictures {

// The module's table. Looks for libvoxlines_pictures.so, in this order: the path in $VOXLINES_PICTURE_MODULE
// alone when that is set; beside the running executable; in the installed library folder relative to it
// (bin/../lib/voxlines); where this build wrote it. Throws vxl::Error (Unsupported) naming `picture` and every
// place tried when none loads. Thread-safe.
const Api& picture_module(const std::string& picture);

}  // namespace vxl::pictures
