// Keeps Mesa's DRI driver loaded for the rest of the process.
//
// Mesa loads its DRI driver (swrast_dri.so, iris_dri.so, ...: tens of MB, with LLVM) when a display is
// initialised (EGL or GLX) and unloads it when the display is terminated. Keeping every loaded DRI driver
// resident means later contexts skip the reload, and the driver's one-time allocations stay reachable
// from its globals instead of turning into leaks of an unmapped module (which LeakSanitizer can neither
// attribute nor suppress). No-op for drivers without *_dri.so (NVIDIA).
#pragma once

namespace vxl {

void pin_dri_drivers() noexcept;

}  // namespace vxl
