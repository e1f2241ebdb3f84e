// Low-dimensional projections of the path-space proposals with their STATED densities, for the
// chi-square checks of proposal samples (docs/validation.md A, "mutation proposals"; validate/chi2):
//  - BidirWayProjection: one way of the bidirectional mutation at a fixed x with k >= 3 segments
//    (delete x_{k-2}, add one vertex; split s' = 1: sampled from the light side at x_{k-3}, s' = 0:
//    from the camera side at x_{k-1}). Projection: the unit direction from the sampling vertex to
//    the new vertex. Stated density in solid angle: split_density() (area, at the new vertex)
//    times d^2 / |cos theta| (geometric normal) at the first hit along the direction, which is
//    where the sampled vertex lies. A density missing its geometry term is visibly off here.
//  - LensOffsetProjection: the realised raster offset d = r(y) - r(x) of the lens perturbation in
//    polar coordinates (phi, rho = ln |d|), in which Veach's kernel is flat. Stated density:
//    T(x -> y) / |dr / dA(y_{k-1})| (the raster projection of T) times |d|^2, the Jacobian of
//    (phi, rho) -> d. The rho range of the chart extends 0.2 beyond [ln r1, ln r2].
//  - CausticAngleProjection: the realised direction change of the caustic perturbation as
//    (phi, rho = ln theta) in the frame about the old direction; stated density T(x -> y) divided
//    by |cos| / d^2 at y_{k-1} (area to solid angle) times sin(theta) theta (solid angle to
//    (phi, rho)). Chart rho range 0.2 beyond [ln theta1, ln theta2].
//  - BidirVertexProjection: the whole bidirectional mutation seen through its one-vertex way
//    (below).
//  - MultiChainAngleProjection: the direction change at the first continued level given a fixed
//    raster offset (see jacobian()).
//  - RamltLensAngleProjection: the primary ray direction change of the regional adaptive lens
//    perturbation as (phi, theta) about the old direction; stated density T(x -> y) divided by
//    |cos| / d^2 at y_{k-1} (solid angle to area; paths with an empty lens chain, so no specular
//    factor enters) times sin(theta). Chart theta in [0, 0.4] (the registry's sigma = 0.05 rad
//    leaves mass exp(-32) beyond; in theta, not ln theta, as the signed-normal kernel of
//    ramlt_direction.h has a density of |theta| that is flat at 0).
//  - RamltMultiChainAngleProjection: the regional adaptive multi-chain perturbation with its
//    primary direction fixed (the first two uniforms, as MultiChainAngleProjection fixes the
//    raster offset): the direction change at the first continued level as (phi, theta) about x's
//    direction there (theta in [0, 0.4], as RamltLensAngleProjection); stated density T(x -> y)
//    divided by g / sin(theta), g the path measure of y per unit solid angle of the level direction
//    given the primary (its truncated-normal density times |cos| / d^2 at y_{k-1}, the specular
//    factors of both chains from path_densities, |cos| / d^2 at the level's next vertex).
//  - HsltTangentProjection: the half-vector mutation on a path light -> x_1 -> camera (k = 2, x_1
//    glossy, so only h_1 moves): y_1 - x_1 on the tangent plane of x_1 in the chart of the step's
//    first-order spread (q = D^{-1} U^T p, M = U D V^T the map from the step's standard normal z to
//    the plane, M = P B^{-1} L: P the surface's tangents in the plane, B the constraint block of
//    Kaplanyan et al. 2014 Eq. 11, L the step factor of Sec. 6.1-6.3), so q is standard normal to
//    first order; stated density T(x -> y) |det D| / |<ng(y_1), n(x_1)>| (area to plane to chart);
//    chart [-5, 5]^2, proposals off it failed samples (the stated mass off it enters the failure
//    cell). The idea of mcmc.hslt.proposal_chi2.glossy, on the registered instance.
// The lens, caustic, multi-chain, ramlt-lens and hslt projections take an optional PathMutation
// (`mutation`): when set, proposals are its propose() and the stated density its density() (the
// registered mutation or a wrapper of it, validate/mcmc/path_space/path_projections.h), and the
// concrete perturbation supplies only the chart (perturb, Jacobians).
#pragma once

#include <cstdint>
#include <functional>
#include <optional>

#include <Eigen/Dense>

#include "lib/mcmc/path_space/bidirectional_mutation.h"
#include "lib/mcmc/path_space/caustic_perturbation.h"
#include "lib/mcmc/path_space/hslt_mutation.h"
#include "lib/mcmc/path_space/lens_perturbation.h"
#include "lib/mcmc/path_space/multi_chain_perturbation.h"
#include "lib/mcmc/path_space/path_mutations.h"
#include "lib/mcmc/path_space/ramlt_direction.h"
#include "lib/mcmc/path_space/ramlt_perturbations.h"

