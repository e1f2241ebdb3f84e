// Pixel reconstruction filters (pbrt-v3 Sec. 7.8): a sample at raster position p contributes
// to pixel (i, j) with weight f(p - c_ij), c_ij = (i + 0.5, j + 0.5), wherever |p - c| is
// within the filter radius on both axes. The film divides by the sum of weights (pbrt-v3
// Eq. 7.12), so filters need not integrate to one.
#pragma once

#include <memory>
#include <string_view>

#include "lib/core/math.h"

namespace tb {

class Filter {
 public:
  virtual ~Filter() = default;
  virtual std::string_view name() const = 0;
  // Half-widths of the support in raster units.
  virtual Vec2 radius() const = 0;
  // Weight of a sample at offset d from the pixel centre; 0 outside the support.
  virtual double eval(const Vec2& d) const = 0;
};

// Box filter, support [-r, r) on both axes (half-open so that with r = 0.5 every raster point
// belongs to exactly one pixel). Weight 1.
class BoxFilter final : public Filter {
 public:
  explicit BoxFilter(Vec2 radius = Vec2(0.5)) : r_(radius) {}
  std::string_view name() const override { return "box"; }
  Vec2 radius() const override { return r_; }
  double eval(const Vec2& d) const override {
    return (d.x >= -r_.x && d.x < r_.x && d.y >= -r_.y && d.y < r_.y) ? 1.0 : 0.0;
  }

 private:
  Vec2 r_;
};

// Truncated Gaussian, separable, shifted to reach zero at the radius (pbrt-v3 Sec. 7.8.2):
// f(x) = exp(-x^2 / (2 sigma^2)) - exp(-r^2 / (2 sigma^2)) per axis.
class GaussianFilter final : public Filter {
 public:
  GaussianFilter(Vec2 radius, double sigma);
  std::string_view name() const override { return "gaussian"; }
  Vec2 radius() const override { return r_; }
  double eval(const Vec2& d) const override;

 private:
  double axis(double x, double r, double edge) const;
  Vec2 r_;
  double inv_2s2_;
  Vec2 edge_;
};

// "box" (radius 0.5) or "gaussian" (radius 1.5, sigma 0.5); throws on an unknown name.
std::shared_ptr<const Filter> make_filter(std::string_view name);

}  // namespace tb
