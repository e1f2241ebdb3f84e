#include "validate/render/render_compare.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

#include "lib/core/rng.h"
#include "lib/geometry/spawn.h"
#include "lib/registry/integrator_registry.h"
#include "lib/scene/scene_loader.h"
#include "validate/stats/tests.h"
#include "validate/render/broken_integrators.h"

namespace tb {

nlohmann::json RenderRun::summary() const {
  nlohmann::json j = {{"integrator", integrator}, {"seconds", seconds}, {"passes", passes},
                      {"nonfinite", nonfinite()}};
  if (!error.empty()) j["error"] = error;
  if (film && film->nonfinite().count() > 0) j["nonfinite_summary"] = film->nonfinite().summary();
  return j;
}

std::string registered_integrator_names() {
  std::string s;
  for (const auto& i : integrators()) s += (s.empty() ? "" : ", ") + i.name;
  return s;
}

RenderRun render_with(const std::string& integrator, const World& world, const RenderSettings& settings) {
  RenderRun run;
  run.integrator = integrator;
  const RenderFunction render = find_render_function(integrator);
  if (!render) {
    run.error = fmt::format("integrator '{}' not registered (registered: {})", integrator, registered_integrator_names());
    return run;
  }
  run.film.emplace(world.camera().width(), world.camera().height());
  const auto t0 = std::chrono::steady_clock::now();
  try {
    run.passes = render(world, settings, *run.film);
  } catch (const std::exception& e) {
    run.error = fmt::format("integrator '{}' threw: {}", integrator, e.what());
  }
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (run.error.empty() && run.film->passes() < 2)
    run.error = fmt::format("integrator '{}' produced {} Welch samples per pixel (need >= 2)", integrator,
                            run.film->passes());
  return run;
}

std::string scenes_dir() {
  namespace fs = std::filesystem;
  if (const char* env = std::getenv("TB_SCENES_DIR")) return env;
  const auto holds_scenes = [](const fs::path& dir) { return fs::is_regular_file(dir / "scenes" / "cornell-box.json"); };
  std::vector<fs::path> starts;
  // This file's path as compiled (absolute unless a compiler launcher rewrote it relative to the
  // build directory), the working directory, and the directory of the running program (the
  // build directory sits inside the source tree).
  if (const fs::path here(__FILE__); here.is_absolute()) starts.push_back(here.parent_path());
  std::error_code ec;
  starts.push_back(fs::current_path(ec));
  if (const fs::path exe = fs::read_symlink("/proc/self/exe", ec); !ec) starts.push_back(exe.parent_path());
  for (fs::path dir : starts)
    for (int up = 0; up < 5 && !dir.empty(); ++up, dir = dir.parent_path()) {
      if (holds_scenes(dir)) return (dir / "scenes").string();
      if (dir == dir.parent_path()) break;
    }
  return "scenes";
}

std::unique_ptr<World> load_scene_at_resolution(const std::string& file, int width, int height) {
  const std::filesystem::path path = std::filesystem::path(scenes_dir()) / file;
  if (!std::ifstream(path)) throw std::runtime_error(fmt::format("cannot open scene {}", path.string()));
  nlohmann::json j = scene_json_from_file(path.string());  // JSON, or Mitsuba XML translated
  j.at("camera")["resolution"] = {width, height};
  return load_world_from_string(j.dump(1), path.string(), scenes_dir());
}

std::vector<bool> shiny_first_hit_pixels(const World& world, double min_roughness, int order) {
  const Camera& cam = world.camera();
  std::vector<bool> mask(size_t(cam.width()) * size_t(cam.height()), false);
  for (int y = 0; y < cam.height(); ++y)
    for (int x = 0; x < cam.width(); ++x) {
      bool delta = false;
      for (int j = 0; j < order && !delta; ++j)
        for (int i = 0; i < order && !delta; ++i) {
          // Positions from the pixel's edges inwards (raster x in [x, x + 1)): a thin delta
          // surface along an edge is caught by either neighbour.
          const Vec2 raster(x + std::min(double(i) / (order - 1), 1.0 - 1e-9),
                            y + std::min(double(j) / (order - 1), 1.0 - 1e-9));
          const auto hit = world.geometry().intersect(cam.generate_ray(raster, Vec2(0.5)).ray);
          if (!hit) continue;
          const Bsdf* b = world.surface(hit->shape_id).bsdf;
          delta = b && ((b->flags() & bsdf_flags::kDelta) || b->beckmann_roughness() < min_roughness);
        }
      mask[size_t(y) * size_t(cam.width()) + size_t(x)] = delta;
    }
  return mask;
}

std::vector<bool> caustic_receiver_pixels(const World& world, int order, int light_samples) {
  const Camera& cam = world.camera();
  const Scene& scene = world.geometry();
  std::vector<bool> mask(size_t(cam.width()) * size_t(cam.height()), false);
  const auto is_delta = [&](const Hit& h) {
    const Bsdf* b = world.surface(h.shape_id).bsdf;
    return b && (b->flags() & bsdf_flags::kDelta);
  };
  for (int y = 0; y < cam.height(); ++y)
    for (int x = 0; x < cam.width(); ++x) {
      bool caustic = false;
      for (int j = 0; j < order && !caustic; ++j)
        for (int i = 0; i < order && !caustic; ++i) {
          const Vec2 raster(x + (i + 0.5) / order, y + (j + 0.5) / order);
          const auto hit = scene.intersect(cam.generate_ray(raster, Vec2(0.5)).ray);
          if (!hit || is_delta(*hit) || !world.surface(hit->shape_id).bsdf) continue;
          for (const Light* light : world.lights())
            for (int b = 0; b < light_samples && !caustic; ++b)
              for (int a = 0; a < light_samples && !caustic; ++a) {
                const Vec2 u((a + 0.5) / light_samples, (b + 0.5) / light_samples);
                const auto ls = light->sample_li(hit->p, u);
                if (!ls) continue;
                const auto blocker = scene.intersect(spawn_ray(*hit, ls->wi));
                caustic = blocker && blocker->t < ls->distance * (1 - 1e-6) && is_delta(*blocker);
              }
        }
      mask[size_t(y) * size_t(cam.width()) + size_t(x)] = caustic;
    }
  return mask;
}

std::vector<bool> mask_union(const std::vector<bool>& a, const std::vector<bool>& b) {
  std::vector<bool> m(std::max(a.size(), b.size()), false);
  for (size_t i = 0; i < m.size(); ++i) m[i] = (i < a.size() && a[i]) || (i < b.size() && b[i]);
  return m;
}

WelchImage image_sum(const WelchImage& image) {
  WelchImage out(1, 1);
  int64_t n = 0;
  Rgb mean(0.0), var_of_sum(0.0);
  for (size_t i = 0; i < image.pixels(); ++i) {
    n = n == 0 ? image.count[i] : std::min(n, image.count[i]);
    mean += image.mean(i);
    if (image.count[i] >= 2) var_of_sum += image.variance(i) / double(image.count[i]);
  }
  out.set_from_moments(0, mean, var_of_sum * double(n), n);
  return out;
}

void exclude_pixels(WelchImage& a, WelchImage& b, const std::vector<bool>& mask) {
  for (size_t i = 0; i < mask.size(); ++i)
    if (mask[i]) {
      a.set_from_moments(i, Rgb(0.0), Rgb(0.0), 2);
      b.set_from_moments(i, Rgb(0.0), Rgb(0.0), 2);
    }
}

int64_t reconcile_deterministic(WelchImage& image, WelchImage& exact, double rel_tol) {
  constexpr double kRoundingSe = 1e-12;  // relative standard error of a sum of rounding errors
  int64_t reconciled = 0;
  for (size_t i = 0; i < image.pixels(); ++i) {
    if (image.count[i] < 2) continue;
    const double n = double(image.count[i]);
    const Rgb v = image.variance(i);
    Rgb m = image.mean(i), e = exact.mean(i), vi = v;
    for (int c = 0; c < 3; ++c) {
      const double tol = std::abs(e[c]);
      if (std::sqrt(v[c] / n) <= kRoundingSe * tol && std::abs(m[c] - e[c]) <= rel_tol * tol) {
        m[c] = e[c];
        vi[c] = 0.0;
        ++reconciled;
      }
    }
    image.set_from_moments(i, m, vi, image.count[i]);
    exact.set_from_moments(i, e, exact.variance(i), exact.count[i]);
  }
  return reconciled;
}

double ChannelCompare::p_value() const {
  const double p = std::min({channel[0].p_value(), channel[1].p_value(), channel[2].p_value()});
  return stats::sidak_adjust(p, 3);
}

double ChannelCompare::mean_relative_difference() const {
  // Each channel's mean relative difference weighted by its reference sum is not kept; the plain
  // average is what a reader wants in a message.
  return (channel[0].mean_relative_difference + channel[1].mean_relative_difference +
          channel[2].mean_relative_difference) / 3.0;
}

int ChannelCompare::worst_channel() const {
  int w = 0;
  for (int c = 1; c < 3; ++c)
    if (channel[c].p_value() < channel[w].p_value()) w = c;
  return w;
}

std::string ChannelCompare::message() const {
  const char* names = "RGB";
  std::string rel;
  for (int c = 0; c < 3; ++c) rel += fmt::format("{}{} {:+.3g}", c ? ", " : "", names[c], channel[c].mean_relative_difference);
  const int w = worst_channel();
  return fmt::format("{} (p={:.3g}); mean rel. diff {}; {}; worst channel {}: {}", rejects() ? "different" : "consistent",
                     p_value(), rel, mde_phrase(min_detectable_relative_bias()), names[w], channel[w].message());
}

double ChannelCompare::min_detectable_relative_bias() const {
  // Each channel's comparison holds one channel (the others are skipped there); the best
  // channel's, valid whatever the dependence between channels (ImageCompareResult).
  return std::min({channel[0].min_detectable_bias_channel[0], channel[1].min_detectable_bias_channel[1],
                   channel[2].min_detectable_bias_channel[2]});
}

nlohmann::json ChannelCompare::details() const {
  nlohmann::json j = {{"alpha", alpha}, {"p_value", p_value()}, {"rejects", rejects()},
                      {"min_detectable_relative_bias", mde_json(min_detectable_relative_bias())}};
  const char* names[3] = {"R", "G", "B"};
  for (int c = 0; c < 3; ++c) j[names[c]] = channel[c].details();
  return j;
}

ImageCompareOptions agreement_compare_options(const std::string& integrator) {
  ImageCompareOptions o;
  // pf1 and pfk correlate pixels only through kernels of radius r, far below a pixel's footprint at check
  // sizes (docs/mmis-paths.md): treated as independent, as pt.
  if (integrator == "pt" || integrator == "pf1" || integrator == "pfk") o.test = CompareTest::kTiled;
  return o;
}

ChannelCompare compare_channels(const WelchImage& a, const WelchImage& b, double alpha,
                                const ImageCompareOptions& options) {
  ChannelCompare r;
  r.alpha = alpha;
  const double alpha_channel = stats::sidak_alpha(alpha, 3);
  for (int c = 0; c < 3; ++c) {
    WelchImage ac = a, bc = b;
    for (size_t i = 0; i < a.pixels(); ++i)
      for (int o = 0; o < 3; ++o) {
        if (o == c) continue;
        // Identical constant samples in both images: skipped by compare_welch_images.
        ac.sum[i][o] = bc.sum[i][o] = 0.0;
        ac.sum_sq[i][o] = bc.sum_sq[i][o] = 0.0;
        if (ac.has_third_moment()) ac.sum_cu[i][o] = 0.0;
        if (bc.has_third_moment()) bc.sum_cu[i][o] = 0.0;
      }
    // A pixel with fewer than two samples in both images cannot happen (see compare_welch_images),
    // and a known reference (count < 2) keeps its count, so the skipped channels read as mean 0,
    // variance 0 on both sides.
    r.channel[c] = compare_welch_images(ac, bc, alpha_channel, options);
  }
  return r;
}

CheckResult compare_record(const ChannelCompare& c, bool expect_reject, const std::string& what) {
  CheckResult r;
  r.passed = expect_reject ? c.rejects() : !c.rejects();
  r.statistic_name = "Stouffer Z (worst channel)";
  r.statistic = c.channel[c.worst_channel()].stouffer.statistic;
  r.p_value = c.p_value();
  r.alpha = c.alpha;
  r.message = fmt::format("{}{}: {}{}", expect_reject ? "negative control (must be rejected): " : "", what,
                          expect_reject ? (c.rejects() ? "caught, " : "NOT caught, ") : "", c.message());
  r.details["compare"] = c.details();
  r.min_detectable_effect = c.min_detectable_relative_bias();
  r.effect_kind = "uniform relative bias of the image";
  return r;
}

CheckResult render_error_record(const RenderRun& run, const std::string& what) {
  CheckResult r;
  r.passed = false;
  r.statistic_name = "render error";
  r.message = fmt::format("{}: {}", what, run.error);
  r.details["render"] = run.summary();
  return r;
}

double bright_tenth_share(const std::vector<double>& visits, const std::vector<Rgb>& ranking) {
  std::vector<size_t> order(ranking.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return luminance(ranking[a]) > luminance(ranking[b]); });
  double top = 0.0, all = 0.0;
  for (size_t k = 0; k < order.size() && k < visits.size(); ++k) {
    all += visits[order[k]];
    if (k < (order.size() + 9) / 10) top += visits[order[k]];
  }
  return all > 0.0 ? top / all : 0.0;
}

double luminance_rrmse(const std::vector<Rgb>& img, const std::vector<Rgb>& ref) {
  double s = 0.0;
  int64_t n = 0;
  for (size_t i = 0; i < img.size() && i < ref.size(); ++i) {
    const double r = luminance(ref[i]);
    if (!(r > 0.0)) continue;
    const double d = (luminance(img[i]) - r) / r;
    s += d * d;
    ++n;
  }
  return n > 0 ? std::sqrt(s / static_cast<double>(n)) : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace tb
