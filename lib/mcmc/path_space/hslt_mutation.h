// The half-vector mutation of half-vector-space light transport (Kaplanyan, Hanika, Dachsbacher
// 2014, "The Natural-Constraint Representation of the Path Space", Sec. 5, Fig. 12) as a Proposal
// on the path-space MLT state (path_state.h), registered as "hslt" (path_mutations.cpp) outside the
// default mixture.
//
// Path x = x_0 (emitter) .. x_k (pinhole camera), k >= 2, every interior vertex x_1 .. x_{k-1} a
// scattering surface vertex, at least one of them non-diffuse (glossy or specular) and at least one
// not specular. The endpoints x_0 and x_k stay fixed (App. A). One proposal (Fig. 12):
//  1. H^perp(x) = (h_1^perp .. h_{k-1}^perp) in the tangent frames of hslt_vertex.h (Sec. 4.2);
//  2. perturb every non-Dirac half vector at once: h_i^perp' = h_i^perp + delta_i, delta_i an
//     isotropic 2D Gaussian of standard deviation sigma_i per axis. Step size (Sec. 6.1): the
//     expected step length is gamma alpha_i / sqrt(pi) (gamma = 0.1, alpha_i the Beckmann-equivalent
//     roughness of the BSDF, Bsdf::beckmann_roughness), and the length of a 2D Gaussian step has
//     mean sigma sqrt(pi / 2), so sigma_i = gamma alpha_i sqrt(2) / pi. Diffuse BSDFs (alpha = inf)
//     use alpha = kDiffuseAlpha. The step is taken in h^perp itself, not in the plane-plane domain
//     of Sec. 6.1 (h_pp = h / sqrt(1 - |h^perp|^2)): a different but symmetric kernel. Dirac
//     (specular) vertices keep their h_i^perp (Sec. 5.1: "their half vectors always remain at a
//     fixed position"; the value of x, ~1e-8 for traced chains, not exactly 0, so that the reverse
//     move targets what the forward one kept);
//     Stratification (Sec. 6.2-6.3, on by default): the ray differentials of the camera ray through
//     x_{k-1} (one pixel in x and y) meet the tangent plane of x_{k-1} in dp_u, dp_v, scaled to 2%
//     of the larger image side, in (u, v) of x_{k-1}; Eq. 9 gives the half-vector changes that
//     would produce them, dh_{u,i} = D_i^{-1} duv_u, dh_{v,i} = D_i^{-1} duv_v (D_i the blocks of the
//     last block row of J^{-1}, hslt_inverse_last_block_row); the step is rotated to the
//     orthonormalised basis e1 = dh_u / |dh_u|, e2 perpendicular, with per-axis standard deviation
//     s_a = max(min(sigma_i, w_i l_a), 1e-3 sigma_i), l_1 = |dh_u|, l_2 = |<dh_v, e2>|, and the
//     bandwidth weights w_i = sigma_i / sum_j sigma_j (Sec. 6.3, over the non-Dirac vertices). The
//     desired change is taken as the standard deviation (the paper's supplement has the exact
//     Phong-lobe form, Sec. 7: not built). Where a D_i is singular or no differential exists the
//     vertex keeps sigma_i I. All of it is a function of x: the reverse density uses y's steps;
//  3. h_to_positions: the predictor-corrector walk of hslt_walk.h (Sec. 5.1) moves x_1 .. x_{k-1}
//     to the new constraints, visibility on, projection side by the Table 2 heuristic; the result
//     is rebuilt from its surfaces at the walk's (u, v) (Scene::surface_at);
//  4. reverse check (Sec. 5.2): the walk from y back to H^perp(x) must return to x (vertices within
//     kLandingTolerance); a non-reversible move is rejected (propose returns nothing).
//
// Proposal density in the path measure (area product of the interior vertices, endpoints fixed;
// N(.; L L^T) below is the 2D normal density of the step of vertex i, L_i from x):
// the density in h^perp times |dH^perp / dX| (the change of measure of Eq. 3-7 at fixed endpoints,
// Eq. 4 without the geometric terms; the first equation of Sec. 5.2 writes the same factor as
// |J|^{-1} with J read as dX/dH^perp):
//   T(x -> y) = prod_{i non-Dirac} N(h_i^perp(y) - h_i^perp(x); L_i L_i^T(x))  * |det J_area(y)|
//               * prod_{i Dirac} |d omega_prev / d h_i| / |<h_i, n_i>|
//               * [walk x -> H^perp(y) lands at y] * [walk y -> H^perp(x) lands at x],
// J_area = dH^perp / d(x_1 .. x_{k-1}) (Eq. 11) in area measure (J_uv diag(1/|dp/du x dp/dv|)),
// with |det| from the block LU of Sec. 7 (hslt_block_lu.h). The Dirac factor converts the delta
// of a specular constraint, delta^2(h_i^perp), into the delta the engine drops (lib/path/dirac.h:
// delta(omega_prev - omega*) in the solid angle of the direction towards x_{i-1}, given the
// direction towards x_{i+1}): delta^2(h^perp) = delta_omega / |d h^perp / d omega_prev|, with
// dh^perp = |<h, n>| dh (App. A) and |dh / d omega_prev| the generalised half-vector Jacobian
// (Eq. 10, lib/material/half_vector.h) with the other direction fixed; the product of the
// per-vertex factors is the determinant because, in coordinates where x_{i-1} is given by the
// direction at x_i, the map between the two sets of deltas is triangular.
//
// Frames and indices of refraction. h^perp depends on the reference vector of each vertex's frame
// (hslt_vertex.h) and on the side of each neighbour: T(x -> y) evaluates y in the frames and with
// the indices of x (frame reference = the unit dp/du of x's vertex; eta from the sides of x's
// neighbours), and y must have the same sides (reflection / transmission) at every vertex.
//
// The two landing indicators make T a function of the pair alone (both walks are deterministic):
// propose samples exactly T (the forward walk lands at y by construction, the reverse walk is the
// rejection test), and T(y -> x) contains the same pair of indicators, so the Metropolis-Hastings
// ratio is exact. Not built: the Phong-lobe form of the anisotropic offset of Sec. 7 (a Gaussian
// is used).
//
// Subspace jump (Sec. 5.2, "Transitioning between Subspaces"; option `jump`, on by default as in
// the paper). Derivation of its density:
//  When: on a path whose interior vertices are all non-Dirac (then h* has 2(k-1) free components
//    and the map below has full rank; a path with a specular vertex never jumps), before the walk:
//    the jump is taken when the first prediction y towards h* is a valid path and the pair (x, y)
//    is bidirectionally invalid (below); otherwise the regular walk runs. The paper attempts the
//    jump after the walk x -> h* failed; that trigger depends on h*, not on the pair, and the
//    reverse jump would then need the walk y -> h** to fail as well (h** the target whose first
//    prediction from y gives x), which it mostly does not: with that trigger (60 jumps proposed on
//    the 8 x 8 glossy image, 256 spp) the acceptance of the selected half-vector moves was 85.6 %
//    with and without jumps. Deciding on the pair-symmetric test makes the reverse jump possible
//    whenever its prediction reproduces x.
//  Proposal: the first prediction of the walk (Sec. 5.2: "the prediction of the first iteration of
//    our scheme"), lambda = 1: Delta(u,v) = J_uv(x)^{-1} (h* - H(x)), x'_i = x_i + dp/du Delta u_i
//    + dp/dv Delta v_i on the tangent plane of x_i, projected in the walk's order (side of x by
//    the Table 2 heuristic) by the first hit of a ray from the projected previous vertex y_prev
//    towards x'_i (Fig. 8) on ANY shape (another primitive or shape: the jump); the segment to the
//    other fixed endpoint must be unoccluded. Valid when every y_i is a scattering surface vertex
//    and y is a path whose interior vertices are all non-Dirac ("non-zero throughput" is left to
//    pi(y) in the acceptance); a ray with |cos| < kJumpMinCos against the tangent plane of x_i or
//    the surface hit is rejected (grazing: G ~ 0, and x'_i is not recoverable from the pair when
//    y_prev lies on that plane).
//  Bidirectionally invalid (Sec. 5.2): the regular walk does not land both ways, i.e. neither
//    x -> H(y) (in x's frames) lands at y nor y -> H(x) (in y's frames) lands at x; otherwise the
//    jump is rejected. This condition is symmetric in (x, y), and the regular T(x -> y) needs both
//    landings, so for each pair at most one of the two branches is positive.
//  Density (Sec. 5.2, first and second equations), in the area product measure of x_1 .. x_{k-1}:
//    p(h*) = N(h* - H(x); L L^T(x)); Delta(u,v) = J_uv^{-1} (h* - H(x)) gives
//    p(Delta uv) = p(h*) |det J_uv(x)|, and the tangent-plane area is |dp/du x dp/dv| d(u,v), so
//    p(x') = p(h*) |det J_area(x)| (the paper's p(H_{t+1}|H_t) |J_{H_t}|^{-1} with J = dX/dH);
//    the ray cast keeps the direction o from y_prev, so dA(y_i) |cos theta_{y_i}| / |y_i - y_prev|^2
//    = dA(x'_i) |cos theta'_{x'_i}| / |x'_i - y_prev|^2 (theta' against the tangent plane's normal),
//    i.e. p(y_i | y_prev) = p(x'_i | y_prev) G(y_prev, y_i) / G(y_prev, x'_i) (second equation;
//    the cosine at y_prev cancels). The map (x'_1 .. x'_{k-1}) -> (y_1 .. y_{k-1}) is triangular in
//    projection order, so
//      T_jump(x -> y) = N(h* - H(x); L L^T(x)) |det J_area(x)| prod_i G(y_prev, y_i) / G(y_prev, x'_i)
//                       * [replay of the prediction from h* gives y] * [bidirectionally invalid (x, y)],
//    and the regular T(x -> y) above gets the factor [the prediction from x towards H(y) does not
//    jump] (the two branches partition the h* of a proposal).
//  From the pair alone: x'_i is the intersection of the line y_prev -> y_i with the tangent plane of
//    x_i (in projection order from x's side), Delta(u,v) its coordinates in (dp/du, dp/dv) of x_i,
//    h* = H(x) + J_uv(x) Delta(u,v); then the indicators are replayed. T_jump(y -> x) is the same
//    function with the roles swapped (tangent planes, frames, side and L of y).
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include <Eigen/Dense>

