// The one representation of a light path (ARCHITECTURE.md, lib/path): a sequence of vertices
// x_0 ... x_k from the emitter (x_0) to the camera lens (x_k), as in Veach 1997, Ch. 8 and 10.
// Every integrator and every later MCMC mutation builds, evaluates and weights paths with these
// functions, so a density used to sample a path is the density used to weight it.
//
// Measure. A path of k segments lives in the product of the area measures of its vertices
// (Veach 1997, Eq. 8.5). Exceptions, as in pbrt-v3 (Sec. 16.3): a vertex on an infinite light
// (environment, directional) is a direction, measured in solid angle at its neighbour; the
// first surface vertex after it is then sampled on the emission disk, whose perpendicular-area
// density converts to area by the cosine at that vertex only.
//
// Measurement contribution (Veach 1997, Eq. 8.7, radiance form):
//   f(X) = Le(x_0 -> x_1) G(x_0, x_1) prod_{i=1}^{k-1} f_s(x_{i-1} -> x_i -> x_{i+1}) G(x_i, x_{i+1})
//          * We(x_k -> x_{k-1}),
// with G(x, y) = V(x, y) |cos_x| |cos_y| / |x - y|^2 with geometric normals, and the BSDF of a
// scattering vertex in its projected form with respect to the geometric normal,
// f_s(l -> c) |l.n_s| / |l.n_g| (Veach 1997, Sec. 5.3.2; l towards x_{i-1}): the measurement
// path tracing estimates when shading normals differ from geometric ones (docs/path.md, Shading
// normals). The forward axis is the normal at the lens; a point light has no cosine.
//
// Densities. For technique (s, t), s + t = k + 1, the light subpath x_0 .. x_{s-1} is sampled
// from the emitter and the camera subpath x_k .. x_s from the lens (Veach 1997, Sec. 10.2). Every
// vertex x_i has two area densities: pL[i] when it is sampled as part of a light subpath (from
// x_{i-1}, x_{i-2}) and pE[i] as part of a camera subpath (from x_{i+1}, x_{i+2}), so
//   p_{s,t}(X) = prod_{i<s} pL[i] * prod_{i>=s} pE[i]                       (Veach Eq. 10.8).
// Densities generated at a vertex that scatters by a Dirac lobe are stored as 0 and read as 1
// in ratios; techniques that would connect through such a vertex (or reach a Dirac emitter by
// chance) have density 0 (Veach 1997, Sec. 10.3.5; pbrt-v3 Sec. 16.3.4). Any other zero density
// is a real one, and every technique that needs it has density 0 (unlike pbrt-v3's remap0, which
// reads every zero as 1). The MIS weight of
// technique s is a heuristic of estimators/mis_heuristics.h applied to q_j = p_{j,k+1-j}(X) / p_s(X).
// The t = 0 techniques (light subpaths hitting the lens) are never used: lenses here are not
// scene geometry.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "lib/core/spectrum.h"
#include "lib/geometry/hit.h"
#include "lib/material/bsdf.h"
#include "lib/path/light_sampler.h"
#include "lib/path/measure.h"
#include "lib/path/scattering.h"
#include "lib/scene/world.h"

namespace tb {

enum class VertexKind : uint8_t { kCamera, kLight, kSurface };

struct PathVertex {
  VertexKind kind = VertexKind::kSurface;
  // Surface: the intersection. Light: the emitter point (full geometry for area lights; p only
  // for point lights, zero normals; unused for infinite lights). Camera: p = lens point,
  // n = ng = the camera's forward axis (the cos theta of the importance, docs/camera.md).
  Hit hit;
  const Bsdf* bsdf = nullptr;    // surface vertices that scatter
  const Light* light = nullptr;  // the emitter at this vertex (kLight, or an emitting surface)
  bool delta = false;            // scatters by a Dirac lobe (surface) / is a Dirac emitter position
  bool infinite = false;         // on an infinite light: a direction, see w_inf
  Vec3 w_inf{0.0};               // infinite light: unit direction from the scene towards the light
  Rgb beta{1.0};                 // sampling weight of the subpath up to this vertex
  double pdf_fwd = 0.0;          // area density in the direction the subpath was sampled
  double pdf_rev = 0.0;          // area density if sampled from the other end

