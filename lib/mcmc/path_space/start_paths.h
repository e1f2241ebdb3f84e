// Paths of the shared representation sampled by bidirectional path tracing
// (lib/integrator/bdpt.h), as starting states for the path-space chains and for the seeded pairs
// of the detailed-balance checks.
#pragma once

#include <functional>
#include <optional>
#include <vector>

#include "lib/core/uniforms.h"
#include "lib/integrator/bdpt.h"
#include "lib/mcmc/path_space/path_state.h"

namespace tb::path_space {

// The full path x_0 .. x_k of BDPT connection (s, t) (the sampled end vertex of s = 1 / t = 1
// replaces the subpath's).
MltPath assemble_connection(const std::vector<PathVertex>& light, const std::vector<PathVertex>& camera, int s, int t,
                            const Connection& c);

// One BDPT sample (uniform raster position over the image); among its connections with a positive
// contribution and at least min_segments segments, one chosen uniformly. Up to `attempts` samples
// are tried; nothing if none has such a connection.
std::optional<MltPath> sample_bdpt_path(const PathContext& ctx, Uniforms& u, int max_depth, int min_segments = 1,
                                        int attempts = 64);

// The start-up of one chain (Veach 1997, Sec. 11.3.1): n_boot BDPT samples with uniform raster
// positions (streams (seed, chain key, i)); b = mean over samples of sum_{s,t} Y(weighted
// contribution), an unbiased estimate of int Y(f) dmu; x resampled among all connections with
// probability proportional to Y (replayed from its stream). By importance resampling,
// E[b g(x)] = int g Y(f) dmu for every g: chains started this way and weighted by b are unbiased
// at every step for a pi-invariant kernel (docs/mlt-path-space.md). x is empty when no sample
// found light (then b = 0). `pick` in [0, 1) chooses the candidate.
struct ChainStart {
  double b = 0.0;
  std::optional<MltPath> x;
};
ChainStart start_chain(const PathContext& ctx, uint64_t seed, uint64_t chain, int64_t n_boot, int max_depth,
                       double pick);

// The start-up for a chain target pi other than Y(f) (Veach 1997, Sec. 11.3.1 with Y(f) replaced
// by pi; Hoberock & Hart 2010): `term(c, x)` is connection c's term, for the assembled path x, of
// an unbiased estimate of int pi dmu summed over a sample's connections (for BDPT's MIS weights
// w_{s,t}: w_{s,t}(x) pi(x) / p_{s,t}(x)); b = mean over the n_boot samples of the summed terms,
// x resampled among all connections with a positive term proportionally to it. Then
// E[b g(x)] = int g pi dmu for every g. Same streams as the plain start-up above; only
// connections with a positive weighted contribution are offered to `term`.
using StartupTerm = std::function<double(const Connection& c, const MltPath& x)>;
ChainStart start_chain(const PathContext& ctx, uint64_t seed, uint64_t chain, int64_t n_boot, int max_depth,
                       double pick, const StartupTerm& term);

// Mean over n BDPT samples (uniform raster positions, streams (seed, key, i), i < n) of
// sum_{s,t} Y(weighted contribution): the start-up's unbiased estimate of int Y(f) dmu, from
// streams of the caller's key. Summed in fixed chunks: the same value for any thread count.
double bdpt_brightness(const PathContext& ctx, uint64_t seed, uint64_t key, int64_t n, int max_depth);

}  // namespace tb::path_space