#include "lib/core/uniforms.h"
#include "lib/differential/hslt_walk.h"
#include "lib/mcmc/path_space/mlt.h"
#include "lib/mcmc/path_space/path_mutations.h"
#include "lib/mcmc/path_space/path_state.h"

namespace tb::path_space {

// Counters of a mutation's proposals (the statistics of Kaplanyan 2014, Table 3). Shared by the
// copies of a mutation; updated with relaxed atomics (they never influence a result).
struct HsltCounters {
  std::atomic<int64_t> proposals{0};       // propose() calls on applicable paths
  std::atomic<int64_t> not_applicable{0};  // propose() calls on paths it does not apply to
  std::array<std::atomic<int64_t>, kHsltWalkStatusCount> forward_status{};  // forward walks by status
  std::atomic<int64_t> iterations_converged{0};  // predictor-corrector iterations of converged forward walks
  std::atomic<int64_t> iterations_all{0};        // ... of all forward walks
  std::atomic<int64_t> non_reversible{0};        // converged forward walk, reverse walk does not return
  std::atomic<int64_t> generated{0};             // proposals returned (reversible walks and jumps)
  // Subspace jumps (Sec. 5.2; Table 3 "Submanifold jump"): attempted = proposal on a path the jump
  // applies to; projected = the first prediction gave a valid path; succeeded = the pair was also
  // bidirectionally invalid and the prediction is returned as the proposal (no walk).
  std::atomic<int64_t> jump_attempted{0};
  std::atomic<int64_t> jump_projected{0};
  std::atomic<int64_t> jump_succeeded{0};
};

struct HsltCountsSnapshot {
  int64_t proposals = 0, not_applicable = 0, converged = 0, iterations_converged = 0, iterations_all = 0,
          non_reversible = 0, generated = 0, jump_attempted = 0, jump_projected = 0, jump_succeeded = 0;
  std::array<int64_t, kHsltWalkStatusCount> status{};
  double iterations_per_converged() const { return converged > 0 ? double(iterations_converged) / double(converged) : 0; }
  double iterations_per_walk() const { return proposals > 0 ? double(iterations_all) / double(proposals) : 0; }
  // Of the converged forward walks, the fraction whose reverse walk does not return (Table 3).
  double non_reversible_fraction() const { return converged > 0 ? double(non_reversible) / double(converged) : 0; }
  double generation_rate() const { return proposals > 0 ? double(generated) / double(proposals) : 0; }
  double jump_success_rate() const { return jump_attempted > 0 ? double(jump_succeeded) / double(jump_attempted) : 0; }
};
HsltCountsSnapshot snapshot(const HsltCounters& c);

class HsltMutation {
 public:
  using State = MltPath;
  static constexpr double kDefaultGamma = 0.1;        // Sec. 6.1
  static constexpr double kDiffuseAlpha = 1.0;        // Beckmann-equivalent alpha used for diffuse BSDFs
  static constexpr double kLandingTolerance = 1e-6;   // scene units: "the vertex positions match" (Sec. 5.2)
  static constexpr double kDiracHoldTolerance = 1e-8; // |h_i^perp(y) - h_i^perp(x)| at a Dirac vertex

