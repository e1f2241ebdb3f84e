// Single-vertex path filtering as an unbiased marginal-MIS estimator (`pf1`; West, Georgiev &
// Hachisuka 2022, Sec. 4.3 Eq. 13 and Sec. 5 with one filtered vertex; docs/mmis-paths.md).
//
// A pass traces one camera prefix per pixel sample (camera ray to its first hit x_1; spp_per_pass
// samples per pixel). A prefix is *filterable* when x_1 has a BSDF with a non-delta lobe and no delta
// lobe. Every filterable prefix y_j samples one direction w_j ~ p_j(w) = pdf of y_j's BSDF for its own
// outgoing direction wo_j (solid angle, radiance mode). The prefixes' first vertices are indexed in a
// hashed grid (PointGrid, the photon map's index) with cells of side r.
//
// Query i (a filterable prefix, first vertex x_1 = y_i) forms its kernel K_i: the filterable prefixes
// with |y_j - x_1| <= r, its own prefix included (distance 0), at most `max_members` of them (the
// nearest, ties by sample slot; a function of the prefixes' positions only). Each member j is a
// conditional technique in the sense of Eq. 13, its auxiliary vertices t_j = prefix j, its sample the
// output path x = (camera, x_1, x_2, ...) whose direction at x_1 is w_j: x_2 is found by tracing the
// actual ray from x_1 along w_j (visibility and BSDF at x_1 evaluated along the actual connection:
// the unbiased variant of Sec. 5.1, not the shared-visibility approximation), and the rest of the
// suffix by a fresh path-tracer estimate L^ of the radiance arriving at x_1 from w_j. The conditional
// density of x given prefix j is p_j(w) times the densities of the suffix beyond x_2, which are the same
// for every technique and cancel in the weight, so the Eq. 13 denominator for the output path of member
// k is the one-kernel case (K = 1) of Eq. 14,
//     D_i(w_k) = sum_{j in K_i} p_j(w_k),
// and the pixel estimate of query i is (camera weight W_i)
//     I_i = W_i [ Le(x_1 -> camera) + sum_{k in K_i} f_i(wo_i, w_k) |w_k . n_s| L^_ik / D_i(w_k) ]
// (written without the next-event estimation at x_1 that is added below),
// i.e. the weight of the output path of member k under its own technique is p_k(w_k) / D_i(w_k)
// (balance heuristic), and the weights of all the techniques of K_i that can produce that output path
// sum to one. Unbiased: conditioned on all prefixes (which fix every kernel), the w_k are independent
// with densities p_k and the suffix estimates are independent and unbiased, so E[I_i | prefixes] =
// W_i [Le + integral of f_i L |cos| dw] as for MIS with one sample per technique (Veach 1997, Eq. 9.7),
// provided sum_j p_j(w) > 0 wherever f_i(wo_i, w) > 0, which the query's own technique p_i guarantees
// (Sec. 5.1: "including the classical path tracing technique ... guarantees this condition").
// Next-event estimation at x_1 is the query's classical technique (Sec. 3.1 split form): its light
// sample w_L (density p_L = pmf pdf_li) has denominator p_L(w_L) + sum_j p_j(w_L), and emission found
// at x_2 by member k's direction has p_L(w_k) + D_i(w_k); light scattered at x_2 or later is found by
// the members only (denominator D_i). Delta lights: light sample only, weight 1. The suffix from x_2
// on is the path tracer's (NEE and MIS there, emission at x_2 left to the weights above), with
// max_depth - 1 scattering events left.
// Camera samples whose first hit is not filterable are plain path-tracer samples.
//
// Parameters: radius (default 0.01 x the scene's bounding-sphere radius), max_members (default 32).
// Random streams: the camera prefix and its direction from Rng::for_sample(seed, pixel, sample index)
// (film, lens, then lobe and direction uniforms); the suffix of the pair (query i, member k) from
// Rng::for_sample(hash(seed, "pf1", pass), slot_i, slot_k), slot = pixel * spp_per_pass + sample.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "estimators/mmis_filtering.h"
#include "lib/film/film.h"
#include "lib/integrator/render_settings.h"
#include "lib/scene/world.h"

namespace tb {

// The MMIS weight of the output path sampled by kernel member `own` (West et al. 2022, Eq. 13 with the
// product of sums of Eq. 14 for one filtered vertex, K = 1): column[j] = p_j(w_own), the conditional
// density of that output path's direction under member j's prefix, for the `members` members of the
// kernel (the query's own prefix among them). The same function (filtering_mmis_weight) the analytic
// filtering checks use.
// `classical` = the Sec. 3.1 split term of the query's light sample, n_L p_L(w_own) (0 for light the
// light sample cannot find). own = -1: the light sample's own denominator (own_pdf 0).
FilteringWeight pf1_mmis_weight(std::span<const double> column, int own, double classical = 0.0);

// The weighting of pf1 as a policy of the renderer template (path_filter_impl.h): the exact one calls
// pf1_mmis_weight; the negative controls of validate/ provide broken ones. `query` is the position of
// the query's own prefix in the kernel.
struct Pf1ExactWeights {
  static FilteringWeight weight(std::span<const double> column, int own, int /*query*/, double classical) {
    return pf1_mmis_weight(column, own, classical);
  }
};

struct Pf1Params {
  double radius = 0.0;
  int max_members = 32;
};
Pf1Params pf1_params(const World& world, const RenderSettings& st);
std::vector<std::pair<std::string, std::string>> pf1_parameter_list();

// One kernel of a pass as the renderer forms it (for the checks): pdf[j * members + k] = p_j(w_k), the
// density of member k's sampled direction under member j's prefix (0 when member k sampled none);
// query = position of the query's own prefix; sampled[k] = member k has a direction.
struct Pf1Kernel {
  int members = 0;
  int query = 0;
  std::vector<double> pdf;
  std::vector<bool> sampled;
};
// The kernels of the first pass of a pf1 render (settings as for render_pf1), of at most max_kernels
// queries (every `stride`-th filterable prefix in slot order), with the members the renderer uses.
std::vector<Pf1Kernel> pf1_sample_kernels(const World& world, const RenderSettings& settings, size_t max_kernels);

// Time spent in the filtering pass (kernels, weights, suffixes) and in the prefix pass, summed over the
// passes of the last completed render_pf1 call of the process, and the mean kernel size.
struct Pf1Timing {
  double prefix_seconds = 0.0;
  double filter_seconds = 0.0;
  double mean_members = 0.0;
  int64_t passes = 0;
};
Pf1Timing pf1_last_timing();

int64_t render_pf1(const World& world, const RenderSettings& settings, Film& film);

}  // namespace tb
