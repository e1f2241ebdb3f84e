#include "lib/mcmc/stratified_target.h"

#include <algorithm>
#include <stdexcept>

namespace tb::mcmc {

double bounded_splat(double S, double r, double B) {
  if (!(r >= 1.0) || !(B > 0.0) || !(S >= 0.0)) throw std::invalid_argument("bounded_splat: needs S >= 0, r >= 1, B > 0");
  return std::max(S / r, B);
}

double stratified_target(double f, double p, double r, double B) {
  if (!(f > 0.0)) return 0.0;
  if (!(r >= 1.0) || !(B > 0.0) || !(p > 0.0)) throw std::invalid_argument("stratified_target: needs p > 0, r >= 1, B > 0");
  return std::min(p * r, f / B);  // = f / max{f / (p r), B}
}

double normalisation_sample(double S, double r, double B) {
  if (!(S > 0.0)) return 0.0;
  if (!(r >= 1.0) || !(B > 0.0)) throw std::invalid_argument("normalisation_sample: needs r >= 1, B > 0");
  return std::min(r, S / B);
}

double pilot_brightness(std::span<const double> splats) {
  if (splats.empty()) throw std::invalid_argument("pilot_brightness: no samples");
  double sum = 0.0;
  for (double s : splats) sum += s;
  return sum / static_cast<double>(splats.size());
}

double stratified_acceptance(double w_x, double t_xy, double w_y, double t_yx) {
  const double den = w_x * t_xy;
  if (!(den > 0.0)) return 1.0;
  return std::min(1.0, w_y * t_yx / den);
}

StratifiedSplats stratified_splats(double s_tilde_x, double s_tilde_y, double acceptance) {
  return {s_tilde_y * acceptance, s_tilde_x * (1.0 - acceptance)};
}

}  // namespace tb::mcmc
