#include "lib/mcmc/pss/pss_steps.h"

#include "estimators/mcmc/mutation.h"

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace tb::pss {

namespace {

bool in_d_both(const PssMove& m, size_t i) {
  const size_t j = i / kStreams, s = i % kStreams;
  return j < m.reads_x[s] && j < m.reads_y[s];
}

}  // namespace

double LargeStep::log_density(const DenseState&, const DenseState& y, const PssMove&) const {
  for (double v : y)
    if (!(v >= 0.0 && v < 1.0)) return -std::numeric_limits<double>::infinity();
  return 0.0;
}

double SmallStep::log_density(const DenseState& x, const DenseState& y, const PssMove&) const {
  double lp = 0.0;
  for (size_t i = 0; i < x.size(); ++i) lp += std::log(wrapped_normal_pdf(y[i] - x[i], sigma_));
  return lp;
}

double RescaledSmallStep::scale(double pi, double y_ref) const {
  if (!(pi > 0.0) || !(y_ref > 0.0)) return s_.sigma_max;
  return std::clamp(s_.sigma * std::pow(y_ref / pi, s_.exponent), s_.sigma_min, s_.sigma_max);
}

double RescaledSmallStep::log_reverse_over_forward(const PssMove& m) const {
  double lr = 0.0;
  for (size_t s = 0; s < static_cast<size_t>(kStreams); ++s) {
    const size_t shared = std::min(m.reads_x[s], m.reads_y[s]);
    for (size_t j = 0; j < shared; ++j) {
      const double d = m.difference(j * kStreams + s);  // g is even: one difference serves both ways
      lr += std::log(wrapped_normal_pdf(d, m.sigma_y)) - std::log(wrapped_normal_pdf(d, m.sigma_x));
    }
  }
  return lr;
}

double RescaledSmallStep::log_density(const DenseState& x, const DenseState& y, const PssMove& m) const {
  double lp = 0.0;
  for (size_t i = 0; i < x.size(); ++i)
    lp += std::log(wrapped_normal_pdf(y[i] - x[i], in_d_both(m, i) ? m.sigma_x : s_.sigma));
  return lp;
}

// ---- selection and the registry -------------------------------------------------------------------

double selection_probability(const PssMutationList& list, int k) {
  double sum = 0.0;
  for (const auto& m : list) sum += std::max(0.0, m->weight());
  const double w = std::max(0.0, list[static_cast<size_t>(k)]->weight());
  return sum > 0.0 ? w / sum : 0.0;
}

int select_mutation(const PssMutationList& list, double v) {
  double sum = 0.0;
  for (const auto& m : list) sum += std::max(0.0, m->weight());
  if (!(sum > 0.0)) return -1;
  const double target = v * sum;
  double acc = 0.0;
  int last = -1;
  for (size_t k = 0; k < list.size(); ++k) {
    const double w = std::max(0.0, list[k]->weight());
    if (w > 0.0) last = static_cast<int>(k);
    acc += w;
    if (target < acc && w > 0.0) return static_cast<int>(k);
  }
  return last;
}

namespace {

template <class M>
std::shared_ptr<const PssMutation> make(const PssStepSettings& s) {
  return std::make_shared<const M>(s);
}

std::vector<PssMutationInfo>& table() {
  static std::vector<PssMutationInfo> t = {
      {"large step", "every coordinate replaced by a fresh uniform (Kelemen et al. 2002)", make<LargeStep>},
      {"small step", "wrapped Gaussian perturbation of every coordinate, sigma0 (Kelemen et al. 2002)", make<SmallStep>},
      {"rescaled small step",
       "wrapped Gaussian with sigma(x) inversely proportional to the path's luminance on D(x) ∩ D(y) "
       "(Szirmay-Kalos & Szecsi 2017)",
       make<RescaledSmallStep>},
  };
  return t;
}

}  // namespace

const std::vector<PssMutationInfo>& pss_mutations() { return table(); }

const PssMutationInfo* find_pss_mutation(const std::string& name) { return mcmc::find_named(table(), name); }

void register_pss_mutation(PssMutationInfo info) { mcmc::add_named(table(), std::move(info), "PSS mutation"); }

void unregister_pss_mutation(const std::string& name) { mcmc::remove_named(table(), name); }

PssMutationList make_pss_mutations(const std::vector<std::string>& names, const PssStepSettings& s) {
  PssMutationList out;
  for (const auto& n : names) {
    const PssMutationInfo* m = find_pss_mutation(n);
    if (!m) throw std::invalid_argument("unknown PSS mutation '" + n + "'");
    out.push_back(m->make(s));
  }
  return out;
}

}  // namespace tb::pss
