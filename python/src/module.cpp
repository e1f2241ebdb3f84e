// The Python module `testbench` (docs/python.md): the chi-square sampler tester for vectorised
// Python samplers and densities (chi2_numpy.h), the C++ tester on built-in warps for comparison,
// and the statistics engine of validate/stats/tests.h.
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "lib/core/hash.h"
#include "lib/core/warp_sphere.h"
#include "python/src/chi2_numpy.h"
#include "python/src/render_python.h"
#include "validate/chi2/sampler_chi2.h"
#include "validate/stats/tests.h"
#include "validate/stats/welford.h"

namespace py = pybind11;
using tb::Chi2Domain;
using tb::Chi2DomainKind;
using tb::SamplerChi2Result;
using tb::Vec2;
using tb::Vec3;

namespace {

using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

const char* kind_name(Chi2DomainKind k) {
  switch (k) {
    case Chi2DomainKind::kInterval: return "interval";
    case Chi2DomainKind::kRectangle: return "rectangle";
    case Chi2DomainKind::kSphere: return "sphere";
    case Chi2DomainKind::kHemisphere: return "hemisphere";
  }
  return "?";
}

// An (m, dim) array (or (m,) when dim = 1) holding a copy of `values`.
py::array_t<double> make_points(const std::vector<double>& values, int64_t m, int dim) {
  py::array_t<double> a = dim == 1 ? py::array_t<double>({static_cast<py::ssize_t>(m)})
                                   : py::array_t<double>({static_cast<py::ssize_t>(m), static_cast<py::ssize_t>(dim)});
  std::copy(values.begin(), values.end(), a.mutable_data());
  return a;
}

// Reads an array of m points of dimension dim: shape (m, dim), or (m,) when dim = 1.
std::vector<double> read_points(const py::handle& obj, int64_t m, int dim, const char* what) {
  DoubleArray a = DoubleArray::ensure(obj);
  if (!a) throw std::invalid_argument(std::string(what) + " must return an array of float64-convertible numbers");
  const bool ok = (a.ndim() == 2 && a.shape(0) == m && a.shape(1) == dim) ||
                  (dim == 1 && a.ndim() == 1 && a.shape(0) == m);
  if (!ok) {
    std::string shape;
    for (py::ssize_t i = 0; i < a.ndim(); ++i) shape += (i ? ", " : "") + std::to_string(a.shape(i));
    throw std::invalid_argument(std::string(what) + " returned shape (" + shape + "), expected (" + std::to_string(m) +
                                ", " + std::to_string(dim) + ")" + (dim == 1 ? " or (" + std::to_string(m) + ",)" : ""));
  }
  return std::vector<double>(a.data(), a.data() + a.size());
}

SamplerChi2Result chi2_test_python(const Chi2Domain& domain, const py::function& sample, const py::function& pdf,
                                   int64_t samples, uint64_t seed, uint64_t key, double min_expected, int subdivisions,
                                   int64_t chunk) {
  tb::py_bindings::VectorChi2Options o;
  o.samples = samples;
  o.seed = seed;
  o.key = key;
  o.min_expected = min_expected;
  o.subdivisions = subdivisions;
  o.chunk = chunk;
  const int dim = tb::py_bindings::point_dimension(domain);
  const tb::py_bindings::VectorSampler draw = [&](const std::vector<double>& u, int64_t m) {
    py::array_t<double> ua({static_cast<py::ssize_t>(m), py::ssize_t{2}});
    std::copy(u.begin(), u.end(), ua.mutable_data());
    const py::object out = sample(ua);
    tb::py_bindings::PointChunk chunk_out;
    if (py::isinstance<py::tuple>(out)) {
      const py::tuple t = out.cast<py::tuple>();
      if (t.size() != 2) throw std::invalid_argument("sample must return points or a tuple (points, valid)");
      chunk_out.values = read_points(t[0], m, dim, "sample");
      const auto valid = py::array_t<bool, py::array::c_style | py::array::forcecast>::ensure(t[1]);
      if (!valid || valid.ndim() != 1 || valid.shape(0) != m)
        throw std::invalid_argument("sample: the validity mask must be a boolean array of shape (m,)");
      chunk_out.valid.assign(valid.data(), valid.data() + m);
    } else {
      chunk_out.values = read_points(out, m, dim, "sample");
    }
    return chunk_out;
  };
  const tb::py_bindings::VectorPdf density = [&](const std::vector<double>& points, int64_t m) {
    const py::object out = pdf(make_points(points, m, dim));
    return read_points(out, m, 1, "pdf");
  };
  return tb::py_bindings::chi2_test_vectorized(domain, draw, density, o);
}

// The C++ tester (adaptive Gauss-Kronrod) on a built-in warp: the reference the vectorised
// tester is compared with in python/tests.
SamplerChi2Result chi2_test_builtin(const std::string& warp, const Chi2Domain& domain, int64_t samples, uint64_t seed,
                                    uint64_t key) {
  tb::SamplerChi2Options o;
  o.samples = samples;
  o.seed = seed;
  o.key = key;
  if (warp == "uniform_sphere")
    return tb::chi2_test(domain, [](const Vec2& u) { return tb::sample_uniform_sphere(u); },
                         [](const Vec3&) { return tb::pdf_uniform_sphere(); }, o);
  if (warp == "uniform_hemisphere")
    return tb::chi2_test(domain, [](const Vec2& u) { return tb::sample_uniform_hemisphere(u); },
                         [](const Vec3& w) { return tb::pdf_uniform_hemisphere(w); }, o);
  if (warp == "cosine_hemisphere")
    return tb::chi2_test(domain, [](const Vec2& u) { return tb::sample_cosine_hemisphere(u); },
                         [](const Vec3& w) { return tb::pdf_cosine_hemisphere(w); }, o);
  throw std::invalid_argument("unknown warp '" + warp + "' (uniform_sphere, uniform_hemisphere, cosine_hemisphere)");
}

// A vectorised warp: (m, 2) uniforms -> (m, 3) directions.
template <class F>
py::array_t<double> warp_array(const DoubleArray& u, F&& f) {
  if (u.ndim() != 2 || u.shape(1) != 2) throw std::invalid_argument("uniforms must have shape (m, 2)");
  const py::ssize_t m = u.shape(0);
  py::array_t<double> out({m, py::ssize_t{3}});
  const double* in = u.data();
  double* o = out.mutable_data();
  for (py::ssize_t i = 0; i < m; ++i) {
    const Vec3 w = f(Vec2{in[2 * i], in[2 * i + 1]});
    o[3 * i] = w.x, o[3 * i + 1] = w.y, o[3 * i + 2] = w.z;
  }
  return out;
}
template <class F>
py::array_t<double> pdf_array(const DoubleArray& w, F&& f) {
  if (w.ndim() != 2 || w.shape(1) != 3) throw std::invalid_argument("directions must have shape (m, 3)");
  const py::ssize_t m = w.shape(0);
  py::array_t<double> out({m});
  const double* in = w.data();
  double* o = out.mutable_data();
  for (py::ssize_t i = 0; i < m; ++i) o[i] = f(Vec3{in[3 * i], in[3 * i + 1], in[3 * i + 2]});
  return out;
}

tb::stats::Welford welford_of(const DoubleArray& a) {
  tb::stats::Welford w;
  const double* p = a.data();
  for (py::ssize_t i = 0; i < a.size(); ++i) w.add(p[i]);
  return w;
}

std::vector<double> as_vector(const DoubleArray& a) { return std::vector<double>(a.data(), a.data() + a.size()); }

py::array_t<double> grid_array(const std::vector<double>& v, const Chi2Domain& d) {
  py::array_t<double> a({static_cast<py::ssize_t>(d.ny), static_cast<py::ssize_t>(d.nx)});
  std::copy(v.begin(), v.end(), a.mutable_data());
  return a;
}

}  // namespace

