// Differential-informed stratified MCMC (Zirr & Dachsbacher 2020, Sec. 4.3, 6.1, 6.5, 6.6, 6.8)
// on Veach's path-space MLT (mlt.h): the integrator mlt-stratified, run_mlt with the target
// below (MltTarget), the mutations, their T and the mixture terms unchanged.
//
// In path space. Pixel j has I_j = P int h_j f dmu (P pixels, whole-image camera normalisation,
// docs/camera.md). Let p(x) = sum_s p_{s,t}(x) (Veach 1997, Eq. 10.8; lib/path/path.h) over the
// techniques (s, t = k + 1 - s, t >= 1) with non-zero density, in the start-up's whole-image
// normalisation (raster uniform over the image): the density of the one-sample balance-heuristic
// estimator. A sample of pixel j has the density P p (its raster uniform over the pixel), so
// its estimate of I_j = P int h_j f dmu is P f / (P p): the pixel estimate of a path is
//   S(x) = Y(f(x)) / p(x)
// (the value BDPT splats; its mean over x ~ p is int Y(f) dmu, the mean pixel value). With the
// variance-bounding ratio r~(x) >= 1 (Eq. 21, below; its p(i_1) is the per-pixel raster density,
// as S is a per-pixel estimate) and the brightness B = the mean pixel value = int Y(f) dmu
// (Veach's b), Eq. 8 bounds the splat and alters the target:
//   S~ = max{ S / r~, B },   W~(x) = Y(f(x)) / S~(x) = min{ r~(x) p(x), Y(f(x)) / B }
// (Eq. 8 and its footnote form), a density with respect to mu; b~ = int W~ dmu <= 1. The chains target W~
// (acceptance of Eq. 22: min{1, W~(y) T(y -> x) / (W~(x) T(x -> y))}), splat f / W~ (of luminance
// S~, Sec. 6.1) with the expected-value weights a and 1 - a (Sec. 6.8), and are normalised by
// b~ = int W~ dmu, estimated by Veach's start-up with Y(f) replaced by W~: the sum over a
// sample's connections of w_{s,t} W~(x) / p_{s,t}(x) (start_paths.h, StartupTerm), the start
// path resampled by those terms; pass scale P b~ / M. Any W~ > 0 wherever f > 0 keeps each
// chain's image unbiased (Hoberock & Hart 2010): r~ and B only decide where the mutations go.
// Where p(x) = 0 (a path no BDPT technique samples) there is no MC estimate to bound and the
// target is Y(f) / B (the plain target, scaled), so the support is the plain MLT's.
//
// r~ (Eq. 21, Sec. 6.5) on the path read from the camera: x_k the lens, x_{k-1}, ..., x_0 the
// emitter, each vertex with its camera-walk area density pE (path_densities, Dirac vertices in
// the coefficient convention of path-space MLT), given to
// differential::subpath_variance_ratio(world, list, k + 1, s = 0, mis_reduction). With
// mis_reduction (Sec. 6.6) the last direction, towards the emitter, is left out: the MIS weights
// against next-event estimation (s = 1) control its variance. r~ = infinity (a non-Dirac
// direction of zero density) gives W~ = Y(f) / B.
//
// B: from an independent pilot of BDPT samples before the first chain (streams of its own key,
// fixed chunks: the same B for any thread count), held fixed; a pilot that finds nothing leaves
// the plain target Y(f).
#pragma once

#include <cstdint>

#include "lib/film/film.h"
#include "lib/integrator/render_settings.h"
#include "lib/mcmc/path_space/mlt.h"
#include "lib/path/path.h"
#include "lib/scene/world.h"

namespace tb::path_space {

struct StratifiedMltSettings {
  bool mis_reduction = true;  // Sec. 6.6: the last direction (towards the emitter) left out of r~
  int64_t pilot = 0;          // pilot BDPT samples for B; 0: max(1024, P)
  double brightness = 0.0;    // > 0: this B instead of a pilot (tests)
};

// W~ of a path (see the top of this file). Thread-safe.
class StratifiedPathTarget {
 public:
  StratifiedPathTarget(const PathContext& ctx, double brightness, bool mis_reduction)
      : ctx_(&ctx), B_(brightness), mis_reduction_(mis_reduction) {}
  // r~(x) of Eq. 21 on the camera-ordered path (>= 1; infinity when unbounded).
  double ratio(const MltPath& x) const;
  // p(x) = sum_s p_{s,t}(x), t >= 1 (whole-image normalisation).
  double technique_sum(const MltPath& x) const;
  // W~(x) = min{ r~ p, Y(f) / B } (Eq. 8, footnote), 0 where Y(f) = 0; Y(f) / B where p = 0.
  double operator()(const MltPath& x, const Rgb& f) const;
  double brightness() const { return B_; }

 private:
  double ratio(const MltPath& x, const PathDensities& d) const;
  const PathContext* ctx_;
  double B_;
  bool mis_reduction_;
};

// B from n BDPT samples of the pilot stream key ("mlt.stratified.pilot"): the start-up's estimate
// of int Y(f) dmu (start_paths.h: bdpt_brightness). Deterministic for any thread count.
double stratified_pilot_brightness(const PathContext& ctx, uint64_t seed, int64_t n, int max_depth);

// The MltOptions::target of mlt-stratified: runs the pilot (unless ss.brightness > 0) and returns
// W~ (or the plain target when B is not positive).
MltTarget stratified_mlt_target(const PathContext& ctx, const RenderSettings& settings,
                                const StratifiedMltSettings& ss);

// run_mlt with the stratified target; the other options (mutations, bootstrap) as given.
MltStats run_mlt_stratified(const World& world, const RenderSettings& settings, Film& film,
                            const StratifiedMltSettings& ss = {}, MltOptions options = {});

}  // namespace tb::path_space

namespace tb {
// The registered renderer (name "mlt-stratified"; parameters mis_reduction, pilot).
int64_t render_mlt_stratified(const World& world, const RenderSettings& settings, Film& film);
}  // namespace tb
