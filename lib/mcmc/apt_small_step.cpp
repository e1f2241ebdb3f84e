#include "lib/mcmc/apt_small_step.h"

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "lib/core/spectrum.h"
#include "lib/differential/variance_bound.h"
#include "lib/mcmc/pss/pss_state.h"

namespace tb::mcmc {

namespace {
double wrap01(double v) {
  v -= std::floor(v);
  return v >= 1.0 ? std::nextafter(1.0, 0.0) : v;
}
}  // namespace

AptTarget::AptTarget(const World& world, int k)
    : world_(&world),
      k_(k),
      width_(static_cast<double>(world.camera().width())),
      height_(static_cast<double>(world.camera().height())) {
  if (k < 1) throw std::invalid_argument("AptTarget: k >= 1 vertices (x_k on an emitter)");
}

Vec2 AptTarget::raster(const State& x) const { return Vec2(x[0] * width_, x[1] * height_); }

std::optional<differential::ForwardPath> AptTarget::trace(const State& x) const { return trace_impl(x, false); }

std::optional<differential::ForwardPath> AptTarget::trace_prefix(const State& x) const { return trace_impl(x, true); }

std::optional<differential::ForwardPath> AptTarget::trace_impl(const State& x, bool prefix) const {
  if (x.size() != dimension()) throw std::invalid_argument("AptTarget: state of 3k - 1 coordinates");
  Eigen::VectorXd U(2 * k_);
  std::vector<double> lobe(static_cast<size_t>(k_ - 1));
  const Vec2 r = raster(x);
  U[0] = r.x;
  U[1] = r.y;
  for (int j = 1; j < k_; ++j) {
    const size_t o = 2 + 3 * static_cast<size_t>(j - 1);
    U[2 * j] = x[o];
    U[2 * j + 1] = x[o + 1];
    lobe[static_cast<size_t>(j - 1)] = x[o + 2];
  }
  return prefix ? differential::trace_forward_prefix(*world_, Vec2(0.0), U, k_, lobe)
                : differential::trace_forward(*world_, Vec2(0.0), U, k_, lobe);
}

Rgb AptTarget::contribution(const World& world, const differential::ForwardPath& path, int k) {
  if (k < 1 || static_cast<int>(path.vertices.size()) < k) return Rgb(0.0);
  const Hit& last = path.vertices[static_cast<size_t>(k - 1)];
  const AreaLight* em = world.surface(last.shape_id).emitter;
  if (!em) return Rgb(0.0);
  const Vec3 wi = k == 1 ? path.camera_dir : path.wi[static_cast<size_t>(k - 2)];  // towards x_k
  Rgb t = em->le(last.n, -wi);
  for (int j = 0; j + 1 < k; ++j) t = t * path.weight[static_cast<size_t>(j)];
  const double v = luminance(t);
  return v > 0.0 && std::isfinite(v) ? t : Rgb(0.0);
}

double AptTarget::density(const State& x) const { return luminance(value(x)); }

Rgb AptTarget::value(const State& x) const {
  const auto path = trace(x);
  return path ? contribution(*world_, *path, k_) : Rgb(0.0);
}

AptScales AptTarget::scales(const State& x) const {
  AptScales s;
  const size_t groups = static_cast<size_t>(k_);
  s.footprint.assign(groups, 0.0);
  std::vector<bool> active(groups, false);
  const auto path = trace(x);
  if (path && k_ == 1) {  // the film group alone: A_0 = 1 / R (Listing 1 with n = 1)
    s.traced = true;
    s.footprint[0] = 1.0;
    active[0] = true;
    s.kkt = kkt_amplifiers(s.footprint, active, 1.0 / std::sqrt(width_ * height_));
  } else if (path) {
    s.traced = true;
    // Eq. 21's terms t_j = p_pixel(i_1) / (p(i_j) |di_j/di_1|) (0 for Dirac lobes, which stay
    // inactive, Listing 1 line 14); in camera-footprint units F_j = t_j / P (the camera's p(i_1)
    // over the whole image is p_pixel / P). Listing 1 lines 1-11.
    const auto ratio = differential::variance_ratio_derivative_free(*world_, *path);
    const double P = width_ * height_;
    s.footprint[0] = 1.0;
    active[0] = true;
    for (size_t j = 1; j < groups; ++j) {
      const double t = ratio.terms[j - 1];
      s.footprint[j] = t / P;
      active[j] = t > 0.0 && std::isfinite(t);
    }
    s.kkt = kkt_amplifiers(s.footprint, active, 1.0 / std::sqrt(P));  // R = 1 / sqrt(P), line 13
  } else {
    s.kkt.amplifier.assign(groups, 1.0);
    s.kkt.active = active;
  }
  s.sigma.resize(groups);
  for (size_t j = 0; j < groups; ++j) s.sigma[j] = 1.0 / std::sqrt(2.0 * std::numbers::pi * s.kkt.amplifier[j]);
  return s;
}

double AptSmallStep::factor(const AptScales& s, size_t i, double d) {
  return pss::wrapped_normal_pdf(d, s.sigma[static_cast<size_t>(AptTarget::group(i))]);
}

std::optional<AptState> AptSmallStep::propose(const State& x, Uniforms& u) const {
  return propose(x, target_->scales(x), u);
}

AptState AptSmallStep::propose(const State& x, const AptScales& s, Uniforms& u) const {
  State y(x.size());
  for (size_t i = 0; i < x.size(); ++i) {
    // Box-Muller: z = sqrt(-2 ln(1 - u1)) cos(2 pi u2) is N(0, 1) for independent uniforms.
    const double u1 = u.next(), u2 = u.next();
    const double z = std::sqrt(-2.0 * std::log1p(-u1)) * std::cos(2.0 * std::numbers::pi * u2);
    y[i] = wrap01(x[i] + s.sigma[static_cast<size_t>(AptTarget::group(i))] * z);
  }
  return y;
}

double AptSmallStep::log_density(const State& x, const State& y, const AptScales& sx) const {
  double l = 0.0;
  for (size_t i = 0; i < x.size(); ++i) l += std::log(factor(sx, i, y[i] - x[i]));
  return l;
}

double AptSmallStep::density(const State& x, const State& y) const {
  return std::exp(log_density(x, y, target_->scales(x)));
}

}  // namespace tb::mcmc
