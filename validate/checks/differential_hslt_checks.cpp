// Registered checks of the half-vector constraint formulation (lib/differential/hslt_*.h;
// Kaplanyan, Hanika, Dachsbacher 2014; docs/hslt.md). All deterministic:
//   differential.hslt.half_vector.specular   traced specular chains have h^perp = 0 (Sec. 4.4)
//   differential.hslt.jacobian.<family>      Eq. 11 blocks A_i, B_i, C_i and the full Jacobian
//                                            against central differences, Ridders (Ceres) and a
//                                            Taylor test (validate/stats/fd_jacobian.h)
//   differential.hslt.determinant            block LU (Sec. 7) vs dense Eigen LU vs the
//                                            determinant of the finite-difference Jacobian; the
//                                            block LU solve vs the dense solve
//   differential.hslt.transfer_matrix        T_1 of Eq. 6 is the inverse of the FD derivative of
//                                            the retraced specular chain's end point
//   differential.hslt.measure                Eq. 5-6 (product of Jacobians) == Eq. 4 (direct)
// Families (validate/differential/hslt_paths.h): curved_mirrors, glass, mirror_chain (traced from
// the camera of scenes/dg-*.json through the specular chain), reflection, refraction, mixed
// (points sampled on the dg scenes' shapes and connected, k = 2 .. 8).
// Each has a negative control (validate/differential/hslt_broken.h) that must be caught.
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "lib/core/hash.h"
#include "lib/core/rng.h"
#include "lib/differential/hslt_block_lu.h"
#include "lib/differential/hslt_constraints.h"
#include "lib/differential/hslt_measure.h"
#include "validate/differential/hslt_broken.h"
#include "validate/differential/hslt_paths.h"
#include "validate/registry.h"
#include "validate/stats/fd_jacobian.h"

