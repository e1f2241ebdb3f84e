#include "lib/path/light_sampler.h"

#include <cmath>

namespace tb {

LightSampler::LightSampler(const World& world) : lights_(world.lights()) {
  std::vector<double> w;
  w.reserve(lights_.size());
  for (const Light* l : lights_) {
    const Rgb p = l->power();
    const double y = luminance(p);
    w.push_back(std::isfinite(y) && y > 0 ? y : 0.0);
  }
  cdf_ = DiscreteCdf::create(w);
  if (!cdf_ && !lights_.empty()) {
    std::vector<double> uniform(lights_.size(), 1.0);
    cdf_ = DiscreteCdf::create(uniform);
  }
  for (size_t i = 0; i < lights_.size(); ++i) index_[lights_[i]] = i;
  if (cdf_) pmf0_ = cdf_->pmf(0);
}

std::optional<LightSampler::Choice> LightSampler::sample_general(double u) const {
  if (!cdf_) return std::nullopt;
  const DiscreteSample s = cdf_->sample(u);
  return Choice{lights_[s.index], cdf_->pmf(s.index), s.u_remapped};
}

double LightSampler::pmf_general(const Light* light) const {
  if (!cdf_) return 0.0;
  const auto it = index_.find(light);
  return it == index_.end() ? 0.0 : cdf_->pmf(it->second);
}

}  // namespace tb
