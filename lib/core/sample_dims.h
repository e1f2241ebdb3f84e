// Named sample dimensions (after Cycles' PRNG_* enum): estimators compared side by side
// consume the same uniforms for the same decisions. Dimension of a decision at bounce b is
// kCameraDims + b * kDimsPerBounce + offset.
#pragma once

#include <cstdint>

namespace tb {

enum class CameraDim : uint32_t {
  kFilmX = 0,
  kFilmY = 1,
  kLensU = 2,
  kLensV = 3,
};
inline constexpr uint32_t kCameraDims = 4;

enum class BounceDim : uint32_t {
  kLightSelect = 0,   // which emitter for next-event estimation
  kLightU = 1,        // point / direction on the emitter (2 dims)
  kLightV = 2,
  kBsdfLobe = 3,      // which BSDF lobe (reflect / transmit, component)
  kBsdfU = 4,         // direction from the lobe (2 dims)
  kBsdfV = 5,
  kRussianRoulette = 6,
};
inline constexpr uint32_t kDimsPerBounce = 7;

constexpr uint32_t sample_dim(uint32_t bounce, BounceDim d) {
  return kCameraDims + bounce * kDimsPerBounce + static_cast<uint32_t>(d);
}
constexpr uint32_t sample_dim(CameraDim d) { return static_cast<uint32_t>(d); }

}  // namespace tb
