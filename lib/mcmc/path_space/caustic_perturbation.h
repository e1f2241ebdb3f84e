// Veach's caustic perturbation (Veach 1997, Sec. 11.4.4; Veach & Guibas 1997, Sec. 5.3.2), the
// light-side analogue of the lens perturbation, for caustic paths (L|D)S*DE: x_{k-1} non-specular,
// x_{k-2} .. x_{j+1} specular (Dirac vertices, lib/path/dirac.h), x_j non-specular (or the
// emitter). The direction of the segment x_j -> x_{j+1} is perturbed by an angular kernel about its
// current direction, the ray is traced from x_j through the specular chain (each vertex with the
// lobe it has in x) to a new x'_{k-1}, which is joined to the kept camera vertex x_k (the image
// position moves). The move fails when the chain changes (a vertex not specular, the other lobe,
// or y_{k-1} specular).
//
// Apex: directions are taken from the ray origin o that spawn_ray gives at x_j on the side of
// x_{j+1} (the point offset off the surface by its error bound), not from x_j itself: the ray is
// traced from o, so the realised direction o -> y_{j+1} is the sampled one. (From x_j the offset,
// ~1e-6, shifts angles of theta1 = 1e-4 by percents, which the chi-square of the angle projection
// detects.) o depends on the side only, which the move keeps (moves through the surface at x_j
// fail), so it is the same for x and y.
// Kernel: angle theta from the old direction with theta = theta2 exp(-ln(theta2 / theta1) u1)
// (theta1 = 1e-4, theta2 = 0.1 rad, Veach's values), azimuth phi = 2 pi u2 about the old direction;
// density in solid angle K(theta) = 1 / (2 pi sin(theta) theta ln(theta2 / theta1)) on
// [theta1, theta2]: a function of the angle between old and new directions only, so symmetric.
// Density in the path measure (area at y_{j+1}, then the pseudo densities of dirac.h with the lobe
// kept, importance mode, for the vertices after each specular one):
//   T(x -> y) = K(theta) |cos theta_{y_{j+1}}| / |o - y_{j+1}|^2            (Veach 1997, Eq. 8.10)
//               * prod_{i=j+1}^{k-2} pdf_next_dirac(y_{i-1}, y_i -> y_{i+1}, kept lobe),
// and the ratio T(y -> x) / T(x -> y) is the ratio of these solid-angle-to-path-measure factors.
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

  // k >= 2, x_{k-1} a non-Dirac surface, x_j (the last non-Dirac vertex before it) can scatter or
  // emit without a Dirac lobe.
  bool applicable(const MltPath& x) const;
  // j: the last non-Dirac vertex before x_{k-1} (-1 if none), and j + 1, the first vertex moved.
  int chain_start(const MltPath& x) const;
  int perturbed_index(const MltPath& x) const { return chain_start(x) + 1; }
  // y with the direction at x_j rotated by (theta, phi) in the frame Frame::from_z(old dir).
  std::optional<MltPath> perturb(const MltPath& x, double theta, double phi) const;
  double kernel_density(double theta) const;  // per solid angle
  // The angle between the directions o -> x_{j+1} and o -> y_{j+1}.
  double angle(const MltPath& x, const MltPath& y) const;
  // |cos| / d^2 at x_{j+1} seen from o, times the chain's pseudo densities: T = K(theta) area_factor(y).
  double area_factor(const MltPath& x) const;
  // The apex o: spawn_ray's origin at x_j towards x_{j+1}.
  Vec3 apex(const MltPath& x) const;
  // Is p on the side of the surface at x_j that x_{j+1} is on?
  bool same_side(const MltPath& x, const Vec3& p) const;
  double theta1() const { return theta1_; }
  const PathContext& context() const { return *ctx_; }
  double theta2() const { return theta2_; }

 private:
  const PathContext* ctx_;
  double theta1_, theta2_;
};

}  // namespace tb::path_space
