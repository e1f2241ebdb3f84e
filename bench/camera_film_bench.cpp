// Throughput of the camera and film: primary rays per second, add_sample and splat per second,
// and the time to write a 512x512 OpenEXR (FLOAT RGB + variance + count).
#include <benchmark/benchmark.h>

#include <filesystem>

#include "lib/camera/pinhole_camera.h"
#include "lib/camera/thin_lens_camera.h"
#include "lib/core/rng.h"
#include "lib/film/exr_io.h"
#include "lib/film/film.h"

namespace tb {
namespace {

CameraSetup setup() {
  CameraSetup s;
  s.eye = {0, 1, 5};
  s.target = {0, 0, 0};
  s.width = 512;
  s.height = 512;
  s.lens_radius = 0.1;
  s.focus_distance = 5;
  return s;
}

void BM_ThinLensGenerateRay(benchmark::State& state) {
  const ThinLensCamera cam(setup());
  Rng rng(1);
  for (auto _ : state) {
    const CameraRay r = cam.generate_ray({rng.uniform() * 512, rng.uniform() * 512}, rng.uniform2());
    benchmark::DoNotOptimize(r);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_ThinLensGenerateRay);

void BM_FilmAddSample(benchmark::State& state) {
  Film film(512, 512, state.range(0) == 0 ? std::shared_ptr<const Filter>(std::make_shared<BoxFilter>())
                                          : std::make_shared<GaussianFilter>(Vec2(1.5), 0.5));
  Rng rng(2);
  uint64_t i = 0;
  for (auto _ : state) film.add_sample({rng.uniform() * 512, rng.uniform() * 512}, Rgb(1, 0.5, 0.25), i++);
  state.SetItemsProcessed(state.iterations());
  state.SetLabel(state.range(0) == 0 ? "box" : "gaussian r=1.5");
}
BENCHMARK(BM_FilmAddSample)->Arg(0)->Arg(1);

void BM_SplatBuffer(benchmark::State& state) {
  SplatBuffer buf(512, 512);
  Rng rng(3);
  uint64_t i = 0;
  for (auto _ : state) {
    buf.splat({rng.uniform() * 512, rng.uniform() * 512}, Rgb(1, 0.5, 0.25), i++);
    if (buf.entries().size() >= (1u << 20)) buf.clear();
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_SplatBuffer);

void BM_FilmSplatDirect(benchmark::State& state) {
  Film film(512, 512);
  Rng rng(4);
  uint64_t i = 0;
  for (auto _ : state) film.splat({rng.uniform() * 512, rng.uniform() * 512}, Rgb(1, 0.5, 0.25), i++);
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_FilmSplatDirect);

void BM_WriteExr512(benchmark::State& state) {
  Film film(512, 512);
  Rng rng(5);
  for (int pass = 0; pass < 2; ++pass) {
    for (int i = 0; i < 512 * 512; ++i) film.add_sample({rng.uniform() * 512, rng.uniform() * 512}, Rgb(rng.uniform()), 0);
    film.end_pass();
  }
  const ExrImage img = exr_image_from_welch(film.welch());
  const std::string path = (std::filesystem::temp_directory_path() / "tb_bench_512.exr").string();
  for (auto _ : state) write_exr(path, img, state.range(0) == 0 ? ExrPixelType::kFloat : ExrPixelType::kHalf);
  std::filesystem::remove(path);
  state.SetLabel(state.range(0) == 0 ? "float RGB + variance + count" : "half RGB + variance + count");
}
BENCHMARK(BM_WriteExr512)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace tb