  bool is_surface() const { return kind == VertexKind::kSurface; }
  bool is_light_kind() const { return kind == VertexKind::kLight; }
  // Can this vertex be joined to another by a deterministic connection (not a Dirac scatterer)?
  bool connectible() const;
  // A normal for cosines (zero: no cosine): shading normal on surfaces and area lights.
  Vec3 shading_normal() const { return infinite ? Vec3(0.0) : hit.n; }
  Vec3 geometric_normal() const { return infinite ? Vec3(0.0) : hit.ng; }
};

// Unit direction from vertex a towards vertex b (handles infinite vertices). Inline, as to_area:
// both run for every connection and every MIS ratio of BDPT and MMLT.
inline Vec3 direction(const PathVertex& a, const PathVertex& b) {
  if (b.infinite) return b.w_inf;
  if (a.infinite) return -a.w_inf;
  return glm::normalize(b.hit.p - a.hit.p);
}

// Environment for path evaluation: the world and the light-selection distribution.
struct PathContext {
  const World* world = nullptr;
  const LightSampler* lights = nullptr;
};

// --- Vertex-level densities (area measure, or solid angle for infinite vertices) ---------------

// Density of sampling `next` from `cur`, the path having reached `cur` from `prev` (null at a
// subpath's first vertex). mode: kRadiance when walking from the camera, kImportance from the
// light. Camera: Camera::pdf_we direction; light: emission direction (or emission disk); surface:
// the BSDF density (0 for Dirac vertices).
double pdf_next(const PathContext& ctx, const PathVertex* prev, const PathVertex& cur, const PathVertex& next,
                TransportMode mode);
// The same density, with `cur_scatter` (null: none) a SurfaceScatter already built on cur's hit
// and BSDF: a surface vertex's density is then evaluated with it instead of a fresh one, so the
// shading frames it has built are reused (the value is bitwise that of pdf_next: a frame is a
// function of the hit's normal and the side, and pdf() reads no importance correction).
double pdf_next(const PathContext& ctx, const PathVertex* prev, const PathVertex& cur, const PathVertex& next,
                TransportMode mode, const SurfaceScatter* cur_scatter);
// Area density at `to` of a direction density pdf_w (solid angle) at `from`: pdf_w itself when
// `to` is a direction (infinite light), 0 when `to` is a point light.
inline double to_area(double pdf_w, const PathVertex& from, const PathVertex& to) {
  if (to.infinite) return pdf_w;                   // solid angle is the measure of a direction
  if (to.is_light_kind() && to.delta) return 0.0;  // a point cannot be hit by chance
  return solid_angle_to_area(pdf_w, from.hit.p, to.hit.p, to.geometric_normal());
}
// Density of x_1 when emitted from x_0 (a light vertex or an emitting surface): the emission
// direction density in area measure, or the emission disk's density for infinite lights.
double pdf_light_next(const PathVertex& x0, const PathVertex& x1);
// Density of the emitter vertex x_0 when sampled by the light sampler: pmf(light) times the
// position density (area lights: area; point lights: 1; infinite lights: solid angle of w_inf).
double pdf_light_origin(const PathContext& ctx, const PathVertex& x0);
// Emitted radiance leaving x_0 towards x_1.
Rgb emitted(const PathVertex& x0, const PathVertex& x1);

// --- Whole-path evaluation (for paths given, not only sampled) ---------------------------------

// How the Dirac (specular) vertices of a given path are evaluated. kZero: f = 0 at a Dirac vertex
// and its densities stored as 0 (read as 1 in MIS ratios): the convention of BDPT and its MIS
// weights. kCoefficient / kCoefficientKeptLobe: the delta dropped from f and from the densities
// alike (lib/path/dirac.h), the densities with / without the lobe-selection probability: the
// convention of path-space MLT (lib/mcmc/path_space).
enum class DiracPolicy : uint8_t { kZero, kCoefficient, kCoefficientKeptLobe };

// f(X) for X = x_0 .. x_k (x_0 a light vertex or an emitting surface, x_k the camera).
// test_visibility: trace shadow rays for every segment (MCMC proposals); the integrators'
// sampled segments are visible by construction. The camera factor is the importance with the
// whole-image normalisation of docs/camera.md.
// dirac: kZero returns 0 for a path with a Dirac surface vertex; otherwise the Dirac vertex
// contributes its lobe coefficient (dirac.h: dirac_f), 0 when no lobe maps one neighbour onto the
// other.
Rgb measurement_contribution(const PathContext& ctx, std::span<const PathVertex> x, bool test_visibility,
                             DiracPolicy dirac = DiracPolicy::kZero);

struct PathDensities {
  std::vector<double> pL, pE;  // per vertex, see the top of this file
  std::vector<uint8_t> delta;  // Dirac scatterer / emitter flags per vertex
  bool x0_infinite = false;    // x_0 is a direction (infinite light)
  size_t size() const { return pL.size(); }
};
// pL and pE of every vertex of X, evaluated from scratch. dirac != kZero: the density of a vertex
// sampled through a Dirac vertex is the pseudo density of dirac.h (pdf_next_dirac) instead of 0.
PathDensities path_densities(const PathContext& ctx, std::span<const PathVertex> x,
                             DiracPolicy dirac = DiracPolicy::kZero);
// p_{s,t}(X), t = k + 1 - s; 0 for a technique that cannot sample X (t >= 1).
double technique_density(const PathDensities& d, int s);
// q_j / q_s for j = 0..k (0 where technique j cannot sample X); q_t=0 excluded.
void technique_ratios(const PathDensities& d, int s, std::vector<double>* q);
// The same over densities held in caller storage (BDPT's connections keep them in fixed arrays on
// the stack): n = k + 1 vertices, q has room for n ratios.
struct PathDensitySpans {
  const double* pL = nullptr;
  const double* pE = nullptr;
  const uint8_t* delta = nullptr;
  size_t n = 0;
  bool x0_infinite = false;
};
void technique_ratios(const PathDensitySpans& d, int s, double* q);

enum class MisKind { kBalance, kPower };
// MIS weight of technique s for X from its densities: BalanceHeuristic / PowerHeuristic (beta = 2)
// of estimators/mis_heuristics.h over the ratios q_j.
double mis_weight(const PathDensities& d, int s, MisKind kind);
// The same from ratios already computed (technique_ratios).
double mis_weight_from_ratios(std::span<const double> q, int s, MisKind kind);

}  // namespace tb
