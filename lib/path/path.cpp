#include "lib/path/path.h"

#include <algorithm>
#include <cmath>

#include "estimators/mis_heuristics.h"
#include "lib/geometry/spawn.h"
#include "lib/path/dirac.h"
#include "lib/path/measure.h"
#include "lib/path/scattering.h"

namespace tb {

namespace {

bool is_zero(const Vec3& v) { return v.x == 0 && v.y == 0 && v.z == 0; }
double remap0(double p) { return p != 0.0 ? p : 1.0; }

}  // namespace

double pdf_light_next(const PathVertex& x0, const PathVertex& x1) {
  if (!x0.light) return 0.0;
  double pos = 0, dir = 0;
  if (x0.infinite) {
    // The emission disk: perpendicular-area density, converted to area at x1 by its cosine.
    x0.light->pdf_le(x0.hit, -x0.w_inf, &pos, &dir);
    const Vec3 n1 = x1.geometric_normal();
    return pos * (is_zero(n1) ? 1.0 : std::abs(glm::dot(n1, x0.w_inf)));
  }
  x0.light->pdf_le(x0.hit, direction(x0, x1), &pos, &dir);
  if (x0.delta && (x0.light->flags() & light_flags::kDeltaDirection)) return 0.0;
  return to_area(dir, x0, x1);
}

bool PathVertex::connectible() const {
  switch (kind) {
    case VertexKind::kCamera:
      return true;
    case VertexKind::kLight:
      return true;  // NEE reaches any emitter, Dirac ones included
    case VertexKind::kSurface:
      return bsdf != nullptr && !delta;
  }
  return false;
}

double pdf_next(const PathContext& ctx, const PathVertex* prev, const PathVertex& cur, const PathVertex& next,
                TransportMode mode) {
  return pdf_next(ctx, prev, cur, next, mode, nullptr);
}

double pdf_next(const PathContext& ctx, const PathVertex* prev, const PathVertex& cur, const PathVertex& next,
                TransportMode mode, const SurfaceScatter* cur_scatter) {
  switch (cur.kind) {
    case VertexKind::kCamera: {
      const CameraPdf p = ctx.world->camera().pdf_we(Ray{cur.hit.p, direction(cur, next)});
      return to_area(p.dir, cur, next);
    }
    case VertexKind::kLight:
      return pdf_light_next(cur, next);
    case VertexKind::kSurface:
      break;
  }
  if (!prev) return pdf_light_next(cur, next);  // an emitting surface as the first vertex
  if (!cur.bsdf || cur.delta) return 0.0;
  const Vec3 wo = direction(cur, *prev), wi = direction(cur, next);
  const double pdf_w = cur_scatter ? cur_scatter->pdf(wo, wi, mode) : SurfaceScatter(cur.hit, *cur.bsdf).pdf(wo, wi, mode);
  return to_area(pdf_w, cur, next);
}

double pdf_light_origin(const PathContext& ctx, const PathVertex& x0) {
  if (!x0.light) return 0.0;
  const double pmf = ctx.lights->pmf(x0.light);
  if (x0.light->is_delta()) return pmf;  // a Dirac mass in position or direction
  if (x0.infinite) return pmf * x0.light->pdf_li(Vec3(0.0), x0.w_inf, nullptr);
  double pos = 0, dir = 0;
  x0.light->pdf_le(x0.hit, x0.hit.n, &pos, &dir);
  return pmf * pos;
}

Rgb emitted(const PathVertex& x0, const PathVertex& x1) {
  if (!x0.light) return Rgb(0.0);
  if (x0.infinite && !x0.light->is_delta()) return x0.light->le(Vec3(0.0), x0.w_inf);
  if (x0.light->is_delta()) {
    // Intensity (point, spot) or irradiance (directional): recovered from the arrival at x1.
    const auto li = x0.light->sample_li(x1.hit.p, Vec2(0.5));
    if (!li) return Rgb(0.0);
    return x0.infinite ? li->li : li->li * (li->distance * li->distance);
  }
  return x0.light->le(x0.hit.n, direction(x0, x1));
}

Rgb measurement_contribution(const PathContext& ctx, std::span<const PathVertex> x, bool test_visibility,
                             DiracPolicy dirac) {
  const size_t k = x.size() - 1;
  if (x.size() < 2 || x[k].kind != VertexKind::kCamera) return Rgb(0.0);
  const Scene& scene = ctx.world->geometry();
  Rgb f = emitted(x[0], x[1]);
  for (size_t i = 0; i < k && !is_black(f); ++i) {
    const PathVertex &a = x[i], &b = x[i + 1];
    // The geometry term with geometric cosines (Veach 1997, Eq. 8.3: the densities of the vertices
    // are in their geometric area, measure.h), except at a scattering vertex b, whose cosine
    // towards the light side a is the shading one of the projected BSDF f_s |l.n_s| that path
    // tracing samples with (Veach 1997, Eq. 5.17): f_s |l.n_s| / |l.n_g| times G's |l.n_g|,
    // without the division (docs/path.md, Shading normals). No distance to a direction.
    double g = 1.0;
    const Vec3 w = direction(a, b);
    const bool b_scatters = i + 1 < k;
    const Vec3 na = a.geometric_normal(), nb = b_scatters ? b.shading_normal() : b.geometric_normal();
    if (!is_zero(na)) g *= std::abs(glm::dot(na, w));
    if (!is_zero(nb)) g *= std::abs(glm::dot(nb, w));
    if (!a.infinite && !b.infinite) {
      const Vec3 d = b.hit.p - a.hit.p;
      g /= glm::dot(d, d);
    }
    f *= g;
    if (test_visibility) {
      bool blocked;
      if (a.infinite || b.infinite) {
        const PathVertex& s = a.infinite ? b : a;
        blocked = scene.occluded(spawn_ray(s.hit, a.infinite ? -w : w));
      } else if (a.kind == VertexKind::kSurface && b.kind == VertexKind::kSurface) {
        blocked = scene.occluded(spawn_ray_to(a.hit, b.hit));
      } else {
        const PathVertex& s = a.kind == VertexKind::kSurface ? a : b;
        const PathVertex& o = a.kind == VertexKind::kSurface ? b : a;
        blocked = scene.occluded(spawn_ray_to(s.hit, o.hit.p));
      }
      if (blocked) return Rgb(0.0);
    }
    if (i + 1 < k) {  // scattering at b, radiance form: wo towards the camera, wi towards the light
      if (dirac != DiracPolicy::kZero && is_dirac_surface(b)) {
        f *= dirac_f(b, direction(b, x[i + 2]), direction(b, a));
        continue;
      }
      if (!b.bsdf || b.delta) return Rgb(0.0);
      f *= SurfaceScatter(b.hit, *b.bsdf).f(direction(b, x[i + 2]), direction(b, a), TransportMode::kRadiance);
    }
  }
  const double we = ctx.world->camera().importance(Ray{x[k].hit.p, direction(x[k], x[k - 1])});
  return f * we;
}

PathDensities path_densities(const PathContext& ctx, std::span<const PathVertex> x, DiracPolicy dirac) {
  const DiracLobeChoice choice =
      dirac == DiracPolicy::kCoefficientKeptLobe ? DiracLobeChoice::kKept : DiracLobeChoice::kSampled;
  const auto step = [&](const PathVertex* prev, const PathVertex& cur, const PathVertex& next, TransportMode mode) {
    return dirac == DiracPolicy::kZero ? pdf_next(ctx, prev, cur, next, mode)
                                       : pdf_next_dirac(ctx, prev, cur, next, mode, choice);
  };
  const size_t n = x.size(), k = n - 1;
  PathDensities d;
  d.pL.assign(n, 0.0);
  d.pE.assign(n, 0.0);
  d.delta.assign(n, 0);
  d.x0_infinite = x[0].infinite;
  for (size_t i = 0; i < n; ++i) d.delta[i] = x[i].delta ? 1 : 0;
  d.pL[0] = pdf_light_origin(ctx, x[0]);
  if (k >= 1 && x[1].kind != VertexKind::kCamera) d.pL[1] = pdf_light_next(x[0], x[1]);
  for (size_t i = 2; i < k; ++i) d.pL[i] = step(&x[i - 2], x[i - 1], x[i], TransportMode::kImportance);
  d.pE[k] = ctx.world->camera().pdf_we_pos(Ray{x[k].hit.p, direction(x[k], x[k - 1])});
  d.pE[k - 1] = pdf_next(ctx, nullptr, x[k], x[k - 1], TransportMode::kRadiance);
  for (size_t i = k - 1; i-- > 0;) d.pE[i] = step(&x[i + 2], x[i + 1], x[i], TransportMode::kRadiance);
  return d;
}

namespace {

// Can technique j (light subpath x_0..x_{j-1}, camera subpath x_j..x_k) sample the path?
bool technique_valid(const PathDensitySpans& d, size_t j) {
  const size_t k = d.n - 1;
  if (j > k) return false;                // t = 0: never used
  if (j == 0) return d.delta[0] == 0;     // the camera path must hit the emitter by chance
  if (j == 1 && d.x0_infinite && k == 1) return false;  // a direction cannot be joined to the lens
  return d.delta[j] == 0 && (j == 1 || d.delta[j - 1] == 0);
}

PathDensitySpans spans_of(const PathDensities& d) {
  return {d.pL.data(), d.pE.data(), d.delta.data(), d.size(), d.x0_infinite};
}

}  // namespace

void technique_ratios(const PathDensitySpans& d, int s, double* q) {
  const size_t n = d.n;
  std::fill(q, q + n, 0.0);
  const size_t ss = static_cast<size_t>(s);
  // A zero in a numerator is read as 1 only when it is the stored pseudo-density of a Dirac vertex
  // (pE[j] generated at a Dirac x_{j+1}, pL[j] at a Dirac x_{j-1}, or pL[1] at a Dirac emitter).
  // Any other zero is a real one: the BSDF or emitter cannot sample that step (a grazing
  // connection, a direction outside a lobe's support), so this technique and every one beyond it,
  // which all need the same density, cannot generate X and get q = 0. Reading it as 1 gave such
  // techniques weight and left the weights of the possible ones summing to less than one.
  // Denominators are densities of technique s, which sampled X; remap0 only guards Dirac zeros.
  const auto pe_num = [&](size_t j) { return d.pE[j] != 0.0 ? d.pE[j] : (j + 1 < n && d.delta[j + 1] ? 1.0 : 0.0); };
  const auto pl_num = [&](size_t j) { return d.pL[j] != 0.0 ? d.pL[j] : (j >= 1 && d.delta[j - 1] ? 1.0 : 0.0); };
  // Technique s itself needs all of its densities (pE[k], the lens position, is common to all).
  for (size_t i = 0; i + 1 < n; ++i)
    if ((i < ss ? pl_num(i) : pe_num(i)) == 0.0) return;
  double r = 1.0;
  if (technique_valid(d, ss)) q[ss] = 1.0;
  for (size_t j = ss; j-- > 0;) {  // x_j moves from the light subpath to the camera subpath
    r *= pe_num(j) / remap0(d.pL[j]);
    if (technique_valid(d, j)) q[j] = r;
  }
  r = 1.0;
  for (size_t j = ss + 1; j < n; ++j) {  // x_{j-1} moves from the camera subpath to the light subpath
    r *= pl_num(j - 1) / remap0(d.pE[j - 1]);
    if (technique_valid(d, j)) q[j] = r;
  }
}

void technique_ratios(const PathDensities& d, int s, std::vector<double>* q) {
  q->assign(d.size(), 0.0);
  technique_ratios(spans_of(d), s, q->data());
}

double technique_density(const PathDensities& d, int s) {
  if (!technique_valid(spans_of(d), static_cast<size_t>(s))) return 0.0;
  double p = 1.0;
  for (size_t i = 0; i < d.size(); ++i) p *= (static_cast<int>(i) < s ? d.pL[i] : d.pE[i]);
  return p;
}

double mis_weight_from_ratios(std::span<const double> q, int s, MisKind kind) {
  const size_t i = static_cast<size_t>(s);
  if (q[i] == 0.0) return 0.0;
  return kind == MisKind::kPower ? PowerHeuristic{}.weight(q, i) : BalanceHeuristic{}.weight(q, i);
}

double mis_weight(const PathDensities& d, int s, MisKind kind) {
  std::vector<double> q;
  technique_ratios(d, s, &q);
  return mis_weight_from_ratios(q, s, kind);
}

}  // namespace tb
