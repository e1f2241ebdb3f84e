// Classical 2D techniques on [0, 1]²: products of two classical 1D techniques,
// p(x, y) = p_x(x) p_y(y) (Lebesgue measure on the plane). Satisfies tb::Technique with Sample = Vec2.
#pragma once

#include <optional>

#include "analytic/classical_techniques_1d.h"
#include "lib/core/math.h"

namespace tb {

struct Product2D {
  using Sample = Vec2;
  Classical1D px = UniformTechnique1D{};
  Classical1D py = UniformTechnique1D{};
  std::optional<Vec2> sample(Uniforms& u) const {
    const auto x = px.sample(u);
    if (!x) return std::nullopt;
    const auto y = py.sample(u);
    if (!y) return std::nullopt;
    return Vec2{*x, *y};
  }
  double pdf(const Vec2& p) const { return px.pdf(p.x) * py.pdf(p.y); }
};

}  // namespace tb
