// The manifold perturbation of manifold exploration (Jakob and Marschner 2012, "Manifold
// Exploration", Sec. 5; the comparison of Kaplanyan, Hanika, Dachsbacher 2014, Sec. 2, 5.1) on the
// path-space MLT state (path_state.h), registered as "manifold" (path_mutations.cpp) outside the
// default mixture; integrator "memlt" (bidirectional + manifold perturbation).
//
// Paths it acts on: x = x_0 (emitter) .. x_k (pinhole camera) with
//   x_k camera, x_{k-1} .. x_{j+1} specular (Dirac, lib/path/dirac.h; possibly none),
//   x_j non-specular surface (the first one from the camera: the lens perturbation's y_j),
//   x_{j-1} .. x_{c+1} specular (at least one: the chain Veach's lens perturbation cannot join),
//   x_c the next non-specular vertex (a surface, or the emitter x_0; kept fixed).
// One proposal:
//  1. lens part (LensPerturbation::trace): the raster position moves by Veach's annulus kernel
//     K(d), the camera ray is traced through x's camera-side specular chain (lobes kept) to a new
//     non-specular y_j;
//  2. manifold part: the chain y_{c+1} .. y_{j-1} between the fixed x_c and the new y_j is the
//     solution of its specular constraints h_i^perp = 0 (Kaplanyan 2014, Sec. 4.4) found by the
//     predictor-corrector walk of hslt_walk.h (endpoints x_c and y_j fixed, start = x's chain,
//     visibility on, projection side by the Table 2 heuristic);
//  3. reverse check: the same walk from y's chain with the endpoint moved back to x_j must return
//     to x's chain (vertices within kLandingTolerance); otherwise the proposal is rejected.
//
// Density in the path measure (engine convention of dirac.h: the delta of every specular vertex
// dropped, in the solid angle of the direction towards the light given the one towards the
// camera). Let S(y) = (x_c, y_{c+1} .. y_{j-1}, y_j), J_S its square Eq. 11 Jacobian
// dH^perp / d(y_{c+1} .. y_{j-1}) at fixed x_c, y_j in area measure (block LU, hslt_block_lu.h):
//   T(x -> y) = K(r(y) - r(x)) P pE_y(k-1) prod_{i=j+1}^{k-1} |cos y_{i-1}| / |y_i - y_{i-1}|^2   (lens part)
//             * |det J_S(y)| prod_{i=c+1}^{j-1} 1 / (|dh_i / d omega_prev| |<h_i, n_i>|)         (generalised geometry term)
//             * [walk from (x's chain, y_j) lands at y] * [walk from (y's chain, x_j) lands at x].
// The first line is the area density of y_j (lens_perturbation.h). Given y_j the chain is the
// walk's deterministic solution: its area density is delta(y_S - W) = |det J_S| delta^2(H^perp_S)
// (change of variables H^perp_S <-> y_S at fixed endpoints), and each delta^2(h_i^perp) is the
// engine's solid-angle delta divided by |d h_i^perp / d omega_prev| = |dh/d omega_prev| |<h, n>|
// (App. A; Eq. 10 with the other direction fixed): HsltMutation::measure_factor with every
// interior vertex Dirac. Both indicators are deterministic functions of the pair, so T(y -> x)
// has the same pair of them and the Metropolis-Hastings ratio is exact. See docs/hslt.md,
// "Manifold exploration (memlt)", for what differs from Jakob and Marschner.
#pragma once

#include <memory>
#include <optional>

#include "lib/core/uniforms.h"
#include "lib/mcmc/path_space/hslt_mutation.h"
#include "lib/mcmc/path_space/lens_perturbation.h"
#include "lib/mcmc/path_space/path_state.h"

namespace tb::path_space {

class ManifoldPerturbation {
 public:
  using State = MltPath;
  static constexpr double kLandingTolerance = HsltMutation::kLandingTolerance;

  // r1, r2: the lens kernel's radii in pixels (r2 <= 0: 10% of the larger image side).
  explicit ManifoldPerturbation(const PathContext& ctx, std::shared_ptr<HsltCounters> counters = nullptr,
                                double r1 = 0.1, double r2 = 0.0);

  std::optional<MltPath> propose(const MltPath& x, Uniforms& u) const;
  double density(const MltPath& x, const MltPath& y) const;
  bool applicable(const MltPath& x) const;

  // --- The parts (checks, negative controls in validate/) ------------------------------------
  int chain_end(const MltPath& x) const { return lens_.chain_end(x); }  // j
  int chain_start(const MltPath& x) const;                               // c (-1 if none)
  // The subpath x_c .. x_j, with x_j replaced by `end` when given.
  MltPath subpath(const MltPath& x, const PathVertex* end = nullptr) const;
  // The walk from the chain of `from` with the end vertex of `to` towards h^perp = 0: y's chain
  // when it converges (nothing otherwise); *iterations receives the walk's iteration count.
  struct WalkOutcome {
    HsltWalkResult walk;
    std::optional<MltPath> path;  // `to` with the chain y_{c+1} .. y_{j-1} of the walk
  };
  WalkOutcome solve_chain(const MltPath& from, const MltPath& to) const;
  // Does the walk from (chain of `from`, end vertex of `to`) land at `to`'s chain?
  bool lands(const MltPath& from, const MltPath& to) const;
  struct DensityParts {
    bool structure = false;      // both applicable, same c, j, lobes, kept vertices
    double lens = 0;             // K(r(y) - r(x)) times the raster Jacobian of y
    double geometry = 0;         // |det J_S(y)| times the Dirac factors
    bool forward_lands = false;
    bool reverse_lands = false;
  };
  DensityParts density_parts(const MltPath& x, const MltPath& y) const;
  // |det J_S| prod 1 / (|dh/d omega_prev| |<h, n>|) of the chain of x (0 when the block LU fails).
  double geometry_term(const MltPath& x) const;

  const LensPerturbation& lens() const { return lens_; }
  const HsltMutation& hslt() const { return hslt_; }
  const std::shared_ptr<HsltCounters>& counters() const { return counters_; }
  const PathContext& context() const { return *ctx_; }

 private:
  const PathContext* ctx_;
  std::shared_ptr<HsltCounters> counters_;
  LensPerturbation lens_;
  HsltMutation hslt_;  // its hslt_path, walk, path_at and measure_factor
};

bool manifold_applies(const ManifoldPerturbation& m, const MltPath& x);

// The mixture of the integrator "memlt": the bidirectional mutation and the manifold perturbation
// with their registered default weights (c_j(x) normalised over the mutations that apply to x).
// r2: the lens kernel's outer radius in pixels (<= 0: 10% of the larger image side).
PathMutationList make_memlt_mixture(const PathContext& ctx, const PathMutationSettings& s,
                                    const std::shared_ptr<HsltCounters>& counters, double r2 = 0.0);

}  // namespace tb::path_space

namespace tb {
// The renderer entry point for the integrator registry (name "memlt"): run_mlt over
// make_memlt_mixture; prints the Table 3 statistics of Kaplanyan 2014 for the manifold walks as
// render_hslt does. RenderSettings::params: "r2" (the lens kernel's outer radius in pixels,
// default 10% of the larger image side).
int64_t render_memlt(const World& world, const RenderSettings& settings, Film& film);
}  // namespace tb
