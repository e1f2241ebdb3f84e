// The BDPT techniques that can generate a given path, enumerated independently of the MIS code
// under test (lib/path/path.cpp: technique_ratios, mis_weight; lib/integrator/bdpt.cpp:
// connection_weight), and the invariant that the MIS weights of those techniques sum to one and
// every other technique gets weight zero (Veach 1997, Eq. 9.3 and Sec. 10.3; docs/integrator-checks.md).
//
// Technique s of a path x_0 .. x_k samples x_0 .. x_{s-1} from the emitter and x_k .. x_s from the
// lens, t = k + 1 - s >= 1 (lenses are not scene geometry, so t = 0 is never used). Written from
// Veach 1997, Sec. 10.3.5 (paths through specular vertices) and the vertex records alone, not from
// the Dirac flags the sampler stored:
//  - s = 0 (the camera subpath hits the emitter by chance): x_0 must have extent: an area light or
//    an infinite light that is not a Dirac one (a point, spot or directional light cannot be hit);
//  - s >= 1 joins x_{s-1} and x_s: neither may be a Dirac surface (every lobe of its BSDF a delta
//    lobe), because a deterministic connection has probability zero of meeting the delta
//    direction; the emitter end (next-event estimation, Dirac emitters included) and the lens end
//    (t = 1) can always be joined, except a direction (x_0 on an infinite light) to the lens
//    (s = 1, t = 1);
//  - its area density p_s = prod_{i<s} pL[i] prod_{i>=s} pE[i] (Veach 1997, Eq. 10.8) must be
//    positive, where a density generated *at* a Dirac vertex (pL[i] after a Dirac x_{i-1} or a
//    Dirac-direction emitter at a finite position, pE[i] before a Dirac x_{i+1}) is a delta common
//    to every technique that can generate the path and counts as 1 (Veach 1997, Sec. 10.3.5), and
//    pE[k], the lens position density, is common to all techniques and left out. A directional
//    light is an infinite emitter: x_0 is its direction, whose delta is pL[0] (common to every
//    s >= 1), and pL[1] is the area density of x_1 drawn on its emission disk, a real density.
// The weights: the power heuristic (beta = 2, Veach 1997, Eq. 9.11) over those techniques,
// w_s = p_s^2 / sum_j p_j^2, in logarithms (no under- or overflow of long products).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "lib/path/path.h"

namespace tb {

// Every lobe of the vertex's BSDF is a Dirac lobe (smooth conductor, smooth dielectric).
bool has_only_dirac_lobes(const PathVertex& v);

struct TechniqueEnumeration {
  std::vector<uint8_t> can_generate;  // per s = 0 .. k
  std::vector<double> weight;         // power heuristic over the techniques that can generate X
  int dirac_vertices = 0;             // surface vertices with only Dirac lobes
};

// x: the path, d: its per-vertex densities (path_densities, DiracPolicy::kZero). d.delta is not read.
TechniqueEnumeration enumerate_techniques(std::span<const PathVertex> x, const PathDensities& d);

// The invariant over many paths: weights given per path (the code under test) against the
// enumeration.
struct MisInvariantTally {
  int64_t paths = 0;
  int64_t paths_with_dirac = 0;
  int64_t techniques = 0;          // (path, s) pairs examined
  int64_t can_generate = 0;        // of those, techniques that can generate their path
  double worst_sum = 0.0;          // max |sum of weights over the generating techniques - 1|
  int64_t nonzero_invalid = 0;     // techniques that cannot generate the path with weight != 0
  double worst_invalid = 0.0;      // largest such weight
  double worst_vs_enumeration = 0.0;  // max |w_code - w_enumeration| over generating techniques
  int64_t sampled_invalid = 0;     // paths sampled by a technique the enumeration says cannot
  std::string first_violation;     // where the first violation was seen
  // Adds one path; `code` has one weight per s = 0..k; `sampled_s` the technique that sampled it.
  void add(std::span<const PathVertex> x, const TechniqueEnumeration& e, std::span<const double> code,
           int sampled_s, const std::string& where);
  // sum to 1 within 1e-12, no nonzero weight on a technique that cannot generate the path, weights
  // within 1e-9 of the enumeration's, no path sampled by a technique that cannot generate it.
  bool holds() const;
};

// Samples BDPT subpath pairs on `world` (lib/integrator/bdpt.h, the integrator's own sampling) and
// adds every connection (s, t) with a nonzero contribution to `tally`: the weights of the code
// under test are mis_weight(path_densities(X), j) for j = 0..k, and BDPT's incremental weight of
// the technique that sampled X must equal its from-scratch one (worst difference in
// *worst_incremental). drop_dirac_flags: the negative control, the weights computed from densities
// whose Dirac flags were cleared (the weights no longer know which connections are impossible).
struct MisInvariantOptions {
  int64_t subpath_pairs = 300;
  int max_depth = 6;  // scattering events
  uint64_t seed = 1;
  bool drop_dirac_flags = false;
};
void sample_mis_invariant(const World& world, const std::string& label, const MisInvariantOptions& o,
                          MisInvariantTally* tally, double* worst_incremental);

}  // namespace tb
