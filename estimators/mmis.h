// Marginal multiple importance sampling (West et al. 2022, Eq. 6), with classical techniques mixed in
// by splitting the balance-heuristic denominator into a classical and a marginal sum (Sec. 3.1):
//   <I> = Σ_{samples x} f(x) / [ Σ_c n_c p_c(x) + Σ_m Σ_{j'} p_m(x | t_{m,j'}) ],
// where n_c samples come from classical technique c and n_m technique-sample pairs (t, x) from
// marginal technique m. Classical techniques can also be extruded into marginal ones
// (extruded_technique.h): the two forms agree exactly in expectation and to round-off per draw.
// Unbiased as long as for every x with f(x) ≠ 0 some classical technique or sampled conditional
// technique has positive density (West et al. 2022, below Eq. 6). A count of 0 leaves a technique
// out, which is how a random subset of techniques is used (technique_subset.h).
// Cost: S·(C + P) pdf evaluations for S samples, C classical techniques in use and P sampled
// auxiliaries: with n pairs from each of T marginal techniques, (nT)² per realisation.
//
// Three layers, each used by the next: draw_mmis draws the pairs; mmis_weight gives one drawn sample's
// MMIS weight with its own technique, for_each_mmis_weight every sample's (mmis_weights collects them),
// e.g. for a renderer that splats RGB contributions; evaluate_mmis sums f(x) / D(x) over the same
// weights, so the scalar estimate of the analytic checks and the per-sample weights of a renderer come
// from one function.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <stdexcept>
#include <utility>
#include <vector>

#include "estimators/concepts.h"
#include "estimators/estimate.h"

namespace tb {

// A marginal technique with the number of technique-sample pairs n_i drawn from it.
template <class M>
struct MarginalGroup {
  std::span<const M> techniques;
  std::span<const int> counts;
};

// The technique-sample pairs of one MMIS realisation: classical samples first (technique by
// technique, classical_counts[c] each), then the marginal (t, x) pairs; xs[classical_samples + k]
// is the sample drawn from aux[k]. Drawing them and evaluating Eq. 6 over them are separate steps
// so that the evaluation (n·N·T conditional pdf evaluations) can be timed on its own. A draw can
// be refilled (draw_mmis_into) without allocating once its vectors have grown.
template <class X, class Aux>
struct MmisDraw {
  struct Pair {
    size_t technique;
    Aux t;
  };
  std::vector<Pair> aux;
  std::vector<std::optional<X>> xs;
  int64_t samples = 0, failed = 0;
  size_t classical_samples() const { return xs.size() - aux.size(); }
  void clear() {
    aux.clear();
    xs.clear();
    samples = failed = 0;
  }
};

template <Technique C, MarginalTechnique M>
  requires std::same_as<typename C::Sample, typename M::Sample>
void draw_mmis_into(MmisDraw<typename M::Sample, typename M::Aux>& d, std::span<const C> classical,
                    std::span<const int> classical_counts, std::span<const M> marginal,
                    std::span<const int> marginal_counts, Uniforms& u) {
  if (classical.size() != classical_counts.size() || marginal.size() != marginal_counts.size())
    throw std::invalid_argument("estimate_mmis: one count per technique");
  d.clear();
  // The order of uniforms is part of the estimator's definition (fixed so runs are reproducible).
  for (size_t c = 0; c < classical.size(); ++c)
    for (int j = 0; j < classical_counts[c]; ++j) {
      ++d.samples;
      d.xs.push_back(classical[c].sample(u));
      if (!d.xs.back()) ++d.failed;
    }
  for (size_t m = 0; m < marginal.size(); ++m)
    for (int j = 0; j < marginal_counts[m]; ++j) {
      ++d.samples;
      auto t = marginal[m].sample_aux(u);
      if (!t) {  // a failed t is a conditional technique of zero probability: it drops out everywhere
        ++d.failed;
        continue;
      }
      d.xs.push_back(marginal[m].sample(*t, u));
      if (!d.xs.back()) ++d.failed;
      d.aux.push_back({m, std::move(*t)});
    }
}

template <Technique C, MarginalTechnique M>
  requires std::same_as<typename C::Sample, typename M::Sample>
MmisDraw<typename M::Sample, typename M::Aux> draw_mmis(std::span<const C> classical,
                                                       std::span<const int> classical_counts,
                                                       std::span<const M> marginal,
                                                       std::span<const int> marginal_counts, Uniforms& u) {
  MmisDraw<typename M::Sample, typename M::Aux> d;
  draw_mmis_into(d, classical, classical_counts, marginal, marginal_counts, u);
  return d;
}

// The MMIS weight of one drawn sample x (West et al. 2022, Eq. 6):
//   denominator D(x) = Σ_c n_c p_c(x) + Σ_(i,j) p_i(x | t_ij)   (the Eq. 6 denominator)
//   own_pdf          = n_c p_c(x) for a sample of classical technique c (Sec. 3.1, split form),
//                      p_i(x | t_ij) for the sample of the pair (i, j)
//   weight           = own_pdf / D(x), the balance weight of the sample's own technique
// so that the sample's term of Eq. 6 is contribution(f(x)) = f(x) / D(x) = weight · f(x) / own_pdf.
// A renderer multiplies its (RGB) path throughput f(x) / own_pdf by weight, or divides f by D.
struct MmisWeight {
  size_t sample = 0;       // index into MmisDraw::xs
  size_t technique = 0;    // index into the classical (classical == true) or the marginal techniques
  bool classical = false;
  double own_pdf = 0.0;
  double denominator = 0.0;
  double weight = 0.0;     // 0 when D(x) = 0
  // f / D(x) with 0 / 0 = 0.
  double contribution(double f) const { return safe_ratio(f, denominator); }
};

// The auxiliary t of a weighted sample's own conditional technique (e.g. the prefix a filtered path was
// conditioned on), nullptr for a sample of a classical technique.
template <class X, class Aux>
const Aux* mmis_own_aux(const MmisDraw<X, Aux>& d, const MmisWeight& w) {
  return w.classical ? nullptr : &d.aux[w.sample - d.classical_samples()].t;
}

template <class X>
struct MmisWeightedSample {
  X x;
  MmisWeight w;
};

// pdf evaluations per drawn sample (Sec. 3.2 cost model): every classical technique in use and every
// sampled conditional technique.
template <class X, class Aux>
int64_t mmis_pdf_evals_per_sample(std::span<const int> classical_counts, const MmisDraw<X, Aux>& d) {
  int64_t c = 0;
  for (int n : classical_counts) c += n > 0;
  return c + static_cast<int64_t>(d.aux.size());
}

namespace mmis_detail {

// The Eq. 6 denominator of one draw at a sample x: Σ_c n_c p_c(x) (the split classical sum), then
// Σ_(i,j) p_i(x | t_ij) in pair order, whatever the sample's own technique (the same order, so the same
// round-off, for every sample). The sample's own term is one of the summands: each sum runs in two
// branch-free halves around it, so it is evaluated once, picked out without a per-term test and added in
// its place. Nothing is allocated; the only calls are to the techniques' pdfs.
template <class C, class M>
struct Eq6Denominator {
  using X = typename M::Sample;
  std::span<const C> classical;
  std::span<const int> classical_counts;
  const M* mar;
  const typename MmisDraw<X, typename M::Aux>::Pair* aux;
  size_t np;