namespace tb::path_space {

struct BidirWayProjection {
  const BidirectionalMutation* mut = nullptr;
  MltPath x;
  int s = 1;
  // The stated p_{s'}(y, l, na, s') (empty: the mutation's split_density; a negative control
  // passes a broken one).
  std::function<double(const MltPath&, int, int, int)> split_density;
  std::optional<Vec3> sample(Uniforms& u) const;
  double pdf(const Vec3& w) const;
};

// The whole bidirectional mutation (propose, density) seen through its one-vertex way at k >= 3
// segments: y kept when way_between(x, y) deletes x_{k-2} alone and adds one vertex (either
// split), every other proposal a failed sample; projection: the unit direction from x_{k-3} to
// y_{k-2}, kept only where y_{k-2} is the first hit from x_{k-3} and f(y) > 0 (elsewhere
// balance does not constrain T, and density() counts e.g. the split that would have reached
// y_{k-2} through an occluder, which the sampler cannot); stated density: density(x, y) (deletion
// and addition probabilities, both splits) times d^2 / |cos theta| at the first hit from x_{k-3},
// where f(y) > 0. It integrates to the probability of that way with f(y) > 0, which the failure
// cell sees.
struct BidirVertexProjection {
  const PathMutation* mutation = nullptr;
  const PathContext* ctx = nullptr;
  const BidirectionalMutation* structure = nullptr;  // way_between
  MltPath x;
  std::optional<Vec3> sample(Uniforms& u) const;
  double pdf(const Vec3& w) const;
};

struct LensOffsetProjection {
  const LensPerturbation* lens = nullptr;
  const PathContext* ctx = nullptr;
  MltPath x;
  const PathMutation* mutation = nullptr;  // set: its propose() and density() (see above)
  std::optional<Vec2> sample(Uniforms& u) const;
  double pdf(const Vec2& phi_rho) const;
  Vec2 chart_lo() const;
  Vec2 chart_hi() const;
};

struct CausticAngleProjection {
  const CausticPerturbation* caustic = nullptr;
  MltPath x;
  const PathMutation* mutation = nullptr;
  std::optional<Vec2> sample(Uniforms& u) const;
  double pdf(const Vec2& phi_rho) const;
  Vec2 chart_lo() const;
  Vec2 chart_hi() const;
};

struct MultiChainAngleProjection {
  const MultiChainPerturbation* sampler = nullptr;
  const MultiChainPerturbation* stated = nullptr;
  const PathContext* ctx = nullptr;
  MltPath x;    // levels(x).size() == 2
  Vec2 u_offset{0.3, 0.5};  // the fixed uniforms of the raster offset
  const PathMutation* mutation = nullptr;  // set: replaces both sampler->propose and stated->density
  std::optional<Vec2> sample(Uniforms& u) const;
  double pdf(const Vec2& phi_rho) const;
  Vec2 chart_lo() const;
  Vec2 chart_hi() const;
  // Jacobian from (phi, theta) at the level (given d0) to the path measure, times K_r(d0); see above.
  double jacobian(const MltPath& y, double theta) const;
};

struct RamltLensAngleProjection {
  const RamltLensPerturbation* lens = nullptr;
  MltPath x;  // applicable, with an empty lens chain (x_{k-1} not specular)
  const PathMutation* mutation = nullptr;
  std::optional<Vec2> sample(Uniforms& u) const;
  double pdf(const Vec2& phi_rho) const;
  Vec2 chart_lo() const;
  Vec2 chart_hi() const;
};

struct RamltMultiChainAngleProjection {
  const RamltMultiChainPerturbation* ramlt = nullptr;  // the chart (perturb, sigma)
  const MultiChainPerturbation* structure = nullptr;   // levels
  const PathContext* ctx = nullptr;
  MltPath x;                 // structure->levels(x).size() == 2
  Vec2 u_primary{0.3, 0.5};  // the fixed uniforms of the primary direction
  const PathMutation* mutation = nullptr;  // whose propose() and density() are tested
  std::optional<Vec2> sample(Uniforms& u) const;
  double pdf(const Vec2& phi_theta) const;
  Vec2 chart_lo() const { return {0.0, 0.0}; }
  Vec2 chart_hi() const { return {2 * kPi, 0.4}; }
  Vec3 primary() const;  // the fixed primary direction
};

struct HsltTangentProjection {
  const HsltMutation* hslt = nullptr;  // the chart (hslt_path, step_factors)
  const PathContext* ctx = nullptr;
  MltPath x;  // k = 2, x_1 not Dirac, hslt->applicable(x)
  const PathMutation* mutation = nullptr;  // whose propose() and density() are tested
  Eigen::Matrix2d to_chart = Eigen::Matrix2d::Identity(), to_plane = Eigen::Matrix2d::Identity();
  double det = 1.0;
  Vec3 o{0.0}, n{0.0, 0.0, 1.0}, s{1.0, 0.0, 0.0}, t{0.0, 1.0, 0.0};  // x_1, its normal and tangent frame
  // Chart half-width: first-order radial mass beyond it exp(-12.5) = 4e-6 (stated, in the failure cell).
  static constexpr double kHalfWidth = 5.0;
  // The chart at x (nothing when x's half-vector form or its blocks fail).
  static std::optional<HsltTangentProjection> at(const HsltMutation* hslt, const PathContext* ctx, const MltPath& x,
                                                 const PathMutation* mutation);
  std::optional<Vec2> sample(Uniforms& u) const;
  double pdf(const Vec2& q) const;
  Vec2 chart_lo() const { return {-kHalfWidth, -kHalfWidth}; }
  Vec2 chart_hi() const { return {kHalfWidth, kHalfWidth}; }
};

// A BDPT-sampled path with exactly k segments (deterministic in seed).
MltPath path_with_segments(const PathContext& ctx, int k, int max_depth, uint64_t seed);

}  // namespace tb::path_space
