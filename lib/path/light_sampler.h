// Choosing an emitter: with probability proportional to its power (the luminance of
// Light::power()), falling back to uniform when every power is zero or infinite. The same
// distribution serves next-event estimation, emission sampling for light tracing and the
// emitter densities of the path MIS weights, so their densities agree.
#pragma once

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
  std::optional<Choice> sample(double u) const;
  double pmf(const Light* light) const;
  size_t size() const { return lights_.size(); }

 private:
  std::vector<const Light*> lights_;
  std::optional<DiscreteCdf> cdf_;
  std::unordered_map<const Light*, size_t> index_;
};

}  // namespace tb