  double classical_range(const X& x, size_t begin, size_t end, double den) const {
    for (size_t c = begin; c < end; ++c)
      if (classical_counts[c] > 0) den += classical_counts[c] * static_cast<double>(classical[c].pdf(x));
    return den;
  }
  double marginal_range(const X& x, size_t begin, size_t end, double den) const {
    for (size_t k = begin; k < end; ++k) den += static_cast<double>(mar[aux[k].technique].pdf(x, aux[k].t));
    return den;
  }
  // Sample s of classical technique c (classical_counts[c] > 0, so its term is a summand).
  MmisWeight of_classical(const X& x, size_t s, size_t c) const {
    MmisWeight w;
    w.sample = s;
    w.technique = c;
    w.classical = true;
    const double before = classical_range(x, 0, c, 0.0);
    w.own_pdf = classical_counts[c] * static_cast<double>(classical[c].pdf(x));
    w.denominator = marginal_range(x, 0, np, classical_range(x, c + 1, classical.size(), before + w.own_pdf));
    w.weight = safe_ratio(w.own_pdf, w.denominator);
    return w;
  }
  // Sample s drawn from pair k, its own conditional technique p_i(x | t_ij).
  MmisWeight of_pair(const X& x, size_t s, size_t k) const {
    MmisWeight w;
    w.sample = s;
    w.technique = aux[k].technique;
    const double before = marginal_range(x, 0, k, classical_range(x, 0, classical.size(), 0.0));
    w.own_pdf = static_cast<double>(mar[aux[k].technique].pdf(x, aux[k].t));
    w.denominator = marginal_range(x, k + 1, np, before + w.own_pdf);
    w.weight = safe_ratio(w.own_pdf, w.denominator);
    return w;
  }
};

template <class C, class M>
Eq6Denominator<C, M> eq6_denominator(std::span<const C> classical, std::span<const int> classical_counts,
                                     std::span<const M> marginal, const MmisDraw<typename M::Sample, typename M::Aux>& d) {
  return {classical, classical_counts, marginal.data(), d.aux.data(), d.aux.size()};
}

}  // namespace mmis_detail

// The MMIS weight of one drawn sample, d.xs[s] (West et al. 2022, Eq. 6), with its own technique (a
// classical technique, or the marginal technique of its pair, whose auxiliary t — e.g. a path prefix — is
// d.aux[s - d.classical_samples()].t); empty when s is out of range or the sample failed. Costs one
// evaluation of every classical technique in use and of every sampled conditional technique.
template <Technique C, MarginalTechnique M>
  requires std::same_as<typename C::Sample, typename M::Sample>
std::optional<MmisWeight> mmis_weight(std::span<const C> classical, std::span<const int> classical_counts,
                                      std::span<const M> marginal,
                                      const MmisDraw<typename M::Sample, typename M::Aux>& d, size_t s) {
  if (s >= d.xs.size() || !d.xs[s]) return std::nullopt;
  const auto den = mmis_detail::eq6_denominator(classical, classical_counts, marginal, d);
  const size_t nc = d.classical_samples();
  if (s >= nc) return den.of_pair(*d.xs[s], s, s - nc);
  size_t first = 0;
  for (size_t c = 0; c < classical.size(); ++c) {
    const size_t n = static_cast<size_t>(classical_counts[c] > 0 ? classical_counts[c] : 0);
    if (s < first + n) return den.of_classical(*d.xs[s], s, c);
    first += n;
  }
  return std::nullopt;
}

// Calls visit(x, MmisWeight) for every drawn sample whose x did not fail, in the order of d.xs; each weight
// is the one mmis_weight gives for that sample (the same code).
template <Technique C, MarginalTechnique M, class Visit>
  requires std::same_as<typename C::Sample, typename M::Sample>
void for_each_mmis_weight(std::span<const C> classical, std::span<const int> classical_counts,
                          std::span<const M> marginal, const MmisDraw<typename M::Sample, typename M::Aux>& d,
                          Visit&& visit) {
  const auto den = mmis_detail::eq6_denominator(classical, classical_counts, marginal, d);
  size_t s = 0;
  for (size_t c = 0; c < classical.size(); ++c)
    for (int j = 0; j < classical_counts[c]; ++j, ++s)
      if (const auto& x = d.xs[s]) visit(*x, den.of_classical(*x, s, c));
  for (size_t k = 0; k < den.np; ++k, ++s)
    if (const auto& x = d.xs[s]) visit(*x, den.of_pair(*x, s, k));
}

// Every drawn sample (failed ones left out) with its MMIS weight.
template <Technique C, MarginalTechnique M>
  requires std::same_as<typename C::Sample, typename M::Sample>
std::vector<MmisWeightedSample<typename M::Sample>> mmis_weights(
    std::span<const C> classical, std::span<const int> classical_counts, std::span<const M> marginal,
    const MmisDraw<typename M::Sample, typename M::Aux>& d) {
  std::vector<MmisWeightedSample<typename M::Sample>> out;
  out.reserve(d.xs.size());
  for_each_mmis_weight(classical, classical_counts, marginal, d,
                       [&](const typename M::Sample& x, const MmisWeight& w) { out.push_back({x, w}); });
  return out;
}

// Eq. 6 (West et al. 2022) over drawn pairs: sum over samples of f(x) / (sum_c n_c p_c(x) +
// sum_(i,j) p_i(x | t_ij)), each term from for_each_mmis_weight.
template <Technique C, MarginalTechnique M, Integrand<typename M::Sample> F>
  requires std::same_as<typename C::Sample, typename M::Sample>
Estimate evaluate_mmis(const F& f, std::span<const C> classical, std::span<const int> classical_counts,
                       std::span<const M> marginal, const MmisDraw<typename M::Sample, typename M::Aux>& d) {
  Estimate e;
  e.samples = d.samples;
  e.failed = d.failed;
  int64_t visited = 0;
  for_each_mmis_weight(classical, classical_counts, marginal, d, [&](const typename M::Sample& x, const MmisWeight& w) {
    ++visited;
    e.add(w.contribution(static_cast<double>(f(x))));
  });
  e.pdf_evals = visited * mmis_pdf_evals_per_sample(classical_counts, d);
  return e;
}

template <Technique C, MarginalTechnique M, Integrand<typename M::Sample> F>
  requires std::same_as<typename C::Sample, typename M::Sample>
Estimate estimate_mmis(const F& f, std::span<const C> classical, std::span<const int> classical_counts,
                       std::span<const M> marginal, std::span<const int> marginal_counts, Uniforms& u) {
  const auto d = draw_mmis(classical, classical_counts, marginal, marginal_counts, u);
  return evaluate_mmis(f, classical, classical_counts, marginal, d);
}

// A classical technique that is never sampled: lets the all-marginal form reuse the general one.
template <class X>
struct NoClassical {
  using Sample = X;
  std::optional<Sample> sample(Uniforms&) const { return std::nullopt; }
  double pdf(const Sample&) const { return 0.0; }
};

// All techniques marginal (classical ones extruded): Eq. 6 as printed.
template <MarginalTechnique M, Integrand<typename M::Sample> F>
Estimate estimate_mmis(const F& f, std::span<const M> marginal, std::span<const int> marginal_counts, Uniforms& u) {
  return estimate_mmis(f, std::span<const NoClassical<typename M::Sample>>{}, std::span<const int>{}, marginal,
                       marginal_counts, u);
}

}  // namespace tb
