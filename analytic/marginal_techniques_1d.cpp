#include "analytic/marginal_techniques_1d.h"

#include <cmath>
#include <stdexcept>

#include "analytic/quadrature.h"

namespace tb {

ConditionalNormal1D::ConditionalNormal1D(Params p) : p_(std::move(p)) {
  if (p_.mode == Mode::kClassical && !p_.classical)
    throw std::invalid_argument("ConditionalNormal1D '" + p_.name + "': kClassical needs a classical technique");
  if (p_.defensive < 0.0 || p_.defensive > 1.0)
    throw std::invalid_argument("ConditionalNormal1D '" + p_.name + "': defensive weight outside [0, 1]");
}

ConditionalNormal1D::Aux ConditionalNormal1D::aux_for(double t) const {
  Aux a;
  a.t = t;
  switch (p_.mode) {
    case Mode::kCentre: a.conditional = TruncatedNormal1D(t, p_.fixed, p_.x_lo, p_.x_hi); break;
    case Mode::kWidth: a.conditional = TruncatedNormal1D(p_.fixed, t, p_.x_lo, p_.x_hi); break;
    case Mode::kClassical: break;
  }
  return a;
}

std::optional<ConditionalNormal1D::Aux> ConditionalNormal1D::sample_aux(Uniforms& u) const {
  const auto t = p_.t_dist.sample(u);
  if (!t) return std::nullopt;
  return aux_for(*t);
}

std::optional<double> ConditionalNormal1D::sample(const Aux& a, Uniforms& u) const {
  if (p_.defensive > 0.0) {
    if (u.next() < p_.defensive) return u.next();  // the defensive uniform on [0, 1]
  }
  if (p_.mode == Mode::kClassical) return p_.classical->sample(u);
  return a.conditional.sample(u.next());
}

double ConditionalNormal1D::burn(double v) const {
  // Work that the optimiser cannot remove: stands for an expensive conditional pdf (e.g. a path pdf
  // with visibility), so that efficiency against n can be shown for a costly p(x | t).
  double acc = v;
  for (int i = 0; i < p_.pdf_cost_repeats; ++i) acc = std::exp(-acc * 1e-3);
  return acc;
}

double ConditionalNormal1D::pdf(double x, const Aux& a) const {
  double q = p_.mode == Mode::kClassical ? p_.classical->pdf(x) : a.conditional.pdf(x);
  if (p_.pdf_cost_repeats > 0) {
    volatile double sink = burn(q);
    (void)sink;
  }
  if (p_.defensive > 0.0) q = (1.0 - p_.defensive) * q + p_.defensive * ((x >= 0.0 && x <= 1.0) ? 1.0 : 0.0);
  return q;
}

double ConditionalNormal1D::marginal_pdf(double x) const {
  if (p_.mode == Mode::kClassical) return pdf(x, Aux{});
  const auto tb = p_.t_dist.breakpoints();
  return integrate_1d([&](double t) { return pdf(x, aux_for(t)) * pdf_t(t); }, tb.front(), tb.back(), tb).value;
}

std::vector<double> ConditionalNormal1D::x_breakpoints() const {
  std::vector<double> b{p_.x_lo, p_.x_hi, 0.0, 1.0};
  if (p_.classical) {
    const auto cb = p_.classical->breakpoints();
    b.insert(b.end(), cb.begin(), cb.end());
  }
  return b;
}

}  // namespace tb