PYBIND11_MODULE(testbench, m) {
  m.doc() = "testbench: chi-square tests of samplers and the statistics engine of the C++ bench (docs/python.md)";

  py::class_<Chi2Domain>(m, "Chi2Domain",
                         "A grid over the domain of a sampler; spheres are binned in (phi, cos theta), where "
                         "d omega = d phi d cos theta, so the pdf is per solid angle.")
      .def_static("interval", &Chi2Domain::interval, py::arg("a"), py::arg("b"), py::arg("n") = 101,
                  "[a, b] with n bins; points are floats (shape (m,)), the pdf is per unit length")
      .def_static(
          "rectangle",
          [](std::pair<double, double> lo, std::pair<double, double> hi, int nx, int ny) {
            return Chi2Domain::rectangle({lo.first, lo.second}, {hi.first, hi.second}, nx, ny);
          },
          py::arg("lo"), py::arg("hi"), py::arg("nx") = 101, py::arg("ny") = 101,
          "[lo, hi] in 2D; points have shape (m, 2), the pdf is per unit area")
      .def_static("sphere", &Chi2Domain::sphere, py::arg("n_phi") = 101, py::arg("n_cos") = 51,
                  "unit directions, shape (m, 3); pdf per solid angle")
      .def_static("hemisphere", &Chi2Domain::hemisphere, py::arg("n_phi") = 101, py::arg("n_cos") = 51,
                  "unit directions with z >= 0")
      .def_static("spherical_cap", &Chi2Domain::spherical_cap, py::arg("cos_min"), py::arg("n_phi") = 101,
                  py::arg("n_cos") = 51, "unit directions with z >= cos_min")
      .def_property_readonly("kind", [](const Chi2Domain& d) { return kind_name(d.kind); })
      .def_readonly("nx", &Chi2Domain::nx)
      .def_readonly("ny", &Chi2Domain::ny)
      .def_readonly("x_min", &Chi2Domain::x_min)
      .def_readonly("x_max", &Chi2Domain::x_max)
      .def_readonly("y_min", &Chi2Domain::y_min)
      .def_readonly("y_max", &Chi2Domain::y_max)
      .def("describe", &Chi2Domain::describe)
      .def("__repr__", [](const Chi2Domain& d) { return "Chi2Domain(" + d.describe() + ")"; });

  py::class_<SamplerChi2Result>(m, "Chi2Result")
      .def("passed", &SamplerChi2Result::passed, py::arg("alpha"),
           "True iff no sample fell outside the domain and Pearson's test does not reject at alpha")
      .def_property_readonly("p_value", &SamplerChi2Result::p_value)
      .def_property_readonly("statistic", [](const SamplerChi2Result& r) { return r.gof.statistic; })
      .def_property_readonly("dof", [](const SamplerChi2Result& r) { return r.gof.dof; })
      .def_property_readonly("pooled_cells", [](const SamplerChi2Result& r) { return r.gof.pooled_cells; })
      .def_property_readonly("zero_expected_observed", [](const SamplerChi2Result& r) { return r.gof.zero_expected_observed; })
      .def_readonly("samples", &SamplerChi2Result::samples)
      .def_readonly("failed", &SamplerChi2Result::failed)
      .def_readonly("outside", &SamplerChi2Result::outside)
      .def_readonly("first_outside", &SamplerChi2Result::first_outside)
      .def_readonly("pdf_integral", &SamplerChi2Result::pdf_integral)
      .def_property_readonly("observed", [](const SamplerChi2Result& r) { return grid_array(r.observed, r.domain); },
                             "observed counts, shape (ny, nx) (row = y, i.e. cos theta on spheres)")
      .def_property_readonly("expected", [](const SamplerChi2Result& r) { return grid_array(r.expected, r.domain); },
                             "expected counts N * integral of the pdf over each cell, shape (ny, nx)")
      .def("message", &SamplerChi2Result::message)
      .def("details", [](const SamplerChi2Result& r) { return py::module_::import("json").attr("loads")(r.details().dump()); })
      .def("__repr__", [](const SamplerChi2Result& r) { return "Chi2Result(" + r.message() + ")"; });

  m.def("chi2_test", &chi2_test_python, py::arg("domain"), py::arg("sample"), py::arg("pdf"),
        py::arg("samples") = 1000000, py::arg("seed") = 1, py::arg("key") = 0, py::arg("min_expected") = 5.0,
        py::arg("subdivisions") = 1, py::arg("chunk") = 1 << 18,
        "Pearson chi-square test of a vectorised sampler against its pdf.\n"
        "sample(u): u is an (m, 2) float64 array of uniforms; returns the m points (shape (m,) on an interval,\n"
        "(m, 2) on a rectangle, (m, 3) on a sphere), or a tuple (points, valid) with a boolean mask of the\n"
        "samples that did not fail. pdf(x): x has the point shape; returns the (m,) densities.\n"
        "Sample i uses the uniforms of the stream (seed, key, i), as the C++ tester does.");
  m.def("chi2_test_builtin", &chi2_test_builtin, py::arg("warp"), py::arg("domain"), py::arg("samples") = 1000000,
        py::arg("seed") = 1, py::arg("key") = 0,
        "The C++ tester (adaptive quadrature) on a C++ warp: uniform_sphere, uniform_hemisphere, cosine_hemisphere");
  m.def("hash_string", [](const std::string& s) { return tb::hash_string(s); }, py::arg("s"),
        "The 64-bit key of a name, as the C++ checks derive stream keys");

  py::module_ warps = m.def_submodule("warps", "Vectorised C++ warps: (m, 2) uniforms -> (m, 3) directions");
  warps.def("sample_uniform_sphere", [](const DoubleArray& u) { return warp_array(u, tb::sample_uniform_sphere); });
  warps.def("pdf_uniform_sphere", [](const DoubleArray& w) { return pdf_array(w, [](const Vec3&) { return tb::pdf_uniform_sphere(); }); });
  warps.def("sample_uniform_hemisphere", [](const DoubleArray& u) { return warp_array(u, tb::sample_uniform_hemisphere); });
  warps.def("pdf_uniform_hemisphere", [](const DoubleArray& w) { return pdf_array(w, tb::pdf_uniform_hemisphere); });
  warps.def("sample_cosine_hemisphere", [](const DoubleArray& u) { return warp_array(u, tb::sample_cosine_hemisphere); });
  warps.def("pdf_cosine_hemisphere", [](const DoubleArray& w) { return pdf_array(w, tb::pdf_cosine_hemisphere); });

  // ---- Statistics (validate/stats/tests.h) --------------------------------------------------------
  namespace st = tb::stats;
  py::class_<st::TestResult>(m, "TestResult")
      .def_readonly("statistic", &st::TestResult::statistic)
      .def_readonly("p_value", &st::TestResult::p_value)
      .def_readonly("dof", &st::TestResult::dof)
      .def("rejects", &st::TestResult::rejects, py::arg("alpha"), "p_value < alpha")
      .def("__repr__", [](const st::TestResult& r) {
        return "TestResult(statistic=" + std::to_string(r.statistic) + ", p_value=" + std::to_string(r.p_value) +
               ", dof=" + std::to_string(r.dof) + ")";
      });

  m.def("z_test", &st::z_test, py::arg("mean"), py::arg("std_error"), py::arg("mu0"), "two-sided z test");
  m.def("one_sample_t_test", py::overload_cast<double, double, int64_t, double>(&st::one_sample_t_test),
        py::arg("mean"), py::arg("s"), py::arg("n"), py::arg("mu0"), "two-sided one-sample t test, dof = n - 1");
  m.def("one_sample_t_test_samples", [](const DoubleArray& x, double mu0) { return st::one_sample_t_test(welford_of(x), mu0); },
        py::arg("x"), py::arg("mu0"), "one-sample t test of an array of realisations");
  m.def("welch_t_test", py::overload_cast<double, double, int64_t, double, double, int64_t>(&st::welch_t_test),
        py::arg("mean1"), py::arg("var1"), py::arg("n1"), py::arg("mean2"), py::arg("var2"), py::arg("n2"),
        "Welch's two-sample t test (unbiased sample variances; Welch-Satterthwaite dof)");
  m.def("welch_t_test_samples", [](const DoubleArray& a, const DoubleArray& b) { return st::welch_t_test(welford_of(a), welford_of(b)); },
        py::arg("a"), py::arg("b"), "Welch's t test of two arrays of realisations");
  m.def("binomial_test", &st::binomial_test, py::arg("k"), py::arg("n"), py::arg("p"),
        "exact two-sided binomial test (as R's binom.test)");
  m.def("binomial_interval", [](int64_t k, int64_t n, double confidence) {
          const st::Interval i = st::binomial_interval(k, n, confidence);
          return std::pair{i.lo, i.hi};
        }, py::arg("k"), py::arg("n"), py::arg("confidence"), "Clopper-Pearson interval (lo, hi)");
  m.def("sidak_alpha", &st::sidak_alpha, py::arg("alpha"), py::arg("m"), "per-test level 1 - (1 - alpha)^(1/m)");
  m.def("sidak_adjust", &st::sidak_adjust, py::arg("p_min"), py::arg("m"), "family-wise p of the smallest of m p-values");
  m.def("stouffer", [](const DoubleArray& z) { return st::stouffer(as_vector(z)); }, py::arg("z"),
        "Stouffer's combined z = sum z / sqrt(P), two-sided normal p-value");
  m.def("sum_z2_test", [](const DoubleArray& z) { return st::sum_z2_test(as_vector(z)); }, py::arg("z"),
        "sum z^2 against chi-square with P dof");
  m.def(
      "ks_test",
      [](const DoubleArray& x, const py::function& cdf) {
        // cdf is vectorised: evaluated once on the sorted samples, then looked up.
        std::vector<double> sorted = as_vector(x);
        std::sort(sorted.begin(), sorted.end());
        const std::vector<double> f =
            read_points(cdf(make_points(sorted, static_cast<int64_t>(sorted.size()), 1)), static_cast<int64_t>(sorted.size()), 1, "cdf");
        return st::ks_test(sorted, [&](double v) {
          const auto it = std::lower_bound(sorted.begin(), sorted.end(), v);
          return f[static_cast<size_t>(it - sorted.begin())];
        });
      },
      py::arg("x"), py::arg("cdf"), "one-sample Kolmogorov-Smirnov test; cdf(x) is vectorised over an array");
  m.def("normal_cdf", &st::normal_cdf, py::arg("x"));
  m.def("normal_quantile", &st::normal_quantile, py::arg("p"));
  m.def("normal_two_sided_p", &st::normal_two_sided_p, py::arg("z"));
  m.def("students_t_two_sided_p", &st::students_t_two_sided_p, py::arg("t"), py::arg("dof"));
  m.def("chi_squared_sf", &st::chi_squared_sf, py::arg("x"), py::arg("dof"));
  m.def("z_test_power", &st::z_test_power, py::arg("delta"), py::arg("alpha"));
  m.def("minimal_detectable_bias", &st::minimal_detectable_bias, py::arg("std_error"), py::arg("alpha"),
        py::arg("power") = 0.9);
  tb::python::bind_render(m);
}
