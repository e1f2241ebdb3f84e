// Dirac (specular) vertices on the shared path representation, for estimators that evaluate f(X)
// and densities of GIVEN paths through mirrors and glass (path-space MLT, lib/mcmc/path_space).
// BDPT and the MIS weights keep the convention of path.h (Dirac densities stored as 0, read as 1);
// nothing here changes them.
//
// Convention (Veach 1997, Sec. 10.3.5 and 11.4; pbrt-v3 Sec. 14.1.3, 16.3): at a specular vertex
// the BSDF is c delta(wi - w*) / |cos wi| and the sampling density is P(lobe) delta(wi - w*); the
// delta cancels in every ratio f / p in which it appears on both sides. We store the
// "coefficients with the delta dropped":
//   f_s  := BsdfSample::f of the lobe that maps wo to wi (radiance form: c / |cos wi|, wi towards
//           the light), the value the measurement contribution multiplies in (path.h);
//   p_w  := P(lobe) for a step sampled in radiance mode (from the camera side), which is the
//           density whose delta is the same as the delta of f_s.
// A step sampled in importance mode (from the light side) carries a delta in the camera-side
// direction instead. The adjoint BSDF identity f_imp(l, c) = f_rad(c, l) (Veach 1997, Eq. 5.19,
// as distributions in the pair of directions) converts it: with the coefficients f_rad(c, l),
// f_imp(l, c) of BsdfSample::f,
//   delta_c = (f_rad(c, l) / f_imp(l, c)) delta_l,   so   p_w := P_imp(lobe) f_rad(c, l) / f_imp(l, c),
// f_imp here without the shading-normal factor of the adjoint (scattering.h), which the light
// subpath's weight carries and f(X) does not (docs/path.md, Shading normals).
// For a mirror the factor is 1; for refraction it carries
// the eta^2 and cosine ratio of the non-symmetric BTDF (Veach 1997, Sec. 5.2). With this, f / p of
// a path equals the true sampling weight whichever side sampled each specular vertex, so sums over
// the ways of sampling a path (the bidirectional mutation) and Metropolis ratios are consistent.
// Perturbations that keep the lobe (caustic / lens / multi-chain) use P(lobe) = 1 (DiracLobeChoice).
#pragma once

#include <optional>

#include "lib/path/path.h"
#include "lib/path/scattering.h"

namespace tb {

// A surface vertex whose BSDF has only Dirac lobes (smooth conductor, smooth dielectric).
bool is_dirac_surface(const PathVertex& v);

// Directions wo -> wi at a Dirac vertex: reflection (same side of the geometric normal) or
// transmission.
bool is_dirac_transmission(const PathVertex& v, const Vec3& wo, const Vec3& wi);

// The Dirac lobe of v's BSDF that maps wo to wi: the SurfaceScatter sample of that lobe (f, lobe
// probability, flags). Empty when no lobe maps wo to within kDiracAngleTolerance of wi (a
// connection through a specular vertex: zero with probability one).
std::optional<WorldBsdfSample> dirac_lobe(const PathVertex& v, const Vec3& wo, const Vec3& wi, TransportMode mode);
// The same with the lobe given (transmission or not): used to trace a specular chain.
std::optional<WorldBsdfSample> dirac_lobe_sample(const PathVertex& v, const Vec3& wo, bool transmission,
                                                 TransportMode mode);

// 1 - cos of the largest angle between a traced direction and the direction recomputed from the
// vertex positions that is taken as "the same" direction. Positions of traced hits carry float
// error ~1e-6 relative (Embree), which moves directions by ~1e-6 rad; 1e-8 is an angle of 1.4e-4,
// far above that and far below any angle by which a connection could miss by chance.
inline constexpr double kDiracCosTolerance = 1e-8;

enum class DiracLobeChoice {
  kSampled,  // the lobe was chosen by the BSDF's sampling: density includes P(lobe)
  kKept,     // the lobe is kept by a perturbation: P(lobe) = 1
};

// The density of `next` sampled from `cur` (reached from `prev`), as pdf_next of path.h, except at
// a Dirac surface vertex cur, where it is the pseudo density of the convention above converted to
// area at next (0 when no lobe maps prev to next).
double pdf_next_dirac(const PathContext& ctx, const PathVertex* prev, const PathVertex& cur, const PathVertex& next,
                      TransportMode mode, DiracLobeChoice choice = DiracLobeChoice::kSampled);

// f_s at a Dirac vertex b, radiance form: wo towards the camera, wi towards the light. Zero when
// no lobe maps wo to wi.
Rgb dirac_f(const PathVertex& b, const Vec3& wo, const Vec3& wi);

}  // namespace tb
