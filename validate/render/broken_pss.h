// Negative controls of primary-sample-space MLT as wrappers of the real components: each is the
// production mutation, sample function or splat weight with one factor removed, handed to the
// unchanged driver (PssSettings::mutations, wrap_sample, splat_weight). The checks that must reject
// them are in validate/checks/mcmc_pss_checks.cpp.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "lib/mcmc/pss/pss_driver.h"
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
