// Broken variants of mlt-stratified (lib/mcmc/path_space/stratified_mlt.h) for the negative
// controls of the image checks: each keeps the stratified target W~ of the chains (Eq. 8, 22) and
// gets one other piece of the estimator wrong.
#pragma once

#include "lib/mcmc/path_space/mlt.h"
#include "lib/mcmc/path_space/stratified_mlt.h"

namespace tb::path_space {

// The splat f / Y(f) of plain MLT with the stratified target: W~ forgotten in the splat (the
// chains are distributed by W~, so the image is weighted by W~ / Y(f) instead of 1).
inline MltOptions stratified_with_plain_splat() {
  MltOptions o;
  o.target = [](const PathContext& ctx, const RenderSettings& st) {
    MltTarget t = stratified_mlt_target(ctx, st, {});
    if (t.density) t.splat_divisor = [](const MltPath&, const Rgb& f, double) { return luminance(f); };
    return t;
  };
  return o;
}

// The start-up of plain MLT with the stratified target: b (and the start path's resampling)
// from Y(f) instead of W~, the normalisation of the wrong target.
inline MltOptions stratified_with_plain_normalisation() {
  MltOptions o;
  o.target = [](const PathContext& ctx, const RenderSettings& st) {
    MltTarget t = stratified_mlt_target(ctx, st, {});
    if (t.density) t.startup = [](const Connection& c, const MltPath&) { return luminance(c.value); };
    return t;
  };
  return o;
}

}  // namespace tb::path_space
