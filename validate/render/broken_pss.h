// Negative controls of primary-sample-space MLT as wrappers of the real components: each is the
// production mutation, sample function or splat weight with one factor removed, handed to the
// unchanged driver (PssSettings::mutations, wrap_sample, splat_weight). The checks that must reject
// them are in validate/checks/mcmc_pss_checks.cpp.
#pragma once

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "lib/mcmc/pss/pss_driver.h"
#include "lib/mcmc/pss/pss_kernel.h"
#include "lib/mcmc/pss/pss_mutation.h"
#include "lib/mcmc/pss/pss_sample.h"

namespace tb::pss {

// A mutation whose acceptance forgets T(y -> x) / T(x -> y) (its stated density is the real one):
// for the rescaled small step, the acceptance min(1, pi(y) / pi(x)) of an asymmetric proposal.
class WithoutProposalRatio final : public PssMutation {
 public:
  explicit WithoutProposalRatio(std::shared_ptr<const PssMutation> m) : m_(std::move(m)) {}
  std::string name() const override { return m_->name(); }
  double weight() const override { return m_->weight(); }
  bool independent() const override { return m_->independent(); }
  bool symmetric() const override { return m_->symmetric(); }
  double scale(double pi, double y_ref) const override { return m_->scale(pi, y_ref); }
  void begin(PssState& s, double scale_x) const override { m_->begin(s, scale_x); }
  double log_reverse_over_forward(const PssMove&) const override { return 0.0; }  // the defect
  double log_density(const DenseState& x, const DenseState& y, const PssMove& m) const override {
    return m_->log_density(x, y, m);
  }

 private:
  std::shared_ptr<const PssMutation> m_;
};

// A mutation whose STATED density T(x -> y) is misstated while its sampler (begin), scales and
// acceptance ratio are the real ones: the stated density is the real one at the displacement
// shrunk by `widen` (y_i - x_i wrapped to [-1/2, 1/2), divided by widen), times the tilt
// prod_i (1 + tilt (y_i - 1/2)). For a wrapped-Gaussian step of sigma the first factor is the
// density of the step of sigma * widen (Gaussian steps: 5 % too wide at widen = 1.05); the tilt
// makes the uniform large step's stated density non-uniform, so every registered mutation is
// misstated. Both factors act coordinate by coordinate, so a factorising T stays factorising.
// The negative control of the generic proposal chi-square (mcmc.pss.negative_control.
// registered_mutations_misstated.chi2).
class MisstatedDensity final : public PssMutation {
 public:
  explicit MisstatedDensity(std::shared_ptr<const PssMutation> m, double widen = 1.05, double tilt = 0.2)
      : m_(std::move(m)), widen_(widen), tilt_(tilt) {}
  std::string name() const override { return m_->name(); }
  double weight() const override { return m_->weight(); }
  bool independent() const override { return m_->independent(); }
  bool symmetric() const override { return m_->symmetric(); }
  double scale(double pi, double y_ref) const override { return m_->scale(pi, y_ref); }
  void begin(PssState& s, double scale_x) const override { m_->begin(s, scale_x); }
  double log_reverse_over_forward(const PssMove& mv) const override { return m_->log_reverse_over_forward(mv); }
  double log_density(const DenseState& x, const DenseState& y, const PssMove& mv) const override {
    DenseState shrunk(y.size());
    double tilt = 0.0;
    for (size_t i = 0; i < y.size(); ++i) {
      double d = y[i] - x[i];
      d -= std::floor(d + 0.5);  // [-1/2, 1/2)
      shrunk[i] = wrap01(x[i] + d / widen_);
      tilt += std::log1p(tilt_ * (y[i] - 0.5));
    }
    DenseMove m(x, shrunk);
    m.reads_x = mv.reads_x;
    m.reads_y = mv.reads_y;
    m.sigma_x = mv.sigma_x;
    m.sigma_y = mv.sigma_y;
    return m_->log_density(x, shrunk, m) + tilt;
  }

 private:
  std::shared_ptr<const PssMutation> m_;
  double widen_, tilt_;
};

// The registered mutations of `settings` with `name` wrapped by WithoutProposalRatio.
inline PssMutationList without_proposal_ratio(const PssSettings& settings, const std::string& name) {
  PssMutationList list = settings.mutation_list();
  for (auto& m : list)
    if (m->name() == name) m = std::make_shared<const WithoutProposalRatio>(m);
  return list;
}

// Expected-value splatting without the (1 - a) splat of the current state.
inline double splat_without_rejected(mcmc::Which which, double w, double pi, const std::vector<Splat>&) {
  return which == mcmc::Which::kCurrent ? 0.0 : w / pi;
}

// Splats v / Y(sum v) instead of v / pi (a custom target forgetting its weight).
inline double splat_throughput(mcmc::Which, double w, double, const std::vector<Splat>& splats) {
  const double y = target_value(splats);
  return y > 0.0 ? w / y : 0.0;
}

// MMLT without the technique count k + 1: the real sample function's splats divided by k + 1 =
// level + 2 (mmlt_sample_function, pss_sample.h).
inline SampleFunction without_technique_count(const SampleFunction& f) {
  SampleFunction g = f;
  g.sample = [inner = f.sample](int level, StreamUniforms& u, std::vector<Splat>* out) {
    const size_t first = out->size();
    inner(level, u, out);
    for (size_t i = first; i < out->size(); ++i) (*out)[i].value = (*out)[i].value / static_cast<double>(level + 2);
  };
  return g;
}

}  // namespace tb::pss
