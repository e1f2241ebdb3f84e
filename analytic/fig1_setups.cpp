#include "analytic/fig1_setups.h"

#include "analytic/mis_variance.h"

namespace tb {

Fig1Top make_fig1_top() {
  // Classical: 90% uniform on the plateau [0.1, 0.35], 10% defensive uniform on [0, 1].
  Classical1D classical(MixtureTechnique1D({UniformTechnique1D{0.1, 0.35}, UniformTechnique1D{0.0, 1.0}}, {0.9, 0.1}),
                        "classical_left");
  ConditionalNormal1D::Params m;
  m.name = "marginal_right";
  m.t_dist = Classical1D(TruncatedNormalTechnique1D(0.72, 0.04, 0.55, 0.9));  // centre t around the peak
  m.mode = ConditionalNormal1D::Mode::kCentre;
  m.fixed = 0.03;
  m.defensive = 0.1;
  ConditionalNormal1D::Params e;
  e.name = "classical_left_extruded";
  e.t_dist = Classical1D(UniformTechnique1D{0.0, 1.0});
  e.mode = ConditionalNormal1D::Mode::kClassical;
  e.classical = classical;
  return {&integrand_1d("fig1_two_features"), classical, ConditionalNormal1D(m), ConditionalNormal1D(e)};
}

Fig1Bottom make_fig1_bottom(int pdf_cost_repeats) {
  std::vector<ConditionalNormal1D> v;
  ConditionalNormal1D::Params a;  // left peak: random centre, x truncated to [0, 0.3]
  a.name = "left_centre";
  a.t_dist = Classical1D(UniformTechnique1D{0.05, 0.25});
  a.fixed = 0.04;
  a.x_lo = 0.0;
  a.x_hi = 0.3;
  a.pdf_cost_repeats = pdf_cost_repeats;
  v.emplace_back(a);
  ConditionalNormal1D::Params b;  // middle peak: random width, x truncated to [0.38, 0.62]
  b.name = "middle_width";
  b.t_dist = Classical1D(UniformTechnique1D{0.02, 0.12});
  b.mode = ConditionalNormal1D::Mode::kWidth;
  b.fixed = 0.5;
  b.x_lo = 0.38;
  b.x_hi = 0.62;
  b.pdf_cost_repeats = pdf_cost_repeats;
  v.emplace_back(b);
  ConditionalNormal1D::Params c;  // right peak: random centre, x truncated to [0.7, 1]
  c.name = "right_centre";
  c.t_dist = Classical1D(TruncatedNormalTechnique1D(0.85, 0.05, 0.7, 1.0));
  c.fixed = 0.03;
  c.x_lo = 0.7;
  c.x_hi = 1.0;
  c.pdf_cost_repeats = pdf_cost_repeats;
  v.emplace_back(c);
  ConditionalNormal1D::Params d;  // defensive: wide normal around a uniform centre, half uniform x
  d.name = "defensive";
  d.t_dist = Classical1D(UniformTechnique1D{0.0, 1.0});
  d.fixed = 0.15;
  d.defensive = 0.5;
  d.pdf_cost_repeats = pdf_cost_repeats;
  v.emplace_back(d);
  return {&integrand_1d("fig1_three_peaks"), std::move(v)};
}

double fig1_bottom_reference_variance(const Fig1Bottom& b, const std::vector<int>& counts) {
  MisVarianceInput in;
  in.f = *b.f;
  in.counts = counts;
  for (const auto& m : b.techniques) {
    in.pdfs.push_back([&m](double x) { return m.marginal_pdf(x); });
    const auto br = m.x_breakpoints();
    in.breakpoints.insert(in.breakpoints.end(), br.begin(), br.end());
  }
  return mis_balance_variance(in);
}

}  // namespace tb
