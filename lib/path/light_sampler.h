// Choosing an emitter: with probability proportional to its power (the luminance of
// Light::power()), falling back to uniform when every power is zero or infinite. The same
// distribution serves next-event estimation, emission sampling for light tracing and the
// emitter densities of the path MIS weights, so their densities agree.
#pragma once

#include <algorithm>
#include <optional>
#include <unordered_map>
#include <vector>

#include "lib/core/discrete.h"
#include "lib/scene/world.h"

namespace tb {

class LightSampler {
 public:
  explicit LightSampler(const World& world);

  struct Choice {
    const Light* light = nullptr;
    double pmf = 0.0;
    double u_remapped = 0.0;
  };
  // Empty when the world has no light.
  std::optional<Choice> sample(double u) const {
    // One light (the common case in NEE), inline: DiscreteCdf::sample's expressions with cdf 0, pmf0_.
    if (lights_.size() == 1) return Choice{lights_[0], pmf0_, std::clamp(u / pmf0_, 0.0, kOneMinusEpsilon)};
    return sample_general(u);
  }
  double pmf(const Light* light) const {
    if (lights_.size() == 1) return light == lights_[0] ? pmf0_ : 0.0;
    return pmf_general(light);
  }
  size_t size() const { return lights_.size(); }

 private:
  std::vector<const Light*> lights_;
  std::optional<DiscreteCdf> cdf_;
  std::unordered_map<const Light*, size_t> index_;
  double pmf0_ = 0.0;  // cdf_->pmf(0): the one light's pmf (1 up to rounding) when there is one
  std::optional<Choice> sample_general(double u) const;
  double pmf_general(const Light* light) const;
};

}  // namespace tb
