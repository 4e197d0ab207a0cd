// The brain-like ellipsoid the synthetic generator draws inside (synth.h), RAS mm: for the generator's
// arithmetic (synth_random.h) and for the tests and tools that check where the points lie.
#pragma once

#include <array>

namespace vxl {

inline constexpr std::array<double, 3> kSynthCentre = {0.0, -18.0, 10.0};
inline constexpr std::array<double, 3> kSynthSemiAxes = {70.0, 85.0, 60.0};

}  // namespace vxl
