#include "lib/mcmc/path_space/bidirectional_mutation.h"

#include <algorithm>
#include <cmath>

#include "lib/mcmc/path_space/subpath_step.h"
#include "lib/path/dirac.h"
#include "lib/path/measure.h"

namespace tb::path_space {

namespace {

// Unnormalised p_d(kd) (Veach 1997, Sec. 11.4.2.1: short deletions are favoured).
double deletion_weight(int kd) {
  if (kd == 1) return 0.25;
  if (kd == 2) return 0.5;
  return std::ldexp(1.0, -kd);
}
// Unnormalised P_add(ka | kd): the new length stays close to the deleted one.
double addition_weight(int kd, int ka) {
  switch (std::abs(ka - kd)) {
    case 0: return 4.0;
    case 1: return 2.0;
    case 2: return 1.0;
    default: return 0.0;
  }
}
bool x0_deletable(const MltPath& x) {
  const PathVertex& v = x.v[0];
  return !(v.light && (v.light->flags() & light_flags::kDeltaPosition));
}
// Lowest l for kd deleted edges.
int lowest_l(const MltPath& x, int kd) { return (kd >= 2 && x0_deletable(x)) ? -1 : 0; }
// Kept ends must not be Dirac vertices: a subpath extended from a kept mirror or glass vertex would
// retrace the deleted vertex (the same point, or the other lobe), so the deleted and the added
// vertices could not be told apart; no connection can be made at such an end either.
bool ends_ok(const MltPath& x, int l, int m) {
  return (l < 0 || !is_dirac_surface(x.v[l])) && !is_dirac_surface(x.v[m]);
}
// The number of valid positions l = lo .. k - kd.
int positions(const MltPath& x, int kd) {
  int n = 0;
  for (int l = lowest_l(x, kd); l <= x.segments() - kd; ++l) n += ends_ok(x, l, l + kd) ? 1 : 0;
  return n;
}

}  // namespace

double BidirectionalMutation::deletion_probability(const MltPath& x, int l, int m) const {
  const int k = x.segments(), kd = m - l;
  if (k < 1 || kd < 1 || m > k || l < lowest_l(x, kd) || !ends_ok(x, l, m)) return 0.0;
  double norm = 0.0;
  for (int d = 1; d <= k + 1; ++d)
    if (positions(x, d) > 0) norm += deletion_weight(d);
  return deletion_weight(kd) / norm / positions(x, kd);
}

double BidirectionalMutation::addition_probability(int k, int kd, int ka) const {
  auto valid = [&](int a) {
    const int ky = k - kd + a;
    return a >= 1 && ky >= 1 && ky <= max_segments_ && !(kd == 1 && a == 1);
  };
  if (!valid(ka)) return 0.0;
  double norm = 0.0;
  for (int a = kd - 2; a <= kd + 2; ++a)
    if (valid(a)) norm += addition_weight(kd, a);
  return addition_weight(kd, ka) / norm;
}

std::vector<int> BidirectionalMutation::valid_splits(const MltPath& x, const Way& w) const {
  const int k = x.segments(), na = w.na();
  std::vector<int> out;
  if (na < 0) return out;
  const bool light_ok = w.l < 0 ? ctx_->lights->size() > 0
                                : can_extend(*ctx_, w.l >= 1 ? &x.v[w.l - 1] : nullptr, x.v[w.l],
                                             TransportMode::kImportance);
  const bool camera_ok =
      can_extend(*ctx_, w.m < k ? &x.v[w.m + 1] : nullptr, x.v[w.m], TransportMode::kRadiance);
  for (int s = 0; s <= na; ++s)
    if ((s == 0 || light_ok) && (s == na || camera_ok)) out.push_back(s);
  return out;
}

std::optional<BidirectionalMutation::Way> BidirectionalMutation::way_between(const MltPath& x,
                                                                             const MltPath& y) const {
  const int nx = static_cast<int>(x.v.size()), ny = static_cast<int>(y.v.size());
  const int n = std::min(nx, ny);
  int cp = 0;
  while (cp < n && same_vertex(x.v[cp], y.v[cp])) ++cp;
  int cs = 0;
  while (cs < n - cp && same_vertex(x.v[nx - 1 - cs], y.v[ny - 1 - cs])) ++cs;
  if (cs == 0) return std::nullopt;  // the camera vertex is always kept
  Way w;
  w.l = cp - 1;
  w.m = nx - cs;
  w.ka = (ny - cs) - w.l;
  if (w.kd() < 1 || w.ka < 1 || (w.kd() == 1 && w.ka == 1)) return std::nullopt;
  return w;
}

double BidirectionalMutation::split_density(const MltPath& y, int l, int na, int s) const {
  const std::vector<PathVertex>& v = y.v;
  const int ky = y.segments();
  double p = 1.0;
  for (int i = l + 1; i <= l + s; ++i) {  // light side: sampled from y_{i-1} (and y_{i-2})
    if (i == 0) {
      p *= pdf_light_origin(*ctx_, v[0]);
      continue;
    }
    p *= pdf_next_dirac(*ctx_, i >= 2 ? &v[i - 2] : nullptr, v[i - 1], v[i], TransportMode::kImportance);
  }
  for (int i = l + s + 1; i <= l + na; ++i) {  // camera side: sampled from y_{i+1} (and y_{i+2})
    p *= pdf_next_dirac(*ctx_, i + 2 <= ky ? &v[i + 2] : nullptr, v[i + 1], v[i], TransportMode::kRadiance);
  }
  return p;
}

bool BidirectionalMutation::split_connectible(const MltPath& y, int l, int s) const {
  const int c = l + s;  // y_c (light end) -- y_{c+1} (camera end) is the connecting edge
  if (c < 0) return !is_dirac_surface(y.v[0]);  // the camera subpath reached the emitter
  return !is_dirac_surface(y.v[c]) && !is_dirac_surface(y.v[c + 1]);
}

double BidirectionalMutation::density(const MltPath& x, const MltPath& y) const {
  if (y.segments() < 1 || y.segments() > max_segments_) return 0.0;
  const auto w = way_between(x, y);
  if (!w) return 0.0;
  const double pd = deletion_probability(x, w->l, w->m);
  const double pa = addition_probability(x.segments(), w->kd(), w->ka);
  if (!(pd > 0.0) || !(pa > 0.0)) return 0.0;
  const std::vector<int> splits = valid_splits(x, *w);
  if (splits.empty()) return 0.0;
  double sum = 0.0;  // Veach 1997, Sec. 11.4.2.1: every split (s', t') that can produce y
  for (int s : splits)
    if (split_connectible(y, w->l, s)) sum += split_density(y, w->l, w->na(), s);
  return pd * pa * sum / static_cast<double>(splits.size());
}

std::optional<MltPath> BidirectionalMutation::propose_way(const MltPath& x, const Way& w, int s, Uniforms& u) const {
  const int k = x.segments(), na = w.na(), t = na - s;
  if (s < 0 || t < 0) return std::nullopt;
  const std::vector<PathVertex>& xv = x.v;
  bool delta = false;
  // Light side: y_{l+1} .. y_{l+s}.
  std::vector<PathVertex> L;
  L.reserve(static_cast<size_t>(s));
  while (static_cast<int>(L.size()) < s) {
    const size_t n = L.size();
    if (w.l < 0 && n == 0) {
      auto v0 = sample_emitter_vertex(*ctx_, u);
      if (!v0) return std::nullopt;
      L.push_back(*v0);
      continue;
    }
    const PathVertex& cur = n == 0 ? xv[w.l] : L[n - 1];
    const PathVertex* prev = n >= 2 ? &L[n - 2] : n == 1 ? (w.l >= 0 ? &xv[w.l] : nullptr)
                                                         : (w.l >= 1 ? &xv[w.l - 1] : nullptr);
    auto nv = sample_next_vertex(*ctx_, prev, cur, TransportMode::kImportance, u, &delta);
    if (!nv) return std::nullopt;
    // The walk's Dirac flag on the vertex it scattered at; a kept end keeps its own, an emitter
    // vertex keeps the light's (as in lib/integrator/bdpt.cpp).
    if (n >= 1 && L[n - 1].is_surface()) L[n - 1].delta = delta;
    L.push_back(*nv);
  }
  // Camera side: y_{l+na} .. y_{l+s+1}, sampled outwards from x_m.
  std::vector<PathVertex> C;
  C.reserve(static_cast<size_t>(t));
  while (static_cast<int>(C.size()) < t) {
    const size_t n = C.size();
    const PathVertex& cur = n == 0 ? xv[w.m] : C[n - 1];
    const PathVertex* prev = n >= 2 ? &C[n - 2] : n == 1 ? &xv[w.m] : (w.m < k ? &xv[w.m + 1] : nullptr);
    auto nv = sample_next_vertex(*ctx_, prev, cur, TransportMode::kRadiance, u, &delta);
    if (!nv) return std::nullopt;
    if (n >= 1) C[n - 1].delta = delta;
    C.push_back(*nv);
  }
  MltPath y;
  y.v.reserve(static_cast<size_t>(k - w.kd() + w.ka + 1));
  for (int i = 0; i <= w.l; ++i) y.v.push_back(xv[i]);
  for (const auto& v : L) y.v.push_back(v);
  for (auto it = C.rbegin(); it != C.rend(); ++it) y.v.push_back(*it);
  for (int i = w.m; i <= k; ++i) y.v.push_back(xv[i]);
  if (y.segments() < 1 || y.segments() > max_segments_) return std::nullopt;
  // No connection through a Dirac vertex (Veach 1997, Sec. 10.3.5): such a y has f = 0 and no
  // split that could produce it has a density in the Dirac convention of lib/path/dirac.h.
  if (!split_connectible(y, w.l, s)) return std::nullopt;
  return y;
}

std::optional<MltPath> BidirectionalMutation::propose(const MltPath& x, Uniforms& u) const {
  const int k = x.segments();
  const double u_del = u.next(), u_add = u.next(), u_split = u.next();
  if (k < 1) return std::nullopt;
  // (l, m) by inversion of P_del over every valid pair.
  Way w;
  bool found = false;
  double acc = 0.0;
  for (int kd = 1; kd <= k + 1 && !found; ++kd)
    for (int l = lowest_l(x, kd); l <= k - kd; ++l) {
      const double p = deletion_probability(x, l, l + kd);
      if (!(p > 0.0)) continue;
      w.l = l;
      w.m = l + kd;  // the last valid pair takes the rounding remainder
      acc += p;
      if (u_del < acc) {
        found = true;
        break;
      }
    }
  if (acc <= 0.0) return std::nullopt;
  // ka by inversion of P_add.
  const int kd = w.kd();
  acc = 0.0;
  int ka = -1;
  for (int a = std::max(1, kd - 2); a <= kd + 2; ++a) {
    const double p = addition_probability(k, kd, a);
    if (!(p > 0.0)) continue;
    ka = a;
    acc += p;
    if (u_add < acc) break;
  }
  if (ka < 1) return std::nullopt;
  w.ka = ka;
  const std::vector<int> splits = valid_splits(x, w);
  if (splits.empty()) return std::nullopt;
  const size_t si = std::min(splits.size() - 1, static_cast<size_t>(u_split * static_cast<double>(splits.size())));
  return propose_way(x, w, splits[si], u);
}

}  // namespace tb::path_space
