// Convergence rate and efficiency of a registered integrator on one world (docs/validation.md F;
// validate/stats/convergence_fit.h; docs/integrator-checks.md): R independent renders at each
// sample count N = 2^k spp (fresh seeds, no sample prefix reused), the image MSE against a
// reference (an exact image, or a long render whose own estimator variance is subtracted so it
// adds no error floor in expectation), a Ceres power-law fit of RMSE against N (and against
// wall time), and the efficiency 1 / (MSE T).
//
// Whitening: the fit weighs ln RMSE_k by sqrt(2 R_k), the inverse of its standard deviation when
// MSE_hat is a mean of R independent squared errors. The image MSE is a mean over R renders of
// K pixel-channels with unequal variances s_i^2; its effective number of chi^2_1 terms is
// Satterthwaite's R (sum s_i^2)^2 / sum s_i^4 (each s_i^2 estimated by the per-pixel mean squared
// error over the replicates), which we pass as the replicate count. Pixels of one render are
// correlated for splatting estimators; the fit then sees non-white residuals and widens its
// interval (convergence_fit.h rescales the covariance by the reduced chi-square).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "lib/core/spectrum.h"
#include "lib/integrator/render_settings.h"
#include "lib/scene/world.h"
#include "validate/stats/convergence_fit.h"

namespace tb {

struct ImageConvergenceOptions {
  int log2_min = 1, log2_max = 6;  // N = 2^k samples per pixel
  int64_t replicates = 16;
  int max_depth = 5;
  uint64_t seed = 1;
  RenderSettings base;              // fault, roulette settings (spp, passes, seed are overwritten)
  stats::FitOptions fit;
};

struct ImageConvergence {
  std::string error;                // a render failed (not registered, threw)
  std::vector<stats::ConvergencePoint> points;
  stats::PowerLawFit fit, time_fit;
  stats::FloorFit floor_fit;
  double efficiency_at_max = 0.0;   // 1 / (MSE T) at the largest N
  int64_t nonfinite = 0;
  bool ok() const { return error.empty(); }
};

// truth: per pixel the reference value; truth_variance: per pixel the variance of the reference
// value itself (0 for an exact image), subtracted from each squared error; mask: pixels to leave
// out (may be empty).
ImageConvergence image_convergence(const std::string& integrator, const World& world, const std::vector<Rgb>& truth,
                                   const std::vector<Rgb>& truth_variance, const std::vector<bool>& mask,
                                   const ImageConvergenceOptions& options);

}  // namespace tb
