// Helpers of the image-level integrator checks (validate/checks/integrator_checks.cpp,
// docs/integrator-checks.md): render a world with a registered integrator by name (a missing
// integrator is an error the check reports as a failure, never a skip), load a shipped scene at
// a small resolution, find the pixels an estimator cannot see (light tracing through a pinhole
// cannot reach a camera vertex whose first hit is a delta BSDF), and turn Welch image
// comparisons (validate/image_compare.h) into check records.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "lib/film/film.h"
#include "lib/integrator/render_settings.h"
#include "lib/scene/world.h"
#include "validate/check_result.h"
#include "validate/image_compare.h"

namespace tb {

struct RenderRun {
  std::string integrator;
  std::string error;            // non-empty: the render did not happen (not registered, threw)
  std::optional<Film> film;
  double seconds = 0.0;
  int64_t passes = 0;
  bool ok() const { return error.empty() && film.has_value(); }
  int64_t nonfinite() const { return film ? film->nonfinite().count() : 0; }
  nlohmann::json summary() const;  // integrator, seconds, passes, non-finite count, error
};

// "not registered" (with the list of registered integrators) when find_integrator fails; the
// exception text when the integrator throws (e.g. rejects a light type).
RenderRun render_with(const std::string& integrator, const World& world, const RenderSettings& settings);

std::string registered_integrator_names();

// Relative RMSE of an image against a reference, by luminance: sqrt(mean over the pixels with
// reference luminance > 0 of ((L - L_ref) / L_ref)^2); NaN when no pixel has L_ref > 0.
double luminance_rrmse(const std::vector<Rgb>& image, const std::vector<Rgb>& reference);

// The share of `visits` (per pixel, e.g. an MCMC run's mutations) that falls in the brightest
// tenth of the pixels of `ranking` (by luminance; ceil(P / 10) pixels); 0 without visits.
double bright_tenth_share(const std::vector<double>& visits, const std::vector<Rgb>& ranking);

// The scenes/ folder of the source tree: $TB_SCENES_DIR if set, else the first folder holding
// scenes/cornell-box.json found going up (at most 4 levels) from this source file's directory,
// the working directory or the running program's directory, else ./scenes.
std::string scenes_dir();
// Loads scenes/<file> with the camera resolution replaced by width x height (the JSON text is
// rewritten and loaded with load_world_from_string, relative paths against scenes/).
std::unique_ptr<World> load_scene_at_resolution(const std::string& file, int width, int height);

// Per pixel: true when some primary ray through the pixel (order x order raster positions, the
// pixel edges included) first hits a surface with a delta BSDF lobe, or a glossy one whose
// Beckmann-equivalent roughness is below `min_roughness` (0: delta only). Light tracing to a
// pinhole never samples a path whose camera vertex is followed by a delta vertex (Veach 1997,
// Sec. 10.3.5: a connection needs a non-delta vertex); through a near-specular vertex it samples
// them with a heavy-tailed estimator (the narrow lobe evaluated at a random connection), for which
// a Welch t-test on a few dozen Welch samples is not valid.
std::vector<bool> shiny_first_hit_pixels(const World& world, double min_roughness = 0.0, int order = 9);

// Per pixel: true when some primary ray (order x order positions) first hits a non-delta surface
// that sees part of an emitter through a delta surface (shadow rays to light_samples x
// light_samples stratified points of each light, sample_li, blocked first by a delta BSDF). Such
// a point receives a caustic that path tracing finds only by BSDF-sampling its way through the
// specular chain into the light: unbiased but, for a small bright light, so heavy-tailed at
// check budgets that a Welch t-test is not valid there.
std::vector<bool> caustic_receiver_pixels(const World& world, int order = 5, int light_samples = 6);

// Element-wise or.
std::vector<bool> mask_union(const std::vector<bool>& a, const std::vector<bool>& b);

// The image sum as a 1x1 WelchImage: per channel the sum of the pixel means, with the variance
// of that sum, sum_i s_i^2 / n_i (pixels independent, as for a path tracer), stored as a
// Welch-sample variance for the smallest pixel count n. Skewness of a sum of P independent
// pixels falls as 1 / sqrt(P), so the t-test on the sum is valid where per-pixel t-tests are not
// (heavy-tailed pixels); it only detects a bias of the image as a whole.
WelchImage image_sum(const WelchImage& image);

// Marks the pixels with mask[i] true as excluded in both images: both get the same two
// zero-variance Welch samples of value 0, which compare_welch_images skips as identical.
void exclude_pixels(WelchImage& a, WelchImage& b, const std::vector<bool>& mask);

// A rendered image against an exact one: where the rendered pixel-channel is deterministic up
// to rounding (standard error below 1e-12 of the exact value) and agrees with the exact value to
// `rel_tol` (e.g. a constant sky times a Lambert albedo, or a furnace traced by BSDF sampling,
// where every sample is the same number), both images get the same zero-variance value so the
// comparison skips the channel as identical instead of counting a zero-variance mismatch or a
// t statistic made of rounding noise. Returns the number of channels reconciled.
int64_t reconcile_deterministic(WelchImage& image, WelchImage& exact, double rel_tol = 1e-9);

// Per-channel comparison. compare_welch_images treats the three channels of a pixel as
// independent z's; in a rendered image they come from the same paths and are strongly
// correlated (perfectly for grey scenes), which inflates the variance of Stouffer's Z and of
// sum z^2 under H0 by up to 3x and makes them anti-conservative. Here each channel is compared
// on its own (the other two set identical, hence skipped), at Šidák(alpha, 3) each; within one
// channel the pixels of a path tracer are independent (splatting estimators correlate pixels
// weakly through shared light paths).
struct ChannelCompare {
  double alpha = 0;
  ImageCompareResult channel[3];
  bool rejects() const { return channel[0].rejects() || channel[1].rejects() || channel[2].rejects(); }
  double p_value() const;  // Šidák over the 3 channels of the smallest channel p-value
  double mean_relative_difference() const;  // over all channels
  int worst_channel() const;
  // The smallest uniform relative bias the comparison detects with 90% power: the best channel's
  // Stouffer test alone (ImageCompareResult::min_detectable_relative_bias), whatever the
  // dependence between channels.
  double min_detectable_relative_bias() const;
  std::string message() const;
  nlohmann::json details() const;
};
// `options` selects the per-pixel (default) or the tiled Welch test (validate/image_compare.h;
// docs/statistics.md "Heavy tails"), applied to each channel.
ChannelCompare compare_channels(const WelchImage& a, const WelchImage& b, double alpha,
                                const ImageCompareOptions& options = {});
// The test of the image-level agreement checks for `integrator` against a reference: the tiled
// test (k from the stored third moments) where its condition of independent pixels within a pass
// holds for the tested integrator (pt: every path adds to one pixel), the per-pixel test otherwise
// (lt and bdpt splat; their rates are in docs/statistics.md).
ImageCompareOptions agreement_compare_options(const std::string& integrator);

// A check record from one image comparison. `expect_reject` for negative controls (the check
// passes when the comparison rejects).
CheckResult compare_record(const ChannelCompare& c, bool expect_reject, const std::string& what);
CheckResult render_error_record(const RenderRun& run, const std::string& what);

}  // namespace tb
