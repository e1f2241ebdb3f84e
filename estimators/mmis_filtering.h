// The MMIS denominator of multi-vertex path filtering at linear cost (West et al. 2022, Sec. 5, Eq. 14).
//
// An output path x̄ is filtered at K vertices; kernel k holds m_k conditioning prefixes y_{k,1..m_k}
// (N(P, κ_k) in Sec. 5). A conditional technique is one prefix per kernel, a combination
// j̄ = (j_1, …, j_K), so there are T = Π_k m_k of them (each with n = 1), and its conditional density
// factorises over the kernels (Eq. 14):
//   p_j̄(x̄ | t̄_j̄) = Π_k p_k(x_k | y_{k,j_k}).
// The Eq. 13 denominator, a sum over every combination of a product over the kernels, is therefore a
// product over the kernels of a sum over that kernel's prefixes:
//   D(x̄) = Σ_j̄ Π_k p_k(x_k | y_{k,j_k}) = Π_k S_k,   S_k = Σ_j p_k(x_k | y_{k,j})          (Eq. 14)
// (distributivity). The left side costs K·Π_k m_k pdf evaluations (exponential in K), the right side
// Σ_k m_k (linear in K). Without classical techniques the MMIS weight of technique j̄ for x̄ is then
// Π_k p_k(x_k | y_{k,j_k}) / S_k: the product of a balance-heuristic MIS weight local to each kernel.
// Classical techniques mixed in by the split denominator of Sec. 3.1 (in path filtering, the suffix
// sampled at the query vertex itself) add their Σ_c n_c p_c(x̄) to D; the product of sums is unchanged.
//
// The densities are given by a callable pdf(k, j) = p_k(x_k | y_{k,j}) for the one output sample whose
// weight is computed (k and j 0-based). mmis.h's for_each_mmis_weight over the T combinations as pairs
// gives the same D and weights at exponential cost (the mmis.filtering.* checks compare them to 1e-12).
#pragma once

#include <cstdint>
#include <span>
#include <stdexcept>

#include "estimators/estimate.h"

namespace tb {

// Advances the combination j̄ (an odometer over j_k in [0, m_k), kernel 0 fastest); false after the last.
inline bool next_filtering_combination(std::span<int> j, std::span<const int> prefixes) {
  for (size_t k = 0; k < j.size(); ++k) {
    if (++j[k] < prefixes[k]) return true;
    j[k] = 0;
  }
  return false;
}

// Number of conditional techniques T = Π_k m_k (Sec. 5).
inline int64_t filtering_technique_count(std::span<const int> prefixes) {
  int64_t t = 1;
  for (int m : prefixes) t *= m;
  return t;
}

// Eq. 14 as printed: Σ over every combination j̄ of Π_k p_k(x_k | y_{k,j_k}). K·Π_k m_k pdf evaluations
// (added to *pdf_evals when given). The reference for filtering_product_of_sums, not for rendering.
template <class Pdf>
double filtering_sum_of_products(std::span<const int> prefixes, const Pdf& pdf, int64_t* pdf_evals = nullptr) {
  const size_t kernels = prefixes.size();
  for (int m : prefixes)
    if (m <= 0) return 0.0;  // an empty kernel: no combination exists
  constexpr size_t kMaxKernels = 64;
  if (kernels > kMaxKernels) throw std::invalid_argument("filtering_sum_of_products: at most 64 kernels");
  int j[kMaxKernels] = {};
  double sum = 0.0;
  int64_t evals = 0;
  do {
    double prod = 1.0;
    for (size_t k = 0; k < kernels; ++k) prod *= static_cast<double>(pdf(k, j[k]));
    evals += static_cast<int64_t>(kernels);
    sum += prod;
  } while (next_filtering_combination(std::span<int>(j, kernels), prefixes));
  if (pdf_evals) *pdf_evals += evals;
  return sum;
}

// The per-sample MMIS weight of an output sample whose own technique is the combination own
// (own[k] = the prefix the sample was conditioned on at kernel k): own_pdf = Π_k p_k(x_k | y_{k,own_k}),
// denominator = classical + Π_k S_k (Eq. 14 reorganised), weight = own_pdf / denominator. A renderer
// splats weight · f_rgb(x̄) / own_pdf, or f_rgb / denominator.
struct FilteringWeight {
  double own_pdf = 0.0;
  double denominator = 0.0;
  double weight = 0.0;     // 0 when the denominator is 0
  int64_t pdf_evals = 0;   // Σ_k m_k
  double contribution(double f) const { return safe_ratio(f, denominator); }
};

// Eq. 14 reorganised as a product of sums: every p_k(x_k | y_{k,j}) is evaluated once, the sample's own
// factors are picked out of the same evaluations (no extra call). classical = Σ_c n_c p_c(x̄) of the
// classical techniques in use (0 without). own = {} (or an own[k] outside [0, m_k)) gives own_pdf 0: a
// sample that is not one of the combinations, e.g. the classical one, whose own density the caller has.
template <class Pdf>
FilteringWeight filtering_mmis_weight(std::span<const int> prefixes, std::span<const int> own, const Pdf& pdf,
                                      double classical = 0.0) {
  if (!own.empty() && own.size() != prefixes.size())
    throw std::invalid_argument("filtering_mmis_weight: one own prefix per kernel");
  FilteringWeight w;
  double product = 1.0, own_pdf = own.empty() ? 0.0 : 1.0;
  for (size_t k = 0; k < prefixes.size(); ++k) {
    double s = 0.0, own_term = 0.0;
    const int own_j = own.empty() ? -1 : own[k];
    for (int j = 0; j < prefixes[k]; ++j) {
      const double v = static_cast<double>(pdf(k, j));
      if (j == own_j) own_term = v;
      s += v;
    }
    w.pdf_evals += prefixes[k];
    product *= s;   // S_k
    own_pdf *= own_term;
  }
  w.own_pdf = own_pdf;
  w.denominator = classical + product;  // Sec. 3.1 split + Eq. 14 as a product of sums
  w.weight = safe_ratio(w.own_pdf, w.denominator);
  return w;
}

// The product of sums alone, Π_k S_k (Σ_k m_k evaluations, added to *pdf_evals when given).
template <class Pdf>
double filtering_product_of_sums(std::span<const int> prefixes, const Pdf& pdf, int64_t* pdf_evals = nullptr) {
  const FilteringWeight w = filtering_mmis_weight(prefixes, std::span<const int>{}, pdf);
  if (pdf_evals) *pdf_evals += w.pdf_evals;
  return w.denominator;
}

}  // namespace tb
