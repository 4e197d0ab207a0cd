// Must not compile: the renderer may not use the viewer's program (see format_includes_converter.cpp).
#include "viewer/app/window_app.h"
