// Registered checks of the film (lib/film): exact float EXR round trip, the Welch image
// comparison (validate/image_compare.h) accepting two independent unbiased images and rejecting
// a 2% bias (its negative control), and bit-identical splatting for 1 and 2 threads.
#include <unistd.h>

#include <filesystem>

#include <fmt/format.h>

#include "lib/core/hash.h"
#include "lib/core/parallel.h"
#include "lib/core/rng.h"
#include "lib/film/exr_io.h"
#include "lib/film/film.h"
#include "lib/film/film_parallel.h"
#include "validate/image_compare.h"
#include "validate/registry.h"

namespace tb {
namespace {

CheckResult run_exr_roundtrip(const CheckContext& ctx) {
  ExrImage img;
  img.width = 67;
  img.height = 45;
  const size_t n = size_t(img.width) * size_t(img.height);
  img.variance.emplace();
  img.count.emplace();
  for (size_t i = 0; i < n; ++i) {
    Rng rng = Rng::for_sample(ctx.seed, hash_string("film.exr.roundtrip"), i);
    // Values spanning many binades, including negatives and zero; stored as float.
    const auto f = [&] { return double(float(std::ldexp(rng.uniform() - 0.3, int(rng.uniform_below(60)) - 30))); };
    img.rgb.push_back(Rgb(f(), f(), i % 17 == 0 ? 0.0 : f()));
    img.variance->push_back(Rgb(std::abs(f()), std::abs(f()), std::abs(f())));
    img.count->push_back(rng.next_u32());
  }
  const std::string path = (std::filesystem::temp_directory_path() /
                            fmt::format("tb_film_check_{}_{}.exr", ::getpid(), ctx.seed))
                               .string();
  int64_t mismatches = 0;
  write_exr(path, img, ExrPixelType::kFloat);
  const ExrImage back = read_exr(path);
  std::filesystem::remove(path);
  if (back.width != img.width || back.height != img.height || !back.variance || !back.count) {
    mismatches = int64_t(n);
  } else {
    for (size_t i = 0; i < n; ++i)
      mismatches += (back.rgb[i] != img.rgb[i]) + ((*back.variance)[i] != (*img.variance)[i]) +
                    ((*back.count)[i] != (*img.count)[i]);
  }
  CheckResult r;
  r.passed = mismatches == 0;
  r.statistic_name = "mismatching pixels";
  r.statistic = double(mismatches);
  r.samples = int64_t(n);
  r.message = fmt::format("EXR write/read (FLOAT RGB, variance, UINT count) of {}x{}: {} mismatches", img.width,
                          img.height, mismatches);
  return r;
}

// Raw samples mu(x, y, c) * Exp(1); one pass = one Welch sample = the average of `spp` raw samples.
Film noisy_film(uint64_t seed, uint64_t key, double scale, int passes, int spp) {
  constexpr int kW = 32, kH = 24;
  Film film(kW, kH);
  for (int pass = 0; pass < passes; ++pass) {
    for (int y = 0; y < kH; ++y)
      for (int x = 0; x < kW; ++x)
        for (int s = 0; s < spp; ++s) {
          const uint64_t idx = uint64_t((pass * kH + y) * kW + x) * uint64_t(spp) + uint64_t(s);
          Rng rng = Rng::for_sample(seed, key, idx);
          const Rgb mu(0.2 + 0.02 * x, 0.3 + 0.04 * y, 1.0);
          const Rgb noise(-std::log1p(-rng.uniform()), -std::log1p(-rng.uniform()), -std::log1p(-rng.uniform()));
          film.add_sample({x + rng.uniform(), y + rng.uniform()}, scale * mu * noise, idx);
        }
    film.end_pass();
  }
  return film;
}

constexpr double kCompareAlpha = 0.01;

CheckResult run_compare(const CheckContext& ctx, bool biased) {
  const int passes = int(ctx.size(32, 64)), spp = 8;
  const Film a = noisy_film(ctx.seed, hash_string("film.welch.a"), biased ? 1.02 : 1.0, passes, spp);
  const Film b = noisy_film(ctx.seed, hash_string("film.welch.b"), 1.0, passes, spp);
  const ImageCompareResult c = compare_welch_images(a.welch(), b.welch(), kCompareAlpha);
  CheckResult r;
  r.passed = biased ? c.rejects() : !c.rejects();
  r.statistic_name = "Stouffer Z";
  r.statistic = c.stouffer.statistic;
  r.p_value = c.p_value();
  r.alpha = kCompareAlpha;
  r.samples = 2 * int64_t(passes) * spp * a.pixel_count();
  r.message = fmt::format("{}{} Welch samples of {} raw samples per pixel: {}",
                          biased ? "negative control, 2% bias (must be rejected): " : "two unbiased images: ", passes,
                          spp, c.message());
  r.details = c.details();
  return r;
}

std::vector<Rgb> splat_image(uint64_t seed, size_t threads, int64_t n) {
  ThreadLimit limit(threads);
  Film film(41, 29);
  splat_parallel(film, uint64_t(n), 1000, [&](uint64_t s, SplatBuffer& buf) {
    Rng rng = Rng::for_sample(seed, hash_string("film.splat.determinism"), s);
    const Vec2 p(rng.uniform() * 41, rng.uniform() * 29);
    buf.splat(p, Rgb(rng.uniform(), 1.0 / (1e-3 + rng.uniform()), 0.5), s);
  });
  film.end_pass(double(film.pixel_count()) / double(n));
  return film.mean_image();
}

CheckResult run_splat_determinism(const CheckContext& ctx) {
  const int64_t n = ctx.size(400000, 4000000);
  const auto one = splat_image(ctx.seed, 1, n), two = splat_image(ctx.seed, 2, n);
  int64_t mismatches = 0;
  for (size_t i = 0; i < one.size(); ++i) mismatches += (one[i] != two[i]);
  CheckResult r;
  r.passed = mismatches == 0;
  r.statistic_name = "mismatching pixels";
  r.statistic = double(mismatches);
  r.samples = 2 * n;
  r.message = fmt::format("{} splats, 1 vs 2 threads: {} of {} pixels differ", n, mismatches, one.size());
  return r;
}

TB_REGISTER_CHECK({.name = "film.exr.roundtrip",
                   .description = "OpenEXR write and read back of FLOAT RGB, variance and UINT count is exact",
                   .kind = CheckKind::kDeterministic,
                   .run = run_exr_roundtrip});
TB_REGISTER_CHECK({.name = "film.welch_compare.unbiased",
                   .description = "the per-pixel Welch t-test comparison (Sidak, Stouffer, sum z^2) accepts two "
                                  "independent unbiased noisy images, alpha 0.01",
                   .kind = CheckKind::kStatistical,
                   .run = [](const CheckContext& c) { return run_compare(c, false); }});
TB_REGISTER_CHECK({.name = "film.welch_compare.negative_control",
                   .description = "the Welch image comparison rejects an image with a 2% bias, alpha 0.01",
                   .kind = CheckKind::kStatistical,
                   .run = [](const CheckContext& c) { return run_compare(c, true); }});
TB_REGISTER_CHECK({.name = "film.splat.determinism",
                   .description = "splatting through per-chunk buffers merged in order is bit-identical for 1 and "
                                  "2 threads",
                   .kind = CheckKind::kDeterministic,
                   .run = run_splat_determinism});

}  // namespace
}  // namespace tb