  static constexpr double kImageFraction = 0.02;     // Sec. 6.2: desired change of x_{k-1}, 2% of the image
  static constexpr bool kDefaultJump = true;         // Sec. 5.2: the subspace jump is the paper's behaviour
  static constexpr double kJumpMinCos = 1e-3;        // jump rays more grazing than this (to x'_i or y_i): rejected

  // stratify: the step sizes of Sec. 6.2-6.3 (min of the BSDF step and the weighted ray-differential
  // step per axis); false: the isotropic BSDF steps of Sec. 6.1 only.
  explicit HsltMutation(const PathContext& ctx, double gamma = kDefaultGamma,
                        std::shared_ptr<HsltCounters> counters = nullptr, bool stratify = true,
                        double image_fraction = kImageFraction, bool jump = kDefaultJump);

  std::optional<MltPath> propose(const MltPath& x, Uniforms& u) const;
  double density(const MltPath& x, const MltPath& y) const;
  bool applicable(const MltPath& x) const;

  // --- The parts (checks, negative controls in validate/) ------------------------------------
  // The path in half-vector form: x's own frames and indices (frames_of == nullptr), or y's
  // vertices in the frames and with the indices of `frames_of` (nothing when a vertex is on
  // another side of its surface than in frames_of, or the structure differs).
  std::optional<HsltPath> hslt_path(const MltPath& x, const HsltPath* frames_of = nullptr) const;
  // sigma_i of the interior vertices (index 0 = x_1): the BSDF steps of Sec. 6.1; 0 at Dirac vertices.
  std::vector<double> sigmas(const MltPath& x) const;
  // The step of every interior vertex: delta_i = L_i z, z a standard 2D normal (covariance L L^T);
  // zero at Dirac vertices. Without stratification L_i = sigma_i I; with it (Sec. 6.2-6.3, see the
  // file comment) L_i = [e1 e2] diag(s_1, s_2).
  std::vector<Eigen::Matrix2d> step_factors(const MltPath& x, const HsltPath& X) const;
  // prod_{non-Dirac} N(h_i(Y) - h_i(X); L_i L_i^T) into *g, the Dirac flags into *dirac; false when a
  // Dirac vertex's h^perp moved by more than kDiracHoldTolerance.
  bool perturbation_density(const std::vector<Eigen::Matrix2d>& L, const HsltPath& X, const HsltPath& Y, double* g,
                            std::vector<bool>* dirac) const;
  // The walk from X to `target` with the mutation's options.
  HsltWalkResult walk(const HsltPath& X, const Eigen::VectorXd& target) const;
  // The MltPath of x with its interior vertices at the walk's result (rebuilt from the surfaces).
  MltPath path_at(const MltPath& x, const HsltPath& walked) const;
  // Does the walk from X to H^perp(Y) return Y (within kLandingTolerance)?
  bool lands(const HsltPath& X, const HsltPath& Y) const;
  // The proposal density's factors for a pair (x, y).
  struct DensityParts {
    bool structure = false;     // both applicable, same shapes, sides, Dirac h^perp kept
    double perturbation = 0;    // prod N(delta_i; sigma_i)
    double measure = 0;         // |det J_area(y)| * Dirac factors
    bool forward_lands = false; // walk x -> H^perp(y) lands at y
    bool reverse_lands = false; // walk y -> H^perp(x) lands at x
  };
  DensityParts density_parts(const MltPath& x, const MltPath& y) const;
  // |det J_area(Y)| * prod_{Dirac} |d omega_prev / d h_i| / |<h_i, n_i>| (0 when the block LU fails).
  double measure_factor(const HsltPath& Y, const std::vector<bool>& dirac) const;
  // The perturbed target of a proposal (Box-Muller from two uniforms per non-Dirac vertex).
  Eigen::VectorXd perturbed_target(const HsltPath& X, const std::vector<Eigen::Matrix2d>& L, Uniforms& u) const;

