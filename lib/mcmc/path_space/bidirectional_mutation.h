// Veach's bidirectional mutation (Veach 1997, Sec. 11.4.2; Veach & Guibas 1997, Sec. 5.2) on
// the shared path representation, with its proposal density T(x -> y) in the path measure.
//
// Notation: x = x_0 .. x_k, with a virtual vertex x_{-1} before the emitter. A mutation keeps a
// light end x_l (l = -1: nothing kept on the light side) and a camera end x_m (l < m <= k; the
// camera vertex is always kept), deletes the kd = m - l edges between them (and the m - l - 1
// vertices x_{l+1} .. x_{m-1}), then adds ka edges: na = ka - 1 new vertices, s' sampled from
// the light side (from x_l, x_{l-1}; a fresh emitter vertex when l = -1) and t' = na - s' from the
// camera side (from x_m, x_{m+1}), joined by a deterministic connection. y has ky = k - kd + ka
// segments.
//
// Probabilities (they depend on x through k, its Dirac flags and the kept ends; the reverse move
// evaluates them on y):
//   P_del(l, m | x)  = p_d(kd) / #positions(kd) (positions with non-Dirac kept ends),
//                      p_d(kd) ∝ {1: 1/4, 2: 1/2, >= 3: 2^-kd} over the valid kd (Veach 1997,
//                      Sec. 11.4.2.1 uses the same shape); no (l = -1, kd = 1) move, and l >= 0 when x_0 is a Dirac-position light (it could not be told
//                      apart from its regeneration);
//   P_add(ka | kd, k) ∝ w(|ka - kd|), w = {4, 2, 1} for 0, 1, 2 (else 0), over ka >= 1 with
//                      1 <= ky <= max_segments, excluding the null move kd = ka = 1;
//   P(s' | na)       = 1 / #valid splits (s' >= 1 needs the light end to be extensible, t' >= 1
//                      the camera end, subpath_step.h: can_extend).
// Proposal density (Veach 1997, Eq. 11.7 and the sum over ways of Sec. 11.4.2.1):
//   T(x -> y) = P_del(l, m | x) P_add(ka | kd, k) sum_{s'} P(s' | na) p_{s'}(y),
//   p_{s'}(y) = prod_{i = l+1}^{l+s'} pL_y(i) prod_{i = l+s'+1}^{l+na} pE_y(i),
// with pL_y(i) = pdf_next(y_{i-2}, y_{i-1} -> y_i) (pdf_light_origin for i = 0) and pE_y(i) =
// pdf_next(y_{i+2}, y_{i+1} -> y_i): the area densities the steps of subpath_step.h sample with.
// Dirac vertices (mirror, glass; lib/path/dirac.h): kept ends x_l, x_m are never Dirac vertices
// (P_del is normalised over the pairs with valid ends, so it depends on x's Dirac flags, and the
// reverse move evaluates it on y); a split whose connecting edge touches a Dirac vertex of y is
// rejected when proposed and has density 0 in the sum (Veach 1997, Sec. 10.3.5: a connection can
// never reach a specular vertex); the densities of vertices sampled through a Dirac vertex are the
// pseudo densities of dirac.h (lobe probability, the delta dropped as in f).
// (l, m, ka) are read off (x, y) as the longest common prefix and suffix: the kept vertices are
// the only shared ones with probability one, so the sum over ways runs over the splits s' only.
#pragma once

#include <optional>
#include <vector>

#include "lib/core/uniforms.h"
#include "lib/mcmc/path_space/path_state.h"

namespace tb::path_space {

class BidirectionalMutation {
 public:
  using State = MltPath;
  struct Way {
    int l = 0, m = 0, ka = 0;  // kept light end, kept camera end (indices in x), added edges
    int kd() const { return m - l; }
    int na() const { return ka - 1; }
  };

  BidirectionalMutation(const PathContext& ctx, int max_segments) : ctx_(&ctx), max_segments_(max_segments) {}

  // Proposal concept (estimators/mcmc/concepts.h).
  std::optional<MltPath> propose(const MltPath& x, Uniforms& u) const;
  double density(const MltPath& x, const MltPath& y) const;

  // ---- the pieces, for tests and checks ----------------------------------------------------------
  double deletion_probability(const MltPath& x, int l, int m) const;
  double addition_probability(int k, int kd, int ka) const;
  // Valid splits s' of na added vertices between the kept ends of way w in x.
  std::vector<int> valid_splits(const MltPath& x, const Way& w) const;
  // The way (l, m, ka) that turns x into y; nothing when y is not reachable in one mutation.
  std::optional<Way> way_between(const MltPath& x, const MltPath& y) const;
  // y from x by way w and split s (uniforms for the new vertices only).
  std::optional<MltPath> propose_way(const MltPath& x, const Way& w, int s, Uniforms& u) const;
  // Is the connecting edge y_{l+s'} -- y_{l+s'+1} of split s' free of Dirac vertices (for l + s' = -1:
  // is y_0, reached by the camera subpath, not a Dirac vertex)?
  bool split_connectible(const MltPath& y, int l, int s) const;
  // p_{s'}(y): product of the area densities of y's added vertices y_{l+1} .. y_{l+na}.
  double split_density(const MltPath& y, int l, int na, int s) const;
  int max_segments() const { return max_segments_; }
  const PathContext& context() const { return *ctx_; }

 private:
  const PathContext* ctx_;
  int max_segments_;
};

}  // namespace tb::path_space
