// testbench.render: a scene file rendered by a registered integrator, returned as NumPy arrays
// (the pass mean and the variance of that mean per pixel and channel), so that a researcher can
// test renders from Python with the same Welch statistics `tb compare` uses (docs/python.md).
#include "python/src/render_python.h"

#include <chrono>
#include <cmath>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>

#include <fmt/format.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "app/scene_loading.h"
#include "lib/core/parallel.h"
#include "lib/film/film.h"
#include "lib/registry/integrator_registry.h"

namespace py = pybind11;

namespace tb::python {
namespace {

py::dict render(const std::string& scene, const std::string& integrator, std::optional<int64_t> spp, int64_t passes, uint64_t seed,
                const std::string& resolution, int threads, const std::map<std::string, double>& params) {
  const IntegratorInfo* integ = find_integrator(integrator);
  if (integ == nullptr) {
    std::string names;
    for (const IntegratorInfo& i : integrators()) names += (names.empty() ? "" : ", ") + i.name;
    throw py::value_error(fmt::format("render: unknown integrator '{}' (known: {})", integrator, names));
  }
  if (integrator.rfind("ramlt-", 0) == 0)
    throw py::value_error("render: the ramlt-* integrators run from `tb render` only (their partition option)");
  if (spp && *spp < 1) throw py::value_error(fmt::format("render: spp must be an integer >= 1 (got {})", *spp));
  if (passes < 1) throw py::value_error(fmt::format("render: passes must be an integer >= 1 (got {})", passes));
  if (threads < 0) throw py::value_error(fmt::format("render: threads must be an integer >= 0 (got {})", threads));
  if (const std::string err = validate_params(*integ, params); !err.empty()) throw py::value_error("render: " + err);

  const std::unique_ptr<World> world = load_scene_file(scene, resolution);  // errors name file, line and key
  RenderSettings st = fixed_work_settings(*world, spp.value_or(0), passes, seed);  // as tb render
  st.params = params;
  Film film(world->camera().width(), world->camera().height());
  int64_t done = 0;
  double seconds = 0;
  {
    py::gil_scoped_release release;
    ThreadLimit limit(static_cast<size_t>(threads));
    const auto t0 = std::chrono::steady_clock::now();
    done = integ->render(*world, st, film);
    seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  const WelchImage& w = film.welch();
  const py::ssize_t H = film.height(), W = film.width();
  py::array_t<double> mean({H, W, py::ssize_t{3}}), var({H, W, py::ssize_t{3}});
  auto m = mean.mutable_unchecked<3>();
  auto v = var.mutable_unchecked<3>();
  for (py::ssize_t y = 0; y < H; ++y)
    for (py::ssize_t x = 0; x < W; ++x) {
      const size_t p = static_cast<size_t>(y * W + x);
      const Rgb mu = w.mean(p), s2 = w.variance(p);
      const double n = static_cast<double>(w.count[p]);
      for (int c = 0; c < 3; ++c) {
        m(y, x, c) = mu[c];
        v(y, x, c) = n >= 2 ? s2[c] / n : std::nan("");  // variance of the mean; unknown from one pass
      }
    }
  py::dict out;
  out["mean"] = mean;
  out["variance_of_mean"] = var;
  out["passes"] = done;
  out["spp"] = st.spp;
  out["seconds"] = seconds;
  out["integrator"] = integrator;
  return out;
}

}  // namespace

void bind_render(py::module_& m) {
  m.def("render", &render, py::arg("scene"), py::arg("integrator") = "pt", py::arg("spp") = py::none(), py::arg("passes") = 8,
        py::arg("seed") = 1, py::arg("resolution") = "", py::arg("threads") = 0,
        py::arg("params") = std::map<std::string, double>{},
        "Render a scene file (JSON, or Mitsuba XML by content) with a registered integrator (`tb render --list`). "
        "spp samples (MCMC: mutations) per pixel (default: the scene's, else 16) split over `passes` independent passes; resolution 'WxH' "
        "overrides the camera's; threads 0 = all cores. Returns a dict: mean and variance_of_mean as (H, W, 3) "
        "arrays (variance_of_mean is NaN with one pass), passes, spp, seconds, integrator. Releases the GIL.");
}

}  // namespace tb::python