  // --- The subspace jump (Sec. 5.2, see the file comment) ---------------------------------------
  // Every interior vertex non-Dirac (and applicable): the jump may start from / land at x.
  bool jump_applicable(const MltPath& x) const;
  // The first prediction of the walk X -> target (lambda = 1) projected by first hits (any shape),
  // with the prediction points x'_i; nothing when a ray misses, meets a non-scattering vertex or
  // the closing segment is occluded.
  struct JumpPrediction {
    MltPath y;
    std::vector<Vec3> predicted;  // x'_i (index = vertex index; endpoints unused)
    bool from_start = true;       // projection order
  };
  std::optional<JumpPrediction> jump_predict(const MltPath& x, const HsltPath& X, const Eigen::VectorXd& target) const;
  // The regular walk lands neither x -> H(y) nor y -> H(x) (Sec. 5.2 "bidirectionally invalid").
  bool bidirectionally_invalid(const MltPath& x, const MltPath& y) const;
  // The factors of T_jump(x -> y).
  struct JumpParts {
    bool structure = false;       // both jump-applicable, same endpoints, x'_i found from y
    Eigen::VectorXd target;       // h* recovered from the pair
    double perturbation = 0;      // N(h* - H(x); L L^T(x))
    double measure = 0;           // |det J_area(x)|
    double g_ratio = 0;           // prod_i G(y_prev, y_i) / G(y_prev, x'_i)
    bool replay_lands = false;    // the prediction from h* reproduces y (kLandingTolerance)
    bool bidirectionally_invalid = false;
  };
  JumpParts jump_parts(const MltPath& x, const MltPath& y) const;
  // The jump propose takes from X towards `target`, if any (valid prediction, bidirectionally invalid).
  std::optional<MltPath> jump_proposal(const MltPath& x, const HsltPath& X, const Eigen::VectorXd& target) const;
  bool jump_preempts(const MltPath& x, const HsltPath& X, const Eigen::VectorXd& target) const;
  double jump_density(const MltPath& x, const MltPath& y) const;

