// Marginal 1D techniques (West et al. 2022, Eq. 2): t ~ p(t) on a technique space, then x ~ p(x | t).
// One family, ConditionalNormal1D, covers the cases of the paper's Fig. 1:
//   kCentre: x | t ~ N(t, sigma²) truncated to [x_lo, x_hi]   (t is the centre)
//   kWidth:  x | t ~ N(mu, t²) truncated to [x_lo, x_hi]      (t is the width)
//   kClassical: x | t ~ a classical technique c, whatever t   (a classical technique extruded over a
//               technique space, West et al. 2022 Sec. 3.1; t is drawn only to show the joint density)
// optionally mixed with a defensive uniform on [0, 1]:  p(x | t) = (1 - ε) q(x | t) + ε.
// All densities are in Lebesgue measure (x in R, t in R). marginal_pdf() integrates p(x | t) p(t)
// over t by quadrature: it is the "exact marginal" of the reference MIS and the tests, never used by
// MMIS. pdf_cost_repeats > 0 makes p(x | t) artificially expensive (the efficiency experiment).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "analytic/classical_techniques_1d.h"
#include "analytic/truncated_normal_1d.h"

namespace tb {

class ConditionalNormal1D {
 public:
  enum class Mode { kCentre, kWidth, kClassical };
  struct Aux {
    double t = 0.0;
    TruncatedNormal1D conditional;  // normaliser precomputed once per sampled technique
  };
  using Sample = double;

  struct Params {
    std::string name;
    Classical1D t_dist = UniformTechnique1D{};  // p(t) on the technique space
    Mode mode = Mode::kCentre;
    double fixed = 0.1;                // sigma (kCentre) or mu (kWidth)
    double x_lo = 0.0, x_hi = 1.0;     // truncation of x | t (may not cover [0, 1])
    double defensive = 0.0;            // weight ε of the uniform on [0, 1]
    std::optional<Classical1D> classical;  // kClassical: the extruded technique
    int pdf_cost_repeats = 0;          // extra exp() evaluations per p(x | t) (cost model only)
  };

  explicit ConditionalNormal1D(Params p);

  std::optional<Aux> sample_aux(Uniforms& u) const;
  std::optional<double> sample(const Aux& a, Uniforms& u) const;
  // p(x | t), Lebesgue measure in x.
  double pdf(double x, const Aux& a) const;
  // p(t), Lebesgue measure in t.
  double pdf_t(double t) const { return p_.t_dist.pdf(t); }
  // p(t) of a sampled auxiliary (with marginal_pdf, makes this a tb::ContinuousTechnique).
  double aux_pdf(const Aux& a) const { return pdf_t(a.t); }
  // p(x, t) = p(x | t) p(t).
  double joint_pdf(double x, double t) const { return pdf(x, aux_for(t)) * pdf_t(t); }
  // p(x) = ∫ p(x | t) p(t) dt by adaptive quadrature (relative tolerance 1e-12).
  double marginal_pdf(double x) const;
  // Breakpoints of the marginal p(x) in x (truncation ends, defensive support, classical breaks).
  std::vector<double> x_breakpoints() const;
  // The technique-space interval [lo, hi] where p(t) may be positive.
  double t_lo() const { return p_.t_dist.breakpoints().front(); }
  double t_hi() const { return p_.t_dist.breakpoints().back(); }
  Aux aux_for(double t) const;
  const Params& params() const { return p_; }
  const std::string& name() const { return p_.name; }

 private:
  double burn(double v) const;
  Params p_;
};

// The reference technique for ConditionalNormal1D: samples t then x, but evaluates the exact
// marginal p(x) (by quadrature). A classical technique (tb::Technique), expensive on purpose.
struct ExactMarginal1D {
  using Sample = double;
  const ConditionalNormal1D* m = nullptr;
  std::optional<double> sample(Uniforms& u) const {
    const auto t = m->sample_aux(u);
    if (!t) return std::nullopt;
    return m->sample(*t, u);
  }
  double pdf(double x) const { return m->marginal_pdf(x); }
};

}  // namespace tb
