// The blend and depth states the modes share.
#pragma once

namespace vxl {

// Over-compositing (basic, axis, segsort, unsorted, and the composites over the base): colour premultiplied,
// coverage accumulated in alpha (docs/rendering.md, pitfall 1).
void over_blending();
// The opaque mode: nearest line wins, colour replaces, alpha stays the clear's 1.
void opaque_blending();

}  // namespace vxl
