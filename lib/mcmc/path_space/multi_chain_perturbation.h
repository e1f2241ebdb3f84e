// Veach's multi-chain perturbation (Veach 1997, Sec. 11.4.3, "multi-chain perturbations"; Veach &
// Guibas 1997, Sec. 5.3.3): the lens perturbation continued through several specular chains, for
// paths (L|D) D S+ D S* E ... whose lens subpath ends at a non-specular x_{j1} followed (towards
// the light) by another specular chain, where the lens perturbation cannot join x_{j1} to x_{j1-1}.
//
// Structure of x read from the camera: x_k, the chain x_{k-1} .. x_{j1+1} (specular, possibly
// empty), x_{j1} non-specular, x_{j1-1} .. x_{j2+1} specular (non-empty), x_{j2} non-specular, ...,
// up to x_{jn} with x_{jn-1} non-specular (joined to the kept x_{jn-1}) or jn = 0 (the emitter).
// Move: the raster offset of the lens perturbation gives y_{k-1} and, through the first chain,
// y_{j1}; at each y_{jm} (m < n) the old direction w_x = x_{jm} -> x_{jm-1} (from the spawn_ray
// apex) is rotated by the angular kernel of the caustic perturbation (theta in [theta1, theta2],
// density K(theta) per solid angle, symmetric) and traced from y_{jm}'s apex through the next
// specular chain (lobes kept) to y_{j(m+1)}. Fails when any chain or lobe changes.
// Density in the path measure (lib/path/dirac.h pseudo densities, radiance mode, lobe kept):
//   T(x -> y) = K_r(r(y) - r(x)) P pE_y(k-1) prod_{chain 1} |cos|/d^2
//               * prod_{m=1}^{n-1} K(theta_m) |cos y_{jm-1}| / |o_y - y_{jm-1}|^2 prod_{chain m+1} |cos|/d^2,
// theta_m the angle between w_x and w_y at level m (the same in T(y -> x): symmetric kernels).
#pragma once

#include <optional>
#include <vector>

#include "lib/core/uniforms.h"
#include "lib/mcmc/path_space/lens_perturbation.h"

namespace tb::path_space {

// The levels j1 > ... > jn of x (see above), independent of the camera model; empty when the
// multi-chain perturbation cannot act on x. Used by the driver's selection probabilities.
std::vector<int> multi_chain_levels(const MltPath& x);

class MultiChainPerturbation {
 public:
  using State = MltPath;
  MultiChainPerturbation(const PathContext& ctx, double r1 = 0.1, double r2 = 0.0, double theta1 = 1e-4,
                         double theta2 = 0.1)
      : ctx_(&ctx), lens_(ctx, r1, r2), theta1_(theta1), theta2_(theta2) {}

  std::optional<MltPath> propose(const MltPath& x, Uniforms& u) const;
  double density(const MltPath& x, const MltPath& y) const;

  // The non-specular vertices j1 > j2 > ... > jn of the structure above; empty when x has none
  // with a specular chain after x_{j1} (then the lens perturbation applies instead).
  std::vector<int> levels(const MltPath& x) const;
  bool applicable(const MltPath& x) const { return !levels(x).empty(); }
  // y from a raster offset and one (theta, phi) per continued level.
  std::optional<MltPath> perturb(const MltPath& x, const Vec2& offset, const std::vector<Vec2>& theta_phi) const;
  double angular_density(double theta) const;
  const LensPerturbation& lens() const { return lens_; }

 private:
  const PathContext* ctx_;
  LensPerturbation lens_;
  double theta1_, theta2_;
};

// Shared with the regional adaptive multi-chain perturbation (ramlt_perturbations.cpp):
// the direction from the apex at x_i (spawn_ray's origin towards x_{i-1}) to x_{i-1};
Vec3 apex_direction(const MltPath& x, int i);
// traces from y_i (already placed) along w through the specular chain of x below i (lobes kept)
// to the next non-specular index `stop`, filling y_{i-1} .. y_stop; false when the chain changes.
bool trace_chain(const PathContext& ctx, const MltPath& x, MltPath& y, int i, Vec3 w, int stop);

}  // namespace tb::path_space
