// A zoomed spherical domain for the sampler chi-square test (docs/validation.md A; docs/chi2.md):
// directions near an axis a, expressed in the frame (s, t, a) and binned on the orthographic
// chart of the cap around a,
//
//   (x, y) = (w . s, w . t)   for w . a > 0,   chart square [-h, h]^2 (h < 1/sqrt 2).
//
// Why: a lobe 1e-4..1e-6 rad wide (a rough dielectric at IOR 1.0001, a distant lens) is a
// sliver in (phi, cos theta) around +z (cos theta bins of width 1e-12 lose all precision), but
// on the chart it is a blob of width ~1e-6 with absolute precision ~1e-16.
//
// Jacobian: the chart inverse is r(x, y) = x s + y t + z a, z = sqrt(1 - x^2 - y^2), a
// parametrisation of the unit sphere. dr/dx = s - (x/z) a, dr/dy = t - (y/z) a, and
// |dr/dx x dr/dy| = |a + (x/z) s + (y/z) t| = sqrt(z^2 + x^2 + y^2) / z = 1 / z. Hence
//
//   d omega = dx dy / z,   pdf_chart(x, y) = pdf_solid_angle(r(x, y)) / z.
//
// Samples outside the chart square (or in the far hemisphere) go to the failure cell, as do
// the sampler's failures; its expected count is N (1 - int_chart pdf_chart), i.e. the mass the
// stated pdf puts outside the chart plus any deficit of the pdf (docs/validation.md A). Because that
// mass can be small but nonzero, the front end lowers failure_mass_floor (see zoomed options).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "lib/core/frame.h"
#include "lib/core/math.h"
#include "lib/core/uniforms.h"
#include "validate/chi2/sampler_chi2.h"

namespace tb {

namespace zoom_detail {
template <class F>
auto call_with_uniforms(const F& f, Uniforms& u) {
  if constexpr (std::is_invocable_v<const F&, Uniforms&>)
    return f(u);
  else
    return f(u.next2());
}
}  // namespace zoom_detail

struct Chi2DirectionChart {
  Frame frame;             // frame.n: the axis (centre of the chart)
  double half_width = 0.1; // chart square [-h, h]^2 in (x, y)
  int n = 41;              // bins per side (odd: no cell edge on the axis)

  static Chi2DirectionChart around(const Vec3& axis, double half_width, int n = 41) {
    return {Frame::from_z(glm::normalize(axis)), std::min(half_width, 0.7), n};
  }
  // Fits a chart to pilot samples (drawn from a stream independent of the test's, so the grid
  // does not depend on the tested samples): centred on the coordinate-wise median of the pilot
  // directions in the chart of `guess`, with h the `coverage` quantile of max(|x|, |y|) about
  // that centre. Returns nothing when too few pilot directions lie in guess's hemisphere.
  static std::optional<Chi2DirectionChart> fit(const std::vector<Vec3>& pilot, const Vec3& guess, double coverage,
                                               int n = 41);

  Chi2Domain domain() const { return Chi2Domain::rectangle({-half_width, -half_width}, {half_width, half_width}, n, n); }
  // Chart point of a world direction, or nothing outside the chart.
  std::optional<Vec2> to_chart(const Vec3& w) const {
    const Vec3 l = frame.to_local(w);
    if (!(l.z > 0.0 && std::abs(l.x) <= half_width && std::abs(l.y) <= half_width)) return std::nullopt;
    return Vec2(l.x, l.y);
  }
  // World direction of a chart point, and d omega / (dx dy) = 1 / z there.
  Vec3 direction(const Vec2& q) const { return frame.to_world(Vec3(q.x, q.y, z_of(q))); }
  static double z_of(const Vec2& q) { return std::sqrt(std::max(0.0, 1.0 - q.x * q.x - q.y * q.y)); }
  double solid_angle_per_area(const Vec2& q) const { return 1.0 / z_of(q); }
  std::string describe() const {
    return fmt::format("zoomed cap around ({:.6g}, {:.6g}, {:.6g}), orthographic chart [-{:.3g}, {:.3g}]^2, {} x {} bins",
                       frame.n.x, frame.n.y, frame.n.z, half_width, half_width, n, n);
  }
};

// Options for zoomed tests: as SamplerChi2Options, with the failure-cell floor lowered to
// quadrature noise (the cell holds the real mass outside the chart).
inline SamplerChi2Options zoomed_chi2_options(SamplerChi2Options o) {
  o.failure_mass_floor = std::min(o.failure_mass_floor, 1e-9);
  return o;
}

// sample: (Vec2) or (Uniforms&) -> std::optional<Vec3> (a unit world direction); pdf: (Vec3)
// -> density w.r.t. solid angle. Non-unit directions are hard failures (outside the domain);
// unit directions off the chart count as failed samples (see above).
template <class SampleFn, class PdfFn>
SamplerChi2Result chi2_test_zoomed(const Chi2DirectionChart& chart, const SampleFn& sample, const PdfFn& pdf,
                                   const SamplerChi2Options& options = {}) {
  const SamplerChi2Options o = zoomed_chi2_options(options);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const auto chart_sample = [&](Uniforms& u) -> std::optional<Vec2> {
    const auto w = chi2_detail::as_optional(zoom_detail::call_with_uniforms(sample, u));
    if (!w) return std::nullopt;
    if (!(is_finite(*w) && std::abs(glm::length(*w) - 1.0) <= o.unit_tolerance)) return Vec2(nan, nan);  // hard
    return chart.to_chart(*w);
  };
  const auto chart_pdf = [&](Vec2 q) {
    return static_cast<double>(pdf(chart.direction(q))) * chart.solid_angle_per_area(q);
  };
  return chi2_test(chart.domain(), chart_sample, chart_pdf, o);
}

}  // namespace tb