namespace tb {
namespace {

using BlocksFn = std::function<HsltBlocks(const HsltPath&)>;

constexpr double kSpecularTolerance = 1e-7;  // |h^perp| at a traced specular vertex
constexpr double kFdTolerance = 1e-6;        // fd_jacobian.h default: central differences and Ridders
constexpr double kLuTolerance = 1e-9;        // block LU vs dense LU: determinant and solve, relative
// Determinant of the FD Jacobian vs analytic, relative: the FD Jacobian has a relative error of
// ~4e-8 (differential.hslt.jacobian.*), which the determinant amplifies by up to cond(J)
// (|d log det| <= |J^{-1}| |dJ|), so the tolerance is 1e-6 + 1e-7 cond(J).
constexpr double kFdDetTolerance = 1e-6, kFdDetConditionFactor = 1e-7;
constexpr double kMeasureTolerance = 1e-8;   // Eq. 5 vs Eq. 4, relative
constexpr double kMaxCondition = 1e6;        // determinant comparisons skip worse-conditioned J

int path_count(const CheckContext& ctx) { return static_cast<int>(ctx.size(24, 160)); }

const std::vector<std::string>& traced_families() {
  static const std::vector<std::string> f{"curved_mirrors", "glass", "mirror_chain"};
  return f;
}

nlohmann::json length_histogram(const HsltPathSet& set) {
  std::map<int, int> h;
  for (const HsltPath& p : set.paths) ++h[p.segments()];
  nlohmann::json j = nlohmann::json::object();
  for (auto [k, c] : h) j[std::to_string(k)] = c;
  return j;
}

// --- specular chains ------------------------------------------------------------------------------

CheckResult run_specular(const CheckContext& ctx, bool broken) {
  double worst = 0, worst_refraction = 0;
  int64_t vertices = 0, refractions = 0, paths = 0;
  nlohmann::json per = nlohmann::json::object();
  for (const std::string& fam : traced_families()) {
    const HsltPathSet set = hslt_path_set(fam, path_count(ctx), ctx.seed);
    double fam_worst = 0;
    for (const HsltPath& p : set.paths) {
      ++paths;
      const Eigen::VectorXd c = broken ? hslt_constraints_swapped_eta(p) : hslt_constraints(p);
      for (int r = 0; r < p.interior_count(); ++r) {
        const HsltVertex& v = p.vertices[static_cast<size_t>(r + 1)];
        const double e = std::hypot(c[2 * r], c[2 * r + 1]);
        ++vertices;
        if (v.eta_prev != v.eta_next) {
          ++refractions;
          worst_refraction = std::max(worst_refraction, e);
        }
        fam_worst = std::max(fam_worst, e);
      }
    }
    worst = std::max(worst, fam_worst);
    per[fam] = {{"paths", set.paths.size()}, {"attempts", set.attempts}, {"worst_h_perp", fam_worst},
                {"lengths", length_histogram(set)}};
  }
  CheckResult r;
  r.passed = worst < kSpecularTolerance && refractions > 0 && vertices > 0;
  r.statistic_name = "max |h_perp|";
  r.statistic = worst;
  r.samples = paths;
  r.message = fmt::format("{} traced paths, {} specular vertices ({} refractions): worst |h_perp| {:.3g} "
                          "(refractions {:.3g}), tolerance {:g}",
                          paths, vertices, refractions, worst, worst_refraction, kSpecularTolerance);
  r.details = {{"families", per}, {"tolerance", kSpecularTolerance}, {"refraction_vertices", refractions},
               {"worst_refraction_h_perp", worst_refraction}};
  return r;
}

// --- Jacobian against finite differences ------------------------------------------------------------

struct JacobianStats {
  int64_t paths = 0, checked = 0, skipped = 0, failed = 0;
  double worst = 0, worst_ridders = 0, worst_slope_dev = 0, max_cond = 0;
  std::vector<double> conds;
  double block_worst[3] = {0, 0, 0};  // A, B, C
  int64_t block_checked = 0, block_failed = 0, block_skipped = 0;
  int64_t first_failure = -1;
  nlohmann::json first_failure_point = nlohmann::json::object();
  void add(const stats::FdPointResult& p, int64_t index, bool full) {
    if (p.skipped) {
      ++(full ? skipped : block_skipped);
      return;
    }
    ++(full ? checked : block_checked);
    if (!p.passed) {
      ++(full ? failed : block_failed);
      if (first_failure < 0) {
        first_failure = index;
        first_failure_point = {{"full_jacobian", full},     {"rel_error", p.rel_error},
                               {"ridders_rel_error", p.ridders_rel_error}, {"taylor_slope", p.taylor_slope},
                               {"condition_number", p.condition_number}};
      }
    }
    if (full) {
      worst = std::max(worst, p.rel_error);
      worst_ridders = std::max(worst_ridders, p.ridders_rel_error);
      if (std::isfinite(p.taylor_slope)) worst_slope_dev = std::max(worst_slope_dev, std::abs(p.taylor_slope - 2.0));
      max_cond = std::max(max_cond, p.condition_number);
      conds.push_back(p.condition_number);
    }
  }
};

JacobianStats jacobian_stats(const HsltPathSet& set, const BlocksFn& blocks_fn, uint64_t seed) {
  const World& world = hslt_family_world(set.name);
  const Scene& scene = world.geometry();
  stats::FdOptions o;
  o.tolerance = o.ridders_tolerance = kFdTolerance;
  o.taylor_h0 = 0.1;  // chart units: 3e-4 scene units down to 2.3e-6 (8 halvings)
  o.seed = seed;
  JacobianStats st;
  for (size_t pi = 0; pi < set.paths.size(); ++pi) {
    const HsltPath& path = set.paths[pi];
    ++st.paths;
    const std::vector<int> free = hslt_free_vertices(path);
    const HsltFdChart chart = hslt_fd_chart(path, free);
    const Eigen::VectorXd x0 = Eigen::VectorXd::Zero(chart.uv0.size());
    // The full Jacobian dH^perp / d(free (u, v)), in the chart of hslt_paths.h.
    const stats::VectorFunction f = [&](const Eigen::VectorXd& x) {
      return chart.value(hslt_constraints(hslt_path_at(scene, path, free, chart.uv(x))));
    };
    const stats::JacobianFunction jac = [&](const Eigen::VectorXd& x) {
      return chart.jacobian(
          hslt_free_columns(hslt_full_jacobian(blocks_fn(hslt_path_at(scene, path, free, chart.uv(x)))), free));
    };
    st.add(stats::check_jacobian_at(f, jac, x0, o, pi), static_cast<int64_t>(pi), true);
    // Each block on its own: h_i^perp as a function of the (u, v) of one neighbour, against
    // central differences and Ridders. The Taylor test runs on the full Jacobian only: along a
    // random direction in 2 coordinates the quadratic term can be small against the cubic one
    // over the step range (slopes up to 2.9 seen on correct blocks), which is no error of J.
    stats::FdOptions ob = o;
    ob.taylor = false;
    const HsltBlocks b = blocks_fn(path);
    for (int r = 0; r < path.interior_count(); ++r) {
      for (int which = 0; which < 3; ++which) {
        const int j = r + which;  // vertex index of the moved neighbour (A: i-1, B: i, C: i+1)
        if (!path.vertices[static_cast<size_t>(j)].on_surface) continue;
        const std::vector<int> one{j};
        const HsltFdChart cb = hslt_fd_chart(path, one);
        const Eigen::VectorXd y0 = Eigen::VectorXd::Zero(2);
        const stats::VectorFunction fb = [&, r](const Eigen::VectorXd& y) {
          const Vec2 hp = hslt_half_vector(hslt_path_at(scene, path, one, cb.uv(y)), r + 1).h_perp;
          return cb.value(Eigen::Vector2d(hp.x, hp.y));
        };
        const auto ur = static_cast<size_t>(r);
        const Eigen::Matrix2d blk = which == 0 ? b.A[ur] : which == 1 ? b.B[ur] : b.C[ur];
        // The block at delta = 0 (the check evaluates the Jacobian at y0 only).
        const stats::JacobianFunction jb = [&](const Eigen::VectorXd&) { return cb.jacobian(Eigen::MatrixXd(blk)); };
        const stats::FdPointResult p = stats::check_jacobian_at(fb, jb, y0, ob, pi * 64 + static_cast<size_t>(3 * r + which));
        st.add(p, static_cast<int64_t>(pi), false);
        if (!p.skipped) st.block_worst[which] = std::max(st.block_worst[which], p.rel_error);
      }
    }
  }
  return st;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

CheckResult jacobian_result(const JacobianStats& st, const HsltPathSet& set) {
  CheckResult r;
  r.passed = st.failed == 0 && st.block_failed == 0 && st.checked > 0 && st.skipped * 2 < st.paths;
  r.statistic_name = "max rel. error";
  r.statistic = std::max({st.worst, st.block_worst[0], st.block_worst[1], st.block_worst[2]});
  r.samples = st.paths;
  r.message = fmt::format(
      "{}: {} paths, full J worst rel. error {:.3g} (Ridders {:.3g}), blocks A/B/C {:.3g}/{:.3g}/{:.3g}, "
      "full J Taylor |slope-2| <= {:.3g}, cond max {:.3g} median {:.3g}; {} failed, {} skipped, {} of {} blocks failed "
      "(tolerance {:g}, slope 2 +- 0.1)",
      set.name, st.paths, st.worst, st.worst_ridders, st.block_worst[0], st.block_worst[1], st.block_worst[2],
      st.worst_slope_dev, st.max_cond, median(st.conds), st.failed, st.skipped, st.block_failed, st.block_checked,
      kFdTolerance);
  r.details = {{"paths", st.paths},
               {"attempts", set.attempts},
               {"lengths", length_histogram(set)},
               {"checked", st.checked},
               {"skipped", st.skipped},
               {"failed", st.failed},
               {"first_failure_path", st.first_failure},
               {"first_failure", st.first_failure_point},
               {"worst_rel_error", st.worst},
               {"worst_ridders_rel_error", st.worst_ridders},
               {"worst_taylor_slope_deviation", st.worst_slope_dev},
               {"max_condition_number", st.max_cond},
               {"median_condition_number", median(st.conds)},
               {"block_worst_rel_error", {{"A", st.block_worst[0]}, {"B", st.block_worst[1]}, {"C", st.block_worst[2]}}},
               {"blocks_checked", st.block_checked},
               {"blocks_failed", st.block_failed},
               {"blocks_skipped", st.block_skipped},
               {"tolerance", kFdTolerance}};
  return r;
}

CheckResult run_jacobian(const CheckContext& ctx, const std::string& family) {
  const HsltPathSet set = hslt_path_set(family, path_count(ctx), ctx.seed);
  return jacobian_result(jacobian_stats(set, hslt_constraint_blocks, ctx.seed), set);
}

// Negative control: the broken blocks must fail the FD check on every listed family.
CheckResult run_jacobian_negative(const CheckContext& ctx, const BlocksFn& broken,
                                  const std::vector<std::string>& families, const std::string& what) {
  CheckResult r;
  r.passed = true;
  int64_t paths = 0, caught = 0;
  nlohmann::json per = nlohmann::json::object();
  std::string msg;
  for (const std::string& fam : families) {
    const HsltPathSet set = hslt_path_set(fam, path_count(ctx), ctx.seed);
    const JacobianStats st = jacobian_stats(set, broken, ctx.seed);
    const CheckResult inner = jacobian_result(st, set);
    r.passed = r.passed && !inner.passed;
    paths += st.paths;
    caught += st.failed;
    per[fam] = {{"caught", !inner.passed}, {"failed_paths", st.failed}, {"paths", st.paths},
                {"worst_rel_error", st.worst}};
    msg += fmt::format("{}{} {}/{} paths caught (worst {:.3g})", msg.empty() ? "" : "; ", fam, st.failed, st.paths,
                       st.worst);
  }
  r.statistic_name = "paths caught";
  r.statistic = static_cast<double>(caught);
  r.samples = paths;
  r.message = what + ": " + msg + (r.passed ? " - caught on every family" : " - NOT caught on some family");
  r.details = {{"families", per}, {"tolerance", kFdTolerance}};
  return r;
}

// --- determinant and solve ---------------------------------------------------------------------------

// Central differences with step scale * eps^(1/3) * max(1, |x_c|), as fd_jacobian.h.
Eigen::MatrixXd central_jacobian(const stats::VectorFunction& f, const Eigen::VectorXd& x, double scale) {
  const Eigen::VectorXd fx = f(x);
  Eigen::MatrixXd J(fx.size(), x.size());
  for (Eigen::Index c = 0; c < x.size(); ++c) {
    const double h0 = scale * std::cbrt(std::numeric_limits<double>::epsilon()) * std::max(1.0, std::abs(x[c]));
    Eigen::VectorXd xp = x, xm = x;
    xp[c] += h0;
    xm[c] -= h0;
    J.col(c) = (f(xp) - f(xm)) / (xp[c] - xm[c]);
  }
  return J;
}

double rel_diff(double a, double b) { return std::abs(a - b) / std::max(std::abs(b), 1e-300); }

CheckResult run_determinant(const CheckContext& ctx, bool broken) {
  double worst_lu = 0, worst_fd = 0, worst_fd_raw = 0, worst_solve = 0, max_cond = 0;
  int64_t checked = 0, skipped = 0, lu_failed = 0, total = 0, fd_checked = 0, fd_skipped = 0;
  nlohmann::json per = nlohmann::json::object();
  for (const std::string& fam : hslt_families()) {
    const HsltPathSet set = hslt_path_set(fam, path_count(ctx), ctx.seed);
    const Scene& scene = hslt_family_world(fam).geometry();
    double fam_lu = 0, fam_fd = 0, fam_fd_raw = 0;
    for (size_t pi = 0; pi < set.paths.size(); ++pi) {
      const HsltPath& path = set.paths[pi];
      ++total;
      const HsltBlocks b = hslt_constraint_blocks(path);
      const Eigen::MatrixXd J = hslt_dense_jacobian(b);
      const Eigen::JacobiSVD<Eigen::MatrixXd> svd(J);
      const double cond = svd.singularValues()(0) / svd.singularValues().tail<1>()(0);
      if (!(cond <= kMaxCondition)) {
        ++skipped;
        continue;
      }
      max_cond = std::max(max_cond, cond);
      const HsltBlockLu lu(b);
      if (!lu.ok()) {
        ++lu_failed;
        continue;
      }
      ++checked;
      bool continue_fd = true;
      const Eigen::PartialPivLU<Eigen::MatrixXd> dense(J);
      const double det_dense = dense.determinant();
      const double det_lu = broken ? hslt_determinant_without_schur(b) : lu.determinant();
      // Interior vertices only: the square J of Eq. 11, differentiated in the chart of hslt_paths.h
      // (det_chart = det_uv prod(scale) / length^(2n)), at steps h and h/2 (disagreement: skip).
      std::vector<int> interior;
      for (int i = 1; i <= path.interior_count(); ++i) interior.push_back(i);
      const HsltFdChart chart = hslt_fd_chart(path, interior);
      const stats::VectorFunction fc = [&](const Eigen::VectorXd& x) {
        return chart.value(hslt_constraints(hslt_path_at(scene, path, interior, chart.uv(x))));
      };
      const Eigen::VectorXd zero = Eigen::VectorXd::Zero(chart.uv0.size());
      const Eigen::MatrixXd Jfd = central_jacobian(fc, zero, 1.0), Jfd2 = central_jacobian(fc, zero, 0.5);
      if (continue_fd && (Jfd - Jfd2).cwiseAbs().maxCoeff() > 1e-4 * std::max(1.0, Jfd2.cwiseAbs().maxCoeff())) {
        ++fd_skipped;
        continue_fd = false;
      }
      double to_chart = 1.0;
      for (Eigen::Index c = 0; c < chart.scale.size(); ++c) to_chart *= chart.scale[c] / chart.length;
      const double det_fd = Jfd2.determinant() / to_chart;
      if (continue_fd) ++fd_checked;
      Rng rng = Rng::for_sample(ctx.seed, hash_string("differential.hslt.determinant." + fam), pi);
      Eigen::VectorXd rhs(J.rows());
      for (Eigen::Index i = 0; i < rhs.size(); ++i) rhs[i] = 2 * rng.uniform() - 1;
      const Eigen::VectorXd x_lu = lu.solve(rhs), x_dense = dense.solve(rhs);
      const double e_lu = std::max(rel_diff(det_lu, det_dense), rel_diff(std::exp(lu.log_abs_determinant()), std::abs(det_dense)));
      const double e_fd_raw = continue_fd ? rel_diff(det_lu, det_fd) : 0.0;
      const double e_fd = e_fd_raw / (kFdDetTolerance + kFdDetConditionFactor * cond);  // <= 1: pass
      fam_fd_raw = std::max(fam_fd_raw, e_fd_raw);
      const double e_solve = (x_lu - x_dense).norm() / x_dense.norm();
      fam_lu = std::max(fam_lu, e_lu);
      fam_fd = std::max(fam_fd, e_fd);
      worst_solve = std::max(worst_solve, e_solve);
    }
    worst_lu = std::max(worst_lu, fam_lu);
    worst_fd = std::max(worst_fd, fam_fd);
    worst_fd_raw = std::max(worst_fd_raw, fam_fd_raw);
    per[fam] = {{"paths", set.paths.size()}, {"lengths", length_histogram(set)}, {"worst_lu_vs_dense", fam_lu},
                {"worst_vs_fd", fam_fd_raw}, {"worst_vs_fd_over_tolerance", fam_fd}};
  }
  const bool ok = worst_lu < kLuTolerance && worst_fd < 1.0 && worst_solve < kLuTolerance &&
                  lu_failed == 0 && checked > 0 && skipped * 2 < total && fd_checked * 2 > checked;
  CheckResult r;
  r.passed = broken ? !ok : ok;
  r.statistic_name = "max rel. error";
  r.statistic = std::max(worst_lu, worst_fd_raw);
  r.samples = checked;
  r.message = fmt::format(
      "{}{} paths ({} skipped with cond > {:g}; {} singular pivots): |det| block LU vs dense {:.3g} (tol {:g}), "
      "solve {:.3g} (tol {:g}); vs FD Jacobian worst {:.3g}, worst error / (1e-6 + 1e-7 cond) {:.3g} (must be < 1) "
      "on {} paths ({} with FD step disagreement not compared); max cond {:.3g}",
      broken ? (ok ? "broken LU NOT caught: " : "broken LU caught: ") : "", checked, skipped, kMaxCondition, lu_failed,
      worst_lu, kLuTolerance, worst_solve, kLuTolerance, worst_fd_raw, worst_fd, fd_checked, fd_skipped, max_cond);
  r.details = {{"families", per},          {"worst_lu_vs_dense", worst_lu}, {"worst_vs_fd", worst_fd_raw},
               {"worst_vs_fd_over_tolerance", worst_fd},
               {"worst_solve", worst_solve}, {"skipped", skipped},          {"singular_pivots", lu_failed},
               {"fd_compared", fd_checked}, {"fd_not_compared", fd_skipped},
               {"max_condition_number", max_cond}};
  return r;
}

// --- measure -----------------------------------------------------------------------------------------

CheckResult run_measure(const CheckContext& ctx, bool broken) {
  double worst = 0;
  int64_t checked = 0, skipped = 0, total = 0;
  nlohmann::json per = nlohmann::json::object();
  for (const std::string& fam : hslt_families()) {
    const HsltPathSet set = hslt_path_set(fam, path_count(ctx), ctx.seed);
    double fam_worst = 0, example_direct = 0, example_product = 0;
    for (const HsltPath& path : set.paths) {
      ++total;
      const Eigen::MatrixXd J = hslt_dense_jacobian(hslt_constraint_blocks(path));
      const Eigen::JacobiSVD<Eigen::MatrixXd> svd(J);
      const double cond = svd.singularValues()(0) / svd.singularValues().tail<1>()(0);
      const HsltMeasureTerms t = hslt_measure_terms(path);
      if (!(cond <= kMaxCondition) || !t.ok) {
        ++skipped;
        continue;
      }
      ++checked;
      const double direct = hslt_measure_direct(t);
      const double product = broken ? hslt_measure_product_without_projection(t) : hslt_measure_product(t);
      const double e = rel_diff(product, direct);
      if (e >= fam_worst) {
        fam_worst = e;
        example_direct = direct;
        example_product = product;
      }
    }
    worst = std::max(worst, fam_worst);
    per[fam] = {{"paths", set.paths.size()}, {"worst_rel_diff", fam_worst}, {"worst_direct", example_direct},
                {"worst_product", example_product}};
  }
  const bool ok = worst < kMeasureTolerance && checked > 0 && skipped * 2 < total;
  CheckResult r;
  r.passed = broken ? !ok : ok;
  r.statistic_name = "max rel. difference";
  r.statistic = worst;
  r.samples = checked;
  r.message = fmt::format("{}{} paths ({} skipped with cond > {:g}): Eq. 5-6 product of Jacobians vs Eq. 4 direct "
                          "form, worst relative difference {:.3g} (tolerance {:g})",
                          broken ? (ok ? "missing |<h,n>| NOT caught: " : "missing |<h,n>| caught: ") : "", checked,
                          skipped, kMaxCondition, worst, kMeasureTolerance);
  r.details = {{"families", per}, {"tolerance", kMeasureTolerance}, {"skipped", skipped}};
  return r;
}

// --- transfer matrix (Eq. 6) against retracing ------------------------------------------------------

// max |M_fd T_1 - I| / max(1, cond(T_1)), M_fd = d(u,v)_k / d(u,v)_1 by FD (Richardson)
constexpr double kTransferTolerance = 1e-6;

CheckResult run_transfer(const CheckContext& ctx, const BlocksFn& blocks_fn, bool broken) {
  double worst = 0, worst_det = 0, max_cond = 0;
  int64_t checked = 0, skipped = 0, total = 0, failed = 0;
  nlohmann::json per = nlohmann::json::object();
  for (const std::string& fam : traced_families()) {
    const World& world = hslt_family_world(fam);
    const HsltPathSet set = hslt_path_set(fam, path_count(ctx), ctx.seed);
    double fam_worst = 0;
    int64_t fam_failed = 0;
    for (const HsltPath& path : set.paths) {
      ++total;
      Eigen::Matrix2d t1;
      if (!hslt_transfer_matrix(blocks_fn(path), &t1)) {
        ++skipped;
        continue;
      }
      // Central differences of the retraced end point, steps of 1e-5 and 5e-6 scene units at x_1.
      const HsltVertex& v1 = path.vertices[1];
      const double step[2] = {1e-5 / glm::length(v1.dpdu), 1e-5 / glm::length(v1.dpdv)};
      Eigen::Matrix2d m[2];
      bool ok = true;
      for (int s = 0; s < 2 && ok; ++s) {
        for (int c = 0; c < 2 && ok; ++c) {
          Vec2 up = v1.uv, um = v1.uv;
          const double h = step[c] / (1 << s);
          up[c] += h;
          um[c] -= h;
          const std::optional<Vec2> a = retrace_hslt_specular_endpoint(world, path, up);
          const std::optional<Vec2> b = retrace_hslt_specular_endpoint(world, path, um);
          if (!a || !b) ok = false;
          else m[s].col(c) = Eigen::Vector2d(a->x - b->x, a->y - b->y) / (up[c] - um[c]);
        }
      }
      // h and h/2 disagree: an edge of the surface or of the chain's topology nearby.
      if (!ok || (m[0] - m[1]).cwiseAbs().maxCoeff() > 1e-3 * std::max(1.0, m[1].cwiseAbs().maxCoeff())) {
        ++skipped;
        continue;
      }
      ++checked;
      // One Richardson step removes the O(h^2) truncation of the central differences.
      const Eigen::Matrix2d mr = (4.0 * m[1] - m[0]) / 3.0;
      const Eigen::JacobiSVD<Eigen::Matrix2d> svd(t1);
      const double cond = svd.singularValues()(0) / svd.singularValues()(1);
      max_cond = std::max(max_cond, cond);
      // An error dM of the FD derivative shows as dM T_1, up to cond(T_1) |dM| |M|: the
      // tolerance is relative to cond(T_1) (Richardson-extrapolated FD: |dM| / |M| ~ 1e-9).
      const double e = (mr * t1 - Eigen::Matrix2d::Identity()).cwiseAbs().maxCoeff() / std::max(1.0, cond);
      worst_det = std::max(worst_det, std::abs(mr.determinant() * t1.determinant() - 1.0));
      fam_worst = std::max(fam_worst, e);
      if (!(e < kTransferTolerance)) ++fam_failed;
    }
    failed += fam_failed;
    worst = std::max(worst, fam_worst);
    per[fam] = {{"paths", set.paths.size()}, {"worst", fam_worst}, {"failed", fam_failed}};
  }
  const bool ok = failed == 0 && checked > 0 && skipped * 2 < total;
  CheckResult r;
  r.passed = broken ? !ok : ok;
  r.statistic_name = "max |M_fd T_1 - I| / cond(T_1)";
  r.statistic = worst;
  r.samples = checked;
  r.message = fmt::format("{}{} traced paths ({} skipped): T_1 (Eq. 6, block LU) times the FD derivative of the "
                          "retraced end point, worst |M T_1 - I| / max(1, cond T_1) {:.3g} (tolerance {:g}), "
                          "|det M det T_1 - 1| {:.3g}, max cond(T_1) {:.3g}; {} failed",
                          broken ? (ok ? "broken NOT caught: " : "broken caught: ") : "", checked, skipped, worst,
                          kTransferTolerance, worst_det, max_cond, failed);
  r.details = {{"families", per}, {"tolerance", kTransferTolerance}, {"skipped", skipped},
               {"worst_det_deviation", worst_det}, {"max_condition_number", max_cond}};
  return r;
}

// --- registration --------------------------------------------------------------------------------

struct HsltChecks {
  HsltChecks() {
    auto& reg = Registry::global();
    reg.add({.name = "differential.hslt.half_vector.specular",
             .description = "Specular chains traced from the camera of scenes/dg-*.json have h_perp = 0 at every "
                            "reflection and refraction (Kaplanyan 2014, Sec. 4.4, App. A), |h_perp| < 1e-7",
             .kind = CheckKind::kDeterministic,
             .run = [](const CheckContext& ctx) { return run_specular(ctx, false); }});
    reg.add({.name = "differential.hslt.half_vector.specular.swapped_eta.negative_control",
             .description = "The refractive indices of the two sides swapped: traced refractions must show h_perp != 0",
             .kind = CheckKind::kDeterministic,
             .run = [](const CheckContext& ctx) {
               CheckResult r = run_specular(ctx, true);
               r.passed = !r.passed && r.details.value("refraction_vertices", 0) > 0;
               r.message = (r.passed ? "caught: " : "NOT caught: ") + r.message;
               return r;
             }});
    for (const std::string& fam : hslt_families()) {
      reg.add({.name = "differential.hslt.jacobian." + fam,
               .description = "Eq. 11 constraint Jacobian (blocks A_i, B_i, C_i and the full matrix in (u, v)) of " +
                              fam + " paths against central differences and Ridders (rel. error < 1e-6) and a "
                                    "Taylor test (slope 2 +- 0.1)",
               .kind = CheckKind::kDeterministic,
               .run = [fam](const CheckContext& ctx) { return run_jacobian(ctx, fam); }});
    }
    reg.add({.name = "differential.hslt.jacobian.sign_error.negative_control",
             .description = "One block (C of the middle row) with its sign flipped must fail the FD check on every family",
             .kind = CheckKind::kDeterministic,
             .run = [](const CheckContext& ctx) {
               return run_jacobian_negative(ctx, hslt_blocks_sign_error, hslt_families(), "sign error in one block");
             }});
    reg.add({.name = "differential.hslt.jacobian.missing_dndu.negative_control",
             .description = "B_i without the shading-frame derivative (dn/du, dn/dv) must fail the FD check on the "
                            "curved families",
             .kind = CheckKind::kDeterministic,
             .run = [](const CheckContext& ctx) {
               return run_jacobian_negative(ctx, hslt_blocks_without_frame_derivative,
                                            {"curved_mirrors", "mirror_chain", "glass", "mixed"}, "missing dn/du term");
             }});
    reg.add({.name = "differential.hslt.determinant",
             .description = "det of Eq. 11 by block LU (Sec. 7) vs dense Eigen LU (rel. 1e-9) vs the FD Jacobian's "
                            "determinant (rel. 1e-5); block LU solve vs dense solve (rel. 1e-9)",
             .kind = CheckKind::kDeterministic,
             .run = [](const CheckContext& ctx) { return run_determinant(ctx, false); }});
    reg.add({.name = "differential.hslt.determinant.no_schur.negative_control",
             .description = "Block LU determinant without the Schur complement (D_r = B_r) must be caught",
             .kind = CheckKind::kDeterministic,
             .run = [](const CheckContext& ctx) { return run_determinant(ctx, true); }});
    reg.add({.name = "differential.hslt.transfer_matrix",
             .description = "Transfer matrix T_1 = dx_1/dx_k at fixed H_perp (Eq. 6, block LU solve) is the inverse of "
                            "the FD derivative of the end point of the specular chain retraced from x_0 through a "
                            "moved x_1 (max |M T_1 - I| / cond(T_1) < 1e-6), on the traced dg-* paths",
             .kind = CheckKind::kDeterministic,
             .run = [](const CheckContext& ctx) { return run_transfer(ctx, hslt_constraint_blocks, false); }});
    reg.add({.name = "differential.hslt.transfer_matrix.missing_dndu.negative_control",
             .description = "T_1 from blocks without the shading-frame derivative must disagree with retracing",
             .kind = CheckKind::kDeterministic,
             .run = [](const CheckContext& ctx) {
               return run_transfer(ctx, hslt_blocks_without_frame_derivative, true);
             }});
    reg.add({.name = "differential.hslt.measure",
             .description = "Half-vector measure: Eq. 5-6 (G(x0,x1) |T_1| prod |do/dh| |<o,n>|/|<h,n>|, Eq. 10) "
                            "equals Eq. 4 (prod G / |det J|), rel. 1e-8",
             .kind = CheckKind::kDeterministic,
             .run = [](const CheckContext& ctx) { return run_measure(ctx, false); }});
    reg.add({.name = "differential.hslt.measure.missing_projection.negative_control",
             .description = "Eq. 5 without the projection factor 1/|<h,n>| must differ from Eq. 4",
             .kind = CheckKind::kDeterministic,
             .run = [](const CheckContext& ctx) { return run_measure(ctx, true); }});
  }
};
const HsltChecks hslt_checks;

}  // namespace
}  // namespace tb
