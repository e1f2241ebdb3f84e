#include "lib/film/filter.h"

#include <stdexcept>
#include <string>

namespace tb {

GaussianFilter::GaussianFilter(Vec2 radius, double sigma) : r_(radius), inv_2s2_(1.0 / (2.0 * sigma * sigma)) {
  if (!(sigma > 0.0) || !(radius.x > 0.0) || !(radius.y > 0.0))
    throw std::invalid_argument("gaussian filter: sigma and radius must be positive");
  edge_ = {std::exp(-radius.x * radius.x * inv_2s2_), std::exp(-radius.y * radius.y * inv_2s2_)};
}

double GaussianFilter::axis(double x, double r, double edge) const {
  if (std::abs(x) >= r) return 0.0;
  return std::max(0.0, std::exp(-x * x * inv_2s2_) - edge);
}

double GaussianFilter::eval(const Vec2& d) const { return axis(d.x, r_.x, edge_.x) * axis(d.y, r_.y, edge_.y); }

std::shared_ptr<const Filter> make_filter(std::string_view name) {
  if (name == "box") return std::make_shared<BoxFilter>();
  if (name == "gaussian") return std::make_shared<GaussianFilter>(Vec2(1.5), 0.5);
  throw std::invalid_argument("unknown filter '" + std::string(name) + "' (known: box, gaussian)");
}

}  // namespace tb
