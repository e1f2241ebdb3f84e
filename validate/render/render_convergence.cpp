#include "validate/render/render_convergence.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include <fmt/format.h>

#include "lib/core/hash.h"
#include "lib/film/film.h"
#include "lib/registry/integrator_registry.h"
#include "validate/render/broken_integrators.h"

namespace tb {

ImageConvergence image_convergence(const std::string& integrator, const World& world, const std::vector<Rgb>& truth,
                                   const std::vector<Rgb>& truth_variance, const std::vector<bool>& mask,
                                   const ImageConvergenceOptions& opt) {
  ImageConvergence out;
  const RenderFunction render = find_render_function(integrator);
  if (!render) {
    out.error = fmt::format("integrator '{}' not registered", integrator);
    return out;
  }
  const size_t pixels = truth.size();
  const double R = double(opt.replicates);
  for (int k = opt.log2_min; k <= opt.log2_max; ++k) {
    const int64_t n = int64_t(1) << k;
    std::vector<double> per_channel_se(pixels * 3, 0.0);  // sum over replicates of squared errors
    double sum_mse = 0.0, sum_err = 0.0, sum_err2 = 0.0, seconds = 0.0;
    int64_t channels = 0;
    for (int64_t r = 0; r < opt.replicates; ++r) {
      RenderSettings st = opt.base;
      st.spp = n;
      st.passes = 1;
      st.max_depth = opt.max_depth;
      st.seed = hash_values(opt.seed, uint64_t(k), uint64_t(r));
      Film film(world.camera().width(), world.camera().height());
      const auto t0 = std::chrono::steady_clock::now();
      try {
        render(world, st, film);
      } catch (const std::exception& e) {
        out.error = fmt::format("integrator '{}' threw: {}", integrator, e.what());
        return out;
      }
      seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      out.nonfinite += film.nonfinite().count();
      const std::vector<Rgb> img = film.mean_image();
      double se = 0.0, err = 0.0;
      channels = 0;
      for (size_t i = 0; i < pixels; ++i) {
        if (!mask.empty() && mask[i]) continue;
        for (int c = 0; c < 3; ++c) {
          const double e = img[i][c] - truth[i][c];
          // E[(X - T)^2] = MSE(X) + Var(T) for an independent unbiased reference T.
          const double tv = truth_variance.empty() ? 0.0 : truth_variance[i][c];
          se += e * e - tv;
          err += e;
          per_channel_se[i * 3 + size_t(c)] += e * e - tv;
          ++channels;
        }
      }
      const double mse = se / double(channels), mean_err = err / double(channels);
      sum_mse += mse;
      sum_err += mean_err;
      sum_err2 += mean_err * mean_err;
    }
    // Satterthwaite's effective number of squared-error terms (see the header).
    double s1 = 0.0, s2 = 0.0;
    for (double v : per_channel_se) {
      const double m = std::max(0.0, v / R);
      s1 += m;
      s2 += m * m;
    }
    const double k_eff = s2 > 0 ? s1 * s1 / s2 : 1.0;
    stats::ConvergencePoint p;
    p.n = double(n);
    // Tiny positive floor: the subtraction of the reference variance can make an almost exact
    // estimate's MSE estimate non-positive, and the log-log fit needs rmse > 0.
    p.rmse = std::sqrt(std::max(sum_mse / R, 1e-300));
    p.replicates = std::max<int64_t>(1, int64_t(std::llround(R * k_eff)));
    p.seconds = seconds / R;
    p.mean_error = sum_err / R;
    p.error_std_error = opt.replicates > 1
                            ? std::sqrt(std::max(0.0, (sum_err2 - sum_err * sum_err / R) / (R - 1.0)) / R)
                            : 0.0;
    out.points.push_back(p);
  }
  out.fit = stats::fit_power_law(out.points, opt.fit);
  if (out.points.size() >= 4) out.floor_fit = stats::fit_power_law_with_floor(out.points, opt.fit);
  out.time_fit = stats::fit_time_power_law(out.points, opt.fit);
  out.efficiency_at_max = stats::efficiency(out.points.back());
  return out;
}

}  // namespace tb
