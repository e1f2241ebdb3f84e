#include "lib/mcmc/pss/pss_kernel.h"

#include <bit>

namespace tb::pss {

DenseEvaluation evaluate_dense(const SampleFunction& f, int level, const DenseState& x, const SplatTarget& pi) {
  thread_local std::vector<Splat> sp;
  sp.clear();
  DenseStreams u(x);
  f.sample(level, u, &sp);
  const double i = pi ? pi(sp) : target_value(sp);
  return {std::isfinite(i) && i > 0.0 ? i : 0.0, u.reads()};
}

PssKernel::PssKernel(SampleFunction f, int level, PssMutationList mutations, double sigma0, double y_ref,
                     SplatTarget pi)
    : target_(std::move(f), level, std::move(pi)), m_(std::move(mutations)), sigma0_(sigma0), y_ref_(y_ref) {}

namespace {

// Evaluates the sample function on the lazy state (as the renderer does); returns I.
double evaluate_lazy(const PssTarget& t, PssState& s) {
  thread_local std::vector<Splat> sp;
  sp.clear();
  s.restart();
  t.function().sample(t.level(), s, &sp);
  const double i = t.splat_target() ? t.splat_target()(sp) : target_value(sp);
  return std::isfinite(i) && i > 0.0 ? i : 0.0;
}

}  // namespace

std::optional<DenseState> PssKernel::propose(int k, const State& x, Uniforms& u) const {
  const PssMutation& mut = mutation(k);
  // The lazy state's fresh numbers come from a generator seeded by two of the proposal's uniforms.
  const uint64_t a = std::bit_cast<uint64_t>(u.next()), b = std::bit_cast<uint64_t>(u.next());
  PssState s = PssState::at(x, Rng::for_sample(a, b, 0), sigma0_);
  const double pi_x = evaluate_lazy(target_, s);
  s.commit_reads();  // D(x)
  mut.begin(s, mut.scale(pi_x, y_ref_));
  evaluate_lazy(target_, s);  // y reads D(y) in order, as in the renderer
  // Coordinates y did not read: moved as the lazy state moves them when next read (sigma0, or a
  // fresh uniform after a large step), never by a rescaled step's sigma(x).
  s.set_rescaled(false);
  for (int st = 0; st < kStreams; ++st) {
    s.use_stream(st);
    while (s.reads()[static_cast<size_t>(st)] * kStreams + static_cast<size_t>(st) < x.size()) s.next();
  }
  if (s.coordinates() > x.size())
    throw std::out_of_range("PssKernel: the sample function read beyond the state's dimension");
  DenseState y(x.size());
  for (size_t i = 0; i < x.size(); ++i) y[i] = s.stored(i);
  return y;
}

DenseMove PssKernel::move(int k, const State& x, const State& y, double* pi_x, double* pi_y) const {
  const DenseEvaluation ex = target_.evaluate(x), ey = target_.evaluate(y);
  if (pi_x) *pi_x = ex.value;
  if (pi_y) *pi_y = ey.value;
  DenseMove m(x, y);
  m.reads_x = ex.reads;
  m.reads_y = ey.reads;
  m.sigma_x = mutation(k).scale(ex.value, y_ref_);
  m.sigma_y = mutation(k).scale(ey.value, y_ref_);
  return m;
}

double PssKernel::density(int k, const State& x, const State& y) const {
  constexpr double kLogFlush = -667.7;      // log(1e-290)
  constexpr double kLogRatioFlush = 690.7;  // -log(1e-300)
  double px = 0.0, py = 0.0;
  const DenseMove m = move(k, x, y, &px, &py);
  const double lf = mutation(k).log_density(x, y, m);
  if (!(lf >= kLogFlush)) return 0.0;
  if (px > 0.0 && py > 0.0) {
    DenseMove back(y, x);
    back.reads_x = m.reads_y;
    back.reads_y = m.reads_x;
    back.sigma_x = m.sigma_y;
    back.sigma_y = m.sigma_x;
    const double log_ratio = std::log(py) + mutation(k).log_density(y, x, back) - std::log(px) - lf;
    if (std::abs(log_ratio) > kLogRatioFlush) return 0.0;
  }
  return std::exp(lf);
}

std::optional<PssKernel::Move> PssKernel::sample_move(const State& x, Uniforms& u) const {
  const int k = select_mutation(m_, u.next());
  if (k < 0) return std::nullopt;
  std::optional<State> y = propose(k, x, u);
  if (!y) return std::nullopt;
  return Move{k, std::move(*y)};
}

double PssKernel::move_density(const State& x, const Move& m) const {
  return selection_probability(m_, m.component) * density(m.component, x, m.y);
}

mcmc::MoveTerms PssKernel::move_terms(const State& x, const Move& m) const {
  double px = 0.0, py = 0.0;
  const DenseMove mv = move(m.component, x, m.y, &px, &py);
  return pss_move_terms(mutation(m.component), selection_probability(m_, m.component), px, py, mv);
}

}  // namespace tb::pss
