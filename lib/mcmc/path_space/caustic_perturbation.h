// Veach's caustic perturbation (Veach 1997, Sec. 11.4.4; Veach & Guibas 1997, Sec. 5.3.2), the
// light-side analogue of the lens perturbation: the direction of the segment x_{k-2} -> x_{k-1}
// is perturbed by an angular kernel about its current direction, the ray from x_{k-2} gives a
// new x'_{k-1}, which is joined to the kept camera vertex x_k (the image position moves). With
// the specular chains of the shared representation empty (path_state.h), Veach's "caustic
// subpath" is the last segment before the camera segment.
//
// Apex: directions are taken from the ray origin o that spawn_ray gives at x_{k-2} on the side of
// x_{k-1} (the point offset off the surface by its error bound), not from x_{k-2} itself: the
// ray is traced from o, so the realised direction o -> y_{k-1} is the sampled one. (From x_{k-2}
// the offset, ~1e-6, shifts angles of theta1 = 1e-4 by percents, which the chi-square of the
// angle projection detects.) o depends on the side only, which the move keeps (moves through
// the surface at x_{k-2} fail), so it is the same for x and y.
// Kernel: angle theta from the old direction with theta = theta2 exp(-ln(theta2 / theta1) u1)
// (theta1 = 1e-4, theta2 = 0.1 rad, Veach's values), azimuth phi = 2 pi u2 about the old direction;
// density in solid angle K(theta) = 1 / (2 pi sin(theta) theta ln(theta2 / theta1)) on
// [theta1, theta2]: a function of the angle between old and new directions only, so symmetric.
// Density in the path measure (area at y_{k-1}):
//   T(x -> y) = K(theta) |cos theta_{y_{k-1}}| / |o - y_{k-1}|^2   (Veach 1997, Eq. 8.10),
// and the ratio T(y -> x) / T(x -> y) is the ratio of the solid-angle-to-area factors.
// The multi-chain perturbation (lens perturbation continued through several specular chains)
// reduces to the lens perturbation on paths without specular vertices and is not separate here.
#pragma once

#include <optional>

#include "lib/core/uniforms.h"
#include "lib/mcmc/path_space/path_state.h"

namespace tb::path_space {

class CausticPerturbation {
 public:
  using State = MltPath;
  CausticPerturbation(const PathContext& ctx, double theta1 = 1e-4, double theta2 = 0.1)
      : ctx_(&ctx), theta1_(theta1), theta2_(theta2) {}

  std::optional<MltPath> propose(const MltPath& x, Uniforms& u) const;
  double density(const MltPath& x, const MltPath& y) const;

  // k >= 2, x_{k-2} can scatter (or emit) without a Dirac lobe, x_{k-1} a non-Dirac surface.
  bool applicable(const MltPath& x) const;
  // y with the direction at x_{k-2} rotated by (theta, phi) in the frame Frame::from_z(old dir).
  std::optional<MltPath> perturb(const MltPath& x, double theta, double phi) const;
  double kernel_density(double theta) const;  // per solid angle
  // The angle between the directions o -> x_{k-1} and o -> y_{k-1}.
  double angle(const MltPath& x, const MltPath& y) const;
  // |cos| / d^2 at x_{k-1} seen from o.
  double area_factor(const MltPath& x) const;
  // The apex o: spawn_ray's origin at x_{k-2} towards x_{k-1}.
  Vec3 apex(const MltPath& x) const;
  // Is p on the side of the surface at x_{k-2} that x_{k-1} is on?
  bool same_side(const MltPath& x, const Vec3& p) const;
  double theta1() const { return theta1_; }
  double theta2() const { return theta2_; }

 private:
  const PathContext* ctx_;
  double theta1_, theta2_;
};

}  // namespace tb::path_space
