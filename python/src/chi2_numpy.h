// The chi-square sampler tester for samplers and densities written in Python (docs/python.md).
//
// As in Mitsuba 3's chi2 tester, the two callables are vectorised: sample(u) receives all
// uniforms of a chunk as an (m, 2) float64 array and returns the m points at once (shape (m,)
// or (m, 1) on an interval, (m, 2) on a rectangle, (m, 3) unit directions on a (hemi)sphere),
// optionally as a tuple (points, valid) where valid is a boolean (m,) array and invalid rows are
// failed samples (the C++ tester's empty optional); pdf(x) receives the quadrature points as
// one array of the same point shape and returns the (m,) densities.
//
// What is shared with the C++ tester (validate/chi2/sampler_chi2.h): the uniforms (sample i uses
// Rng::for_sample(seed, key, i).uniform2(), so the same seed gives the same samples as
// tb::chi2_test of a (Vec2) sampler), the domains and their grids, the classification of a point
// (chi2_detail::classify: outside the domain, not unit length, below the hemisphere), the
// failure cell with expected count N (1 - integral of the pdf), and Pearson's test with pooling
// (pearson_chi2_gof). What differs: the pdf is integrated over every cell with a fixed
// tensor-product 7-point Gauss-Legendre rule on s x s sub-cells (s = `subdivisions`), so that it
// can be evaluated in one vectorised call, instead of adaptive Gauss-Kronrod; a discontinuity
// inside a cell is resolved only as well as the sub-cells resolve it.
#pragma once

#include <cstdint>
#include <functional>

#include "validate/chi2/sampler_chi2.h"

namespace tb::py_bindings {

struct VectorChi2Options {
  int64_t samples = 1000000;
  uint64_t seed = 1;
  uint64_t key = 0;
  double min_expected = 5.0;
  int subdivisions = 1;          // per cell and dimension, each with a 7 x 7 Gauss-Legendre rule
  int64_t chunk = 1 << 18;       // rows per call of sample() and pdf()
  double failure_mass_floor = 1e-5;
  double unit_tolerance = 1e-6;
};

// A chunk of points as the callables exchange them: row-major, `dim` doubles per point
// (1 interval, 2 rectangle, 3 sphere), and an optional validity flag per row.
struct PointChunk {
  std::vector<double> values;
  std::vector<char> valid;  // empty: all valid
};

// sample(u (m x 2, row-major), m) -> m points; pdf(points (m x dim, row-major), m) -> m densities.
using VectorSampler = std::function<PointChunk(const std::vector<double>& u, int64_t m)>;
using VectorPdf = std::function<std::vector<double>(const std::vector<double>& points, int64_t m)>;

int point_dimension(const Chi2Domain& d);

SamplerChi2Result chi2_test_vectorized(const Chi2Domain& domain, const VectorSampler& sample, const VectorPdf& pdf,
                                       const VectorChi2Options& options);

}  // namespace tb::py_bindings