  bool jump() const { return jump_; }
  double gamma() const { return gamma_; }
  bool stratify() const { return stratify_; }
  const PathContext& context() const { return *ctx_; }
  const std::shared_ptr<HsltCounters>& counters() const { return counters_; }
  HsltWalkOptions walk_options() const { return options_; }

 private:
  const PathContext* ctx_;
  double gamma_;
  std::shared_ptr<HsltCounters> counters_;
  bool stratify_ = true;
  double image_fraction_ = kImageFraction;
  bool jump_ = kDefaultJump;
  HsltWalkOptions options_;
};

// The paths "hslt" applies to (registered applicability): HsltMutation::applicable.
bool hslt_applies(const HsltMutation& m, const MltPath& x);

// The mixture of the integrator "hslt" (as the paper's HSLT+MLT, Sec. 8): the bidirectional
// mutation and the half-vector mutation with their registered default weights (0.4, 0.5; c_j(x)
// normalised over the mutations that apply to x), run by run_mlt's one chain loop (mlt_chain.h).
// `counters` receives the half-vector mutation's walk statistics.
PathMutationList make_hslt_mixture(const PathContext& ctx, const PathMutationSettings& s,
                                   const std::shared_ptr<HsltCounters>& counters,
                                   double gamma = HsltMutation::kDefaultGamma, bool stratify = true,
                                   bool jump = HsltMutation::kDefaultJump);

// Prints the Table 3 line of Kaplanyan 2014 (iterations per converged / per forward walk, generation
// rate, non-reversible fraction, acceptance of the mutation named `mutation`, mutations per second).
void print_walk_statistics(const char* label, const char* mutation, const char* what, const HsltCounters& counters,
                           const MltStats& stats);

}  // namespace tb::path_space

namespace tb {
// The renderer entry point for the integrator registry (name "hslt"): run_mlt over
// make_hslt_mixture; prints the statistics of Kaplanyan 2014, Table 3 (iterations per converged /
// per forward walk, generation rate, non-reversible fraction, acceptance, mutations per second).
// RenderSettings::params: "gamma" (Sec. 6.1 step scale, default 0.1), "stratify" (0: the BSDF
// steps of Sec. 6.1 only; default 1: Sec. 6.2-6.3), "jump" (0: no subspace jump; default 1: Sec. 5.2).
int64_t render_hslt(const World& world, const RenderSettings& settings, Film& film);
}  // namespace tb
