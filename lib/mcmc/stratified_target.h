// The stratified MCMC target of Zirr & Dachsbacher 2020, Sec. 4.3 and 6.8: splats of an MC
// estimate S(X) = f(X) / p(X) downweighted by the variance-bounding ratio r~(X) >= 1
// (lib/differential/variance_bound.h, Eq. 20 or 21) and bounded below by the image brightness B,
//   S~(X) = max{ S(X) / r~(X), B },   W~(X) = f(X) / S~(X) = min{ p(X) r~(X), f(X) / B }   (Eq. 8
// and its footnote), with B = the integral of f over path space (the sum of the pixel values I_j
// when the pixel filters sum to one), estimated from a pilot. A Markov chain targeting W~ splats
// S~ instead of the usual b / f (Sec. 6.1), with the acceptance of Eq. 22 and the expected-value
// splats S~(Y) A (proposal) and S~(X) (1 - A) (current). An estimate of pixel j is then
//   I_j = (integral of W~) E_{pi~}[h_j S~],   pi~ = W~ / (integral of W~),
// and the normalisation  integral of W~ = E_p[ min{ r~, S / B } ]  (per sample: W~ / p) is estimated
// from the same MC samples as B. Bounds: integral of W~ <= integral of f / B = 1 and <= E_p[r~].
#pragma once

#include <cstdint>
#include <span>

namespace tb::mcmc {

// Eq. 8: S~ = max{S / r~, B}. S >= 0, r~ >= 1, B > 0.
double bounded_splat(double S, double r, double B);
// Eq. 8: W~ = f / S~ (0 where f = 0), evaluated as min{p r~, f / B} (the footnote's form).
double stratified_target(double f, double p, double r, double B);
// W~ / p = min{r~, S / B}: one sample's estimate of the normalisation (the integral of W~) when
// X ~ p (the footnote's form divided by p).
double normalisation_sample(double S, double r, double B);
// B from a pilot: the mean of S = f / p over samples drawn from p over the whole image.
double pilot_brightness(std::span<const double> splats);

// Eq. 22: A = min{1, W~(Y) T(Y -> X) / (W~(X) T(X -> Y))} with W~ = f / S~ (1 when W~(X) = 0).
double stratified_acceptance(double w_x, double t_xy, double w_y, double t_yx);

// The splats after one proposal (Sec. 6.8): S~(Y) A for the proposal, S~(X) (1 - A) for the
// current state.
struct StratifiedSplats {
  double proposal = 0.0, current = 0.0;
};
StratifiedSplats stratified_splats(double s_tilde_x, double s_tilde_y, double acceptance);

}  // namespace tb::mcmc
