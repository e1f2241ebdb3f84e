// Registered checks of the predictor-corrector walk in half-vector space (lib/differential/
// hslt_walk.h; Kaplanyan, Hanika, Dachsbacher 2014, Sec. 5.1, 5.2, 7; docs/hslt.md). All
// deterministic, on the path families of validate/differential/hslt_paths.h:
//   differential.hslt.walk.converges     walks to h* = h^perp(X) + delta (delta = 1e-3 on a disk
//                                        per vertex) converge; the result, rebuilt from its
//                                        shapes at its (u, v), is on the surfaces and has
//                                        H^perp = h* (independent of the walk's own residual)
//   differential.hslt.walk.quadratic     Newton order: log(r_{n+1}/r_n) / log(r_n/r_{n-1}) ~ 2
//   differential.hslt.walk.reversible    walking back to h^perp(X) returns X (Sec. 5.2), and
//                                        the reversible fraction over a sweep of delta
//   differential.hslt.walk.first_order   X' - X = J^{-1} delta + O(delta^2): Taylor slope 2
//   differential.hslt.walk.statistics    status counts and average iterations over families and
//                                        a delta sweep (the analogue of Table 3), no NaN
// Each has a negative control (validate/differential/hslt_walk_broken.h) that must be caught.
#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "lib/core/hash.h"
#include "lib/differential/hslt_block_lu.h"
#include "lib/differential/hslt_walk.h"
#include "validate/differential/hslt_broken.h"
#include "validate/differential/hslt_paths.h"
#include "validate/differential/hslt_walk_broken.h"
#include "validate/differential/hslt_walk_support.h"
#include "validate/registry.h"

namespace tb {
namespace {

// A walk as the checks see it (the production walk or a broken copy).
using WalkFn = std::function<HsltWalkResult(const Scene&, const HsltPath&, const Eigen::VectorXd&, const HsltWalkOptions&)>;

HsltWalkResult production_walk(const Scene& s, const HsltPath& p, const Eigen::VectorXd& t, const HsltWalkOptions& o) {
  return hslt_walk(s, p, t, o);
}
HsltWalkResult no_projection_walk(const Scene&, const HsltPath& p, const Eigen::VectorXd& t, const HsltWalkOptions& o) {
  return hslt_walk_without_projection(p, t, o);
}

constexpr double kSmallDelta = 1e-3;          // (a), (c): |h*_i - h_i^perp|
constexpr double kSurfaceTolerance = 1e-9;    // |p - surface_at(uv).p|, scene units
constexpr double kConstraintTolerance = 1e-10;  // |H^perp(rebuilt) - h*|_2 (walk tolerance 1e-11)
constexpr double kMinConvergedFraction = 0.9;   // of the walks at delta = 1e-3
constexpr double kReversibleTolerance = 1e-7;   // max vertex distance after walking back
constexpr double kMinReversibleFraction = 0.95; // of the converged walks at delta = 1e-3
constexpr double kQuadraticDelta = 2e-2;
constexpr double kResidualFloor = 1e-12;        // residuals below are rounding, not Newton
constexpr double kOrderLow = 1.8, kOrderHigh = 2.2, kOrderMinP10 = 1.5;
constexpr double kMaxRatioP90 = 1e4;            // 90% quantile of r_{n+1} / r_n^2 (Newton's constant)
constexpr double kSlopeTolerance = 0.1;         // first-order: Taylor slope 2 +- 0.1
constexpr double kFirstOrderDelta0 = 2e-3;      // first-order: delta = delta_0 2^-m, m = 0 .. 7, with
constexpr double kFirstOrderMaxMove = 1e-3;     // delta_0 = min(2e-3, 1e-3 / |first-order move per delta|)
const std::array<double, 6> kSweep{1e-4, 1e-3, 1e-2, 3e-2, 0.1, 0.3};

int path_count(const CheckContext& ctx) { return static_cast<int>(ctx.size(24, 160)); }

uint64_t family_key(const std::string& fam) { return hash_string("differential.hslt.walk." + fam); }

// The paths of a family the walk can start from (hslt_walk_start_ok), with their indices.
struct WalkPaths {
  std::vector<HsltPath> paths;
  std::vector<int64_t> index;
  int64_t generated = 0, not_traceable = 0;
};
WalkPaths walk_paths(const std::string& fam, const CheckContext& ctx) {
  const HsltPathSet set = hslt_path_set(fam, path_count(ctx), ctx.seed);
  const Scene& scene = hslt_family_world(fam).geometry();
  const bool vis = hslt_walk_options_for(fam).visibility;
  WalkPaths w;
  for (size_t i = 0; i < set.paths.size(); ++i) {
    ++w.generated;
    if (!hslt_walk_start_ok(scene, set.paths[i], vis)) {
      ++w.not_traceable;
      continue;
    }
    w.paths.push_back(set.paths[i]);
    w.index.push_back(static_cast<int64_t>(i));
  }
  return w;
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size())))];
}

// --- (a) convergence and the on-surface test -------------------------------------------------------

CheckResult run_converges(const CheckContext& ctx, const WalkFn& walk, bool broken) {
  int64_t walks = 0, converged = 0, bad = 0, not_traceable = 0;
  double worst_surface = 0, worst_constraint = 0;
  nlohmann::json per = nlohmann::json::object();
  std::string caught_families;
  bool every_curved_caught = true;
  for (const std::string& fam : hslt_families()) {
    const WalkPaths wp = walk_paths(fam, ctx);
    const Scene& scene = hslt_family_world(fam).geometry();
    const HsltWalkOptions opt = hslt_walk_options_for(fam);
    not_traceable += wp.not_traceable;
    int64_t f_conv = 0, f_bad = 0;
    double f_surface = 0, f_constraint = 0;
    for (size_t i = 0; i < wp.paths.size(); ++i) {
      const Eigen::VectorXd target = hslt_walk_target(wp.paths[i], kSmallDelta, ctx.seed, family_key(fam), wp.index[i]);
      const HsltWalkResult r = walk(scene, wp.paths[i], target, opt);
      ++walks;
      // Every returned path (the last accepted one, whatever the status) must lie on the
      // surfaces; a converged one must also meet h*.
      const HsltOnSurface s = hslt_walk_on_surface(scene, r.path, target);
      f_surface = std::max(f_surface, s.surface_distance);
      const bool conv = r.status == HsltWalkStatus::kConverged;
      if (conv) {
        ++f_conv;
        f_constraint = std::max(f_constraint, s.constraint_error);
      }
      if (!(s.surface_distance < kSurfaceTolerance) || (conv && !(s.constraint_error < kConstraintTolerance))) ++f_bad;
    }
    converged += f_conv;
    bad += f_bad;
    worst_surface = std::max(worst_surface, f_surface);
    worst_constraint = std::max(worst_constraint, f_constraint);
    const int64_t f_walks = static_cast<int64_t>(wp.paths.size());
    const bool f_caught = f_bad > 0;  // by the on-surface / constraint test itself
    // The tangent plane is the surface on the flat floor and slab: only the curved families must
    // catch a walk that does not project.
    if (fam == "curved_mirrors" || fam == "mirror_chain" || fam == "reflection" || fam == "mixed") {
      every_curved_caught = every_curved_caught && f_caught;
    }
    if (f_caught) caught_families += (caught_families.empty() ? "" : ", ") + fam;
    per[fam] = {{"walks", f_walks}, {"not_traceable", wp.not_traceable}, {"converged", f_conv},
                {"failed_on_surface_test", f_bad}, {"worst_surface_distance", f_surface},
                {"worst_constraint_error", f_constraint}};
  }
  const bool ok = walks > 0 && bad == 0 && converged >= kMinConvergedFraction * static_cast<double>(walks);
  CheckResult r;
  r.passed = broken ? (!ok && every_curved_caught) : ok;
  r.statistic_name = "converged fraction";
  r.statistic = walks > 0 ? static_cast<double>(converged) / static_cast<double>(walks) : 0.0;
  r.samples = walks;
  r.message = fmt::format(
      "{}{} walks to |h* - h_perp| = {:g} per vertex ({} paths not ray-traceable skipped): {} converged "
      "(>= {:g} required), {} failed the on-surface test (any status) or missed h* (converged); worst |p - surface(uv)| {:.3g} (tol {:g}), worst "
      "|H_perp(rebuilt) - h*| {:.3g} (tol {:g}){}",
      broken ? (r.passed ? "caught: " : "NOT caught on every curved family: ") : "", walks, kSmallDelta, not_traceable,
      converged, kMinConvergedFraction, bad, worst_surface, kSurfaceTolerance, worst_constraint, kConstraintTolerance,
      broken ? "; families caught: " + caught_families : "");
  r.details = {{"families", per}, {"surface_tolerance", kSurfaceTolerance},
               {"constraint_tolerance", kConstraintTolerance}, {"delta", kSmallDelta}};
  return r;
}

// --- (b) quadratic convergence ------------------------------------------------------------------

CheckResult run_quadratic(const CheckContext& ctx, bool broken) {
  std::vector<double> orders, ratios;
  int64_t walks = 0, converged = 0, used = 0;
  nlohmann::json per = nlohmann::json::object();
  for (const std::string& fam : hslt_families()) {
    const WalkPaths wp = walk_paths(fam, ctx);
    const Scene& scene = hslt_family_world(fam).geometry();
    const HsltWalkOptions opt = hslt_walk_options_for(fam);
    std::vector<double> f_orders;
    int64_t f_walks = 0, f_conv = 0;
    for (size_t i = 0; i < wp.paths.size(); ++i) {
      // The sign error is in C of the middle block row, inside J only for k >= 3.
      if (broken && wp.paths[i].segments() < 3) continue;
      const Eigen::VectorXd target =
          hslt_walk_target(wp.paths[i], kQuadraticDelta, ctx.seed, family_key(fam), wp.index[i]);
      const HsltWalkResult r = broken ? hslt_walk_sign_error(scene, wp.paths[i], target, opt)
                                      : hslt_walk(scene, wp.paths[i], target, opt);
      ++f_walks;
      if (r.status == HsltWalkStatus::kConverged) ++f_conv;
      const std::vector<double>& rs = r.residuals;
      bool any = false;
      for (size_t n = 1; n + 1 < rs.size(); ++n) {
        // Full Newton steps only (lambda = 1 for both), residuals above the rounding floor.
        if (r.step_sizes[n - 1] != 1.0 || r.step_sizes[n] != 1.0) continue;
        if (!(rs[n + 1] > kResidualFloor)) continue;
        const double p = std::log(rs[n + 1] / rs[n]) / std::log(rs[n] / rs[n - 1]);
        if (!std::isfinite(p)) continue;
        f_orders.push_back(p);
        ratios.push_back(rs[n + 1] / (rs[n] * rs[n]));
        any = true;
      }
      if (any) ++used;
    }
    walks += f_walks;
    converged += f_conv;
    orders.insert(orders.end(), f_orders.begin(), f_orders.end());
    per[fam] = {{"walks", f_walks}, {"converged", f_conv}, {"order_estimates", f_orders.size()},
                {"median_order", quantile(f_orders, 0.5)}};
  }
  const double med = quantile(orders, 0.5), p10 = quantile(orders, 0.1);
  double max_ratio = 0;
  for (double q : ratios) max_ratio = std::max(max_ratio, q);
  // The order is measured on every walk's full steps (converged or not); how many converge at
  // this delta is differential.hslt.walk.statistics' business.
  const double ratio_p90 = quantile(ratios, 0.9);
  const bool ok = orders.size() >= 10 && med >= kOrderLow && med <= kOrderHigh && p10 >= kOrderMinP10 &&
                  ratio_p90 < kMaxRatioP90;
  CheckResult r;
  r.passed = broken ? (!ok && walks > 0) : ok;
  r.statistic_name = "median order";
  r.statistic = med;
  r.samples = static_cast<int64_t>(orders.size());
  r.message = fmt::format(
      "{}{} walks (delta {:g}), {} converged; {} order estimates log(r_n+1/r_n)/log(r_n/r_n-1) from {} walks: "
      "median {:.3f} (must be in [{:g}, {:g}]), 10% quantile {:.3f} (>= {:g}); r_n+1/r_n^2 median {:.3g}, 90% "
      "quantile {:.3g} (< {:g}), max {:.3g}",
      broken ? (r.passed ? "sign-flipped block caught: " : "sign-flipped block NOT caught: ") : "", walks,
      kQuadraticDelta, converged, orders.size(), used, med, kOrderLow, kOrderHigh, p10, kOrderMinP10,
      quantile(ratios, 0.5), ratio_p90, kMaxRatioP90, max_ratio);
  r.details = {{"families", per},
               {"median_order", med},
               {"order_p10", p10},
               {"order_p90", quantile(orders, 0.9)},
               {"max_ratio_r_next_over_r_sq", max_ratio},
               {"median_ratio_r_next_over_r_sq", quantile(ratios, 0.5)},
               {"residual_floor", kResidualFloor}};
  return r;
}

// --- (c) reversibility ---------------------------------------------------------------------------

struct ReversibleCount {
  int64_t forward = 0, converged = 0, reversible = 0;
  int64_t back_failed = 0, back_elsewhere = 0;  // non-reversible: the way back fails / ends at another path
  double worst_distance = 0;  // over converged forward walks whose back walk converged
};

CheckResult run_reversible(const CheckContext& ctx, const WalkFn& walk, bool broken) {
  std::map<double, ReversibleCount> by_delta;
  for (const std::string& fam : hslt_families()) {
    const WalkPaths wp = walk_paths(fam, ctx);
    const Scene& scene = hslt_family_world(fam).geometry();
    const HsltWalkOptions opt = hslt_walk_options_for(fam);
    for (size_t i = 0; i < wp.paths.size(); ++i) {
      const HsltPath& x = wp.paths[i];
      for (const double delta : kSweep) {
        ReversibleCount& c = by_delta[delta];
        ++c.forward;
        const HsltWalkResult f = walk(scene, x, hslt_walk_target(x, delta, ctx.seed, family_key(fam), wp.index[i]), opt);
        if (f.status != HsltWalkStatus::kConverged) continue;
        ++c.converged;
        const HsltWalkResult b = walk(scene, f.path, hslt_constraints(x), opt);
        if (b.status != HsltWalkStatus::kConverged) {
          ++c.back_failed;
          continue;
        }
        const double d = hslt_max_vertex_distance(b.path, x);
        c.worst_distance = std::max(c.worst_distance, d);
        if (d < kReversibleTolerance) ++c.reversible;
        else ++c.back_elsewhere;
      }
    }
  }
  nlohmann::json sweep = nlohmann::json::array();
  std::string table;
  for (const auto& [delta, c] : by_delta) {
    const double frac = c.converged > 0 ? static_cast<double>(c.reversible) / static_cast<double>(c.converged) : 0.0;
    sweep.push_back({{"delta", delta}, {"walks", c.forward}, {"converged", c.converged}, {"reversible", c.reversible},
                     {"reversible_fraction_of_converged", frac}, {"worst_distance", c.worst_distance},
                     {"back_walk_failed", c.back_failed}, {"back_walk_reached_another_path", c.back_elsewhere}});
    table += fmt::format("{}delta {:g}: {}/{} reversible", table.empty() ? "" : "; ", delta, c.reversible, c.converged);
    if (c.back_failed + c.back_elsewhere > 0)
      table += fmt::format(" (back walk failed {}, reached another path {})", c.back_failed, c.back_elsewhere);
  }
  const ReversibleCount& small = by_delta[kSmallDelta];
  const double frac = small.converged > 0 ? static_cast<double>(small.reversible) / static_cast<double>(small.converged) : 0.0;
  const bool ok = small.converged >= kMinConvergedFraction * static_cast<double>(small.forward) &&
                  frac >= kMinReversibleFraction;
  CheckResult r;
  r.passed = broken ? !ok : ok;
  r.statistic_name = "reversible fraction at delta 1e-3";
  r.statistic = frac;
  r.samples = small.forward;
  r.message = fmt::format(
      "{}delta {:g}: {} of {} converged walks walk back to X within {:g} ({:.4f}, >= {:g} required); {}",
      broken ? (r.passed ? "single-step walk caught: " : "single-step walk NOT caught: ") : "", kSmallDelta,
      small.reversible, small.converged, kReversibleTolerance, frac, kMinReversibleFraction, table);
  r.details = {{"sweep", sweep}, {"tolerance", kReversibleTolerance}};
  return r;
}

// --- (d) first order: X' - X = J^{-1} delta + O(delta^2) -----------------------------------------

double least_squares_slope(const std::vector<double>& x, const std::vector<double>& y) {
  const double n = static_cast<double>(x.size());
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (size_t i = 0; i < x.size(); ++i) {
    sx += x[i];
    sy += y[i];
    sxx += x[i] * x[i];
    sxy += x[i] * y[i];
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

CheckResult run_first_order(const CheckContext& ctx, bool broken) {
  int64_t paths = 0, checked = 0, failed = 0, not_converged = 0;
  double worst_dev = 0;
  std::vector<double> slopes;
  nlohmann::json per = nlohmann::json::object(), failures = nlohmann::json::array(),
                 unconverged = nlohmann::json::array();
  for (const std::string& fam : hslt_families()) {
    const WalkPaths wp = walk_paths(fam, ctx);
    const Scene& scene = hslt_family_world(fam).geometry();
    const HsltWalkOptions opt = hslt_walk_options_for(fam);
    int64_t f_checked = 0, f_failed = 0;
    double f_dev = 0;
    for (size_t i = 0; i < wp.paths.size(); ++i) {
      const HsltPath& x = wp.paths[i];
      if (broken && x.segments() < 3) continue;  // the broken block is inside J for k >= 3 only
      ++paths;
      const Eigen::VectorXd dir = hslt_walk_direction(x, ctx.seed, family_key(fam), wp.index[i]);
      // First-order displacement per unit delta: J^{-1} dir (block LU), mapped by dp/du, dp/dv.
      const HsltBlockLu lu(broken ? hslt_blocks_sign_error(x) : hslt_constraint_blocks(x));
      if (!lu.ok()) continue;
      const Eigen::VectorXd duv = lu.solve(dir);
      const Eigen::VectorXd h0 = hslt_constraints(x);
      // The largest step moves no vertex by more than 1e-3 scene units to first order (a chain
      // near a caustic moves its vertices by much more per unit of h^perp than the others).
      double disp1 = 0;
      for (int v = 1; v < x.segments(); ++v) {
        const HsltVertex& a = x.vertices[static_cast<size_t>(v)];
        const Eigen::Index c = 2 * (v - 1);
        disp1 = std::max(disp1, glm::length(a.dpdu * duv[c] + a.dpdv * duv[c + 1]));
      }
      const double delta0 = std::min(kFirstOrderDelta0, kFirstOrderMaxMove / std::max(disp1, 1e-300));
      std::vector<double> ld, le;
      bool ok = true;
      for (int m = 0; m < 8 && ok; ++m) {
        const double delta = delta0 * std::ldexp(1.0, -m);
        const HsltWalkResult r = hslt_walk(scene, x, h0 + delta * dir, opt);
        if (r.status != HsltWalkStatus::kConverged) {
          ok = false;
          if (unconverged.size() < 16)
            unconverged.push_back({{"family", fam}, {"path", wp.index[i]}, {"k", x.segments()}, {"delta", delta},
                                   {"status", hslt_walk_status_name(r.status)}, {"condition", r.condition_estimate},
                                   {"residuals", r.residuals}, {"halvings", r.halvings}});
          break;
        }
        // The walk stops at |F| < 1e-11: its remaining error moves the vertices by about
        // (dp/du, dp/dv) J^{-1} F; points with e below 100 times that are dropped.
        const HsltBlockLu lu_end(hslt_constraint_blocks(r.path));
        const Eigen::VectorXd rest = lu_end.ok() ? lu_end.solve(Eigen::VectorXd(hslt_constraints(r.path) - h0 - delta * dir))
                                                 : Eigen::VectorXd::Zero(duv.size());
        double e = 0, floor = 1e-14;
        for (int v = 1; v < x.segments(); ++v) {
          const HsltVertex& a = x.vertices[static_cast<size_t>(v)];
          const Eigen::Index c = 2 * (v - 1);
          const Vec3 lin = a.dpdu * (delta * duv[c]) + a.dpdv * (delta * duv[c + 1]);
          e = std::max(e, glm::length(r.path.vertices[static_cast<size_t>(v)].p - a.p - lin));
          floor = std::max(floor, 100 * glm::length(a.dpdu * rest[c] + a.dpdv * rest[c + 1]));
        }
        if (e > floor) {
          ld.push_back(std::log(delta));
          le.push_back(std::log(e));
        }
      }
      if (!ok) {
        ++not_converged;
        continue;
      }
      if (ld.size() < 3) continue;  // locally linear: no slope
      // The asymptotic regime: the least-squares slope over the (up to) 5 smallest delta (on
      // strongly curved chains the third-order term still bends the first points).
      if (ld.size() > 5) {
        ld.erase(ld.begin(), ld.end() - 5);
        le.erase(le.begin(), le.end() - 5);
      }
      const double s = least_squares_slope(ld, le);
      slopes.push_back(s);
      ++f_checked;
      const double dev = std::abs(s - 2.0);
      f_dev = std::max(f_dev, dev);
      if (!(dev <= kSlopeTolerance)) {
        ++f_failed;
        if (failures.size() < 8) {
          failures.push_back({{"family", fam}, {"path", wp.index[i]}, {"k", x.segments()}, {"slope", s},
                              {"log_delta", ld}, {"log_error", le}});
        }
      }
    }
    checked += f_checked;
    failed += f_failed;
    worst_dev = std::max(worst_dev, f_dev);
    per[fam] = {{"checked", f_checked}, {"failed", f_failed}, {"worst_slope_deviation", f_dev}};
  }
  const bool ok = checked > 0 && failed == 0 && not_converged * 10 < paths;
  CheckResult r;
  r.passed = broken ? (!ok && failed * 2 > checked) : ok;
  r.statistic_name = "max |slope - 2|";
  r.statistic = worst_dev;
  r.samples = checked;
  r.message = fmt::format(
      "{}{} paths, delta = delta_0 2^-m, m = 0..7, delta_0 = min(2e-3, 1e-3 / first-order vertex move) (slope over the 5 smallest): max_i |x'_i - x_i - (dp/du, dp/dv) J^-1 delta| has "
      "log-log slope 2 +- {:g}: {} checked, {} failed, worst |slope - 2| {:.3g}, median slope {:.3f}; {} walks "
      "of a sweep not converged",
      broken ? (r.passed ? "sign-flipped J^-1 caught: " : "sign-flipped J^-1 NOT caught: ") : "", paths,
      kSlopeTolerance, checked, failed, worst_dev, quantile(slopes, 0.5), not_converged);
  r.details = {{"families", per}, {"slope_tolerance", kSlopeTolerance}, {"not_converged", not_converged},
               {"failures", failures}, {"unconverged", unconverged}};
  return r;
}

// --- (4) failure statistics (the analogue of Table 3) ----------------------------------------------

CheckResult run_statistics(const CheckContext& ctx, const WalkFn& walk, bool broken) {
  struct Row {
    std::array<int64_t, kHsltWalkStatusCount> count{};
    int64_t walks = 0, iterations = 0, converged_iterations = 0, halvings = 0, recheck_failed = 0;
    double max_condition = 0;
    bool finite = true;
  };
  std::map<double, Row> rows;
  int64_t not_traceable = 0;
  bool all_finite_sides = true;
  nlohmann::json smallest_failures = nlohmann::json::array();  // non-converged walks at delta 1e-4
  for (const std::string& fam : hslt_families()) {
    const WalkPaths wp = walk_paths(fam, ctx);
    not_traceable += wp.not_traceable;
    const Scene& scene = hslt_family_world(fam).geometry();
    const HsltWalkOptions opt = hslt_walk_options_for(fam);
    for (size_t i = 0; i < wp.paths.size(); ++i) {
      for (const double delta : kSweep) {
        const Eigen::VectorXd target = hslt_walk_target(wp.paths[i], delta, ctx.seed, family_key(fam), wp.index[i]);
        const HsltWalkResult r = walk(scene, wp.paths[i], target, opt);
        Row& row = rows[delta];
        ++row.walks;
        if (delta == kSweep[0] && r.status != HsltWalkStatus::kConverged && smallest_failures.size() < 8) {
          const HsltWalkStatus s0 = r.status;
          smallest_failures.push_back({{"family", fam}, {"path", wp.index[i]}, {"k", wp.paths[i].segments()},
                                       {"status", hslt_walk_status_name(s0)}, {"condition", r.condition_estimate},
                                       {"residuals", r.residuals}});
        }
        ++row.count[static_cast<size_t>(r.status)];
        row.iterations += r.iterations;
        row.halvings += r.halvings;
        row.max_condition = std::max(row.max_condition, r.condition_estimate);
        bool fin = std::isfinite(r.residual) && std::isfinite(r.condition_estimate) && std::isfinite(r.side_ratio);
        for (double x : r.residuals) fin = fin && std::isfinite(x);
        for (const HsltVertex& v : r.path.vertices) fin = fin && std::isfinite(glm::length(v.p));
        row.finite = row.finite && fin;
        const HsltOnSurface s = hslt_walk_on_surface(scene, r.path, target);
        if (!(s.surface_distance < kSurfaceTolerance)) ++row.recheck_failed;
        if (r.status == HsltWalkStatus::kConverged) {
          row.converged_iterations += r.iterations;
          if (!(s.constraint_error < kConstraintTolerance)) ++row.recheck_failed;
        }
      }
    }
  }
  // Table 2 analogue: the three projection sides at delta = 3e-2.
  nlohmann::json sides = nlohmann::json::object();
  std::string side_msg;
  for (const auto& [side, name] : std::vector<std::pair<HsltProjectionSide, std::string>>{
           {HsltProjectionSide::kFromStart, "from_x0"}, {HsltProjectionSide::kFromEnd, "from_xk"},
           {HsltProjectionSide::kHeuristic, "heuristic"}}) {
    int64_t n = 0, conv = 0, iters = 0, chose_start = 0;
    bool fin = true;
    for (const std::string& fam : hslt_families()) {
      const WalkPaths wp = walk_paths(fam, ctx);
      const Scene& scene = hslt_family_world(fam).geometry();
      HsltWalkOptions opt = hslt_walk_options_for(fam);
      opt.side = side;
      for (size_t i = 0; i < wp.paths.size(); ++i) {
        const Eigen::VectorXd target = hslt_walk_target(wp.paths[i], 3e-2, ctx.seed, family_key(fam), wp.index[i]);
        const HsltWalkResult r = walk(scene, wp.paths[i], target, opt);
        ++n;
        iters += r.iterations;
        if (r.from_start) ++chose_start;
        fin = fin && std::isfinite(r.residual);
        if (r.status == HsltWalkStatus::kConverged) ++conv;
      }
    }
    all_finite_sides = all_finite_sides && fin;
    sides[name] = {{"walks", n}, {"converged", conv}, {"iterations", iters}, {"projected_from_x0", chose_start}};
    side_msg += fmt::format("{}{} {}/{} converged, {:.2f} iterations", side_msg.empty() ? "" : ", ", name, conv, n,
                            static_cast<double>(iters) / static_cast<double>(std::max<int64_t>(1, n)));
  }
  bool all_finite = all_finite_sides;
  int64_t recheck_failed = 0;
  nlohmann::json table = nlohmann::json::array();
  std::string msg;
  for (const auto& [delta, row] : rows) {
    all_finite = all_finite && row.finite;
    recheck_failed += row.recheck_failed;
    const int64_t conv = row.count[static_cast<size_t>(HsltWalkStatus::kConverged)];
    nlohmann::json counts = nlohmann::json::object();
    std::string cs;
    for (int s = 0; s < kHsltWalkStatusCount; ++s) {
      const char* name = hslt_walk_status_name(static_cast<HsltWalkStatus>(s));
      counts[name] = row.count[static_cast<size_t>(s)];
      if (s > 0 && row.count[static_cast<size_t>(s)] > 0) cs += fmt::format(" {} {}", name, row.count[static_cast<size_t>(s)]);
    }
    const double avg_conv = conv > 0 ? static_cast<double>(row.converged_iterations) / static_cast<double>(conv) : 0.0;
    const double avg_all = static_cast<double>(row.iterations) / static_cast<double>(std::max<int64_t>(1, row.walks));
    table.push_back({{"delta", delta}, {"walks", row.walks}, {"status", counts},
                     {"average_iterations_converged", avg_conv}, {"average_iterations_all", avg_all},
                     {"halvings", row.halvings}, {"recheck_failed", row.recheck_failed},
                     {"max_condition_estimate", row.max_condition}, {"all_finite", row.finite}});
    msg += fmt::format("{}delta {:g}: {}/{} converged, iterations {:.2f}/{:.2f}{}", msg.empty() ? "" : "; ", delta, conv,
                       row.walks, avg_conv, avg_all, cs);
  }
  const Row& small = rows[kSmallDelta];
  const int64_t small_conv = small.count[static_cast<size_t>(HsltWalkStatus::kConverged)];
  const bool ok = all_finite && recheck_failed == 0 && small.walks > 0 &&
                  small_conv >= kMinConvergedFraction * static_cast<double>(small.walks);
  CheckResult r;
  r.passed = broken ? !ok : ok;
  r.statistic_name = "converged fraction at delta 1e-3";
  r.statistic = small.walks > 0 ? static_cast<double>(small_conv) / static_cast<double>(small.walks) : 0.0;
  r.samples = small.walks;
  r.message = fmt::format("{}{} (iterations per converged / per walk; {} paths not ray-traceable); all finite: {}; "
                          "{} walks failed the on-surface recheck (or, converged, missed h*); projection side at "
                          "delta 3e-2 (Table 2): {}",
                          broken ? (r.passed ? "caught: " : "NOT caught: ") : "", msg, not_traceable,
                          all_finite ? "yes" : "NO", recheck_failed, side_msg);
  r.details = {{"sweep", table}, {"not_traceable", not_traceable}, {"projection_side_delta_3e-2", sides},
               {"not_converged_at_delta_1e-4", smallest_failures}};
  return r;
}

// --- registration --------------------------------------------------------------------------------

struct HsltWalkChecks {
  HsltWalkChecks() {
    auto& reg = Registry::global();
    reg.add({.name = "differential.hslt.walk.converges",
             .description = "Predictor-corrector walks (Sec. 5.1) to h* = h_perp(X) + 1e-3 (cos phi, sin phi) per vertex "
                            "converge (>= 90%), and every converged path rebuilt from its shapes at its (u, v) is on "
                            "the surfaces (1e-9) with |H_perp - h*| < 1e-10",
             .kind = CheckKind::kDeterministic,
             .run = [](const CheckContext& ctx) { return run_converges(ctx, production_walk, false); }});
    reg.add({.name = "differential.hslt.walk.converges.no_projection.negative_control",
             .description = "A walk that leaves the vertices on the tangent plane (no ray-cast projection) must fail "
                            "the on-surface test on every curved family",
             .kind = CheckKind::kDeterministic,
             .run = [](const CheckContext& ctx) { return run_converges(ctx, no_projection_walk, true); }});
    reg.add({.name = "differential.hslt.walk.quadratic",
             .description = "Newton order of the walk at delta 2e-2: median of log(r_n+1/r_n)/log(r_n/r_n-1) in "
                            "[1.8, 2.2], 10% quantile >= 1.5, 90% quantile of r_n+1/r_n^2 < 1e4 (full steps, residuals > 1e-12)",
             .kind = CheckKind::kDeterministic,
             .run = [](const CheckContext& ctx) { return run_quadratic(ctx, false); }});
    reg.add({.name = "differential.hslt.walk.quadratic.sign_error.negative_control",
             .description = "The walk with hslt_blocks_sign_error's Jacobian (k >= 3) must not converge quadratically",
             .kind = CheckKind::kDeterministic,
             .run = [](const CheckContext& ctx) { return run_quadratic(ctx, true); }});
    reg.add({.name = "differential.hslt.walk.reversible",
             .description = "Walking back from X' to h_perp(X) returns X within 1e-7 for >= 95% of the converged walks "
                            "at delta 1e-3 (Sec. 5.2); the reversible fraction over delta 1e-4 .. 0.3 reported",
             .kind = CheckKind::kDeterministic,
             .run = [](const CheckContext& ctx) { return run_reversible(ctx, production_walk, false); }});
    reg.add({.name = "differential.hslt.walk.reversible.single_step.negative_control",
             .description = "A walk that stops after one predictor-corrector step and declares convergence must be "
                            "caught as non-reversible",
             .kind = CheckKind::kDeterministic,
             .run = [](const CheckContext& ctx) {
               return run_reversible(ctx, hslt_walk_single_step_broken, true);
             }});
    reg.add({.name = "differential.hslt.walk.first_order",
             .description = "X' - X = (dp/du, dp/dv) J^-1 delta + O(delta^2): log-log slope of the error over delta "
                            "delta_0 2^-m, m = 0 .. 7, delta_0 = min(2e-3, 1e-3 / first-order vertex move) (least squares over the 5 smallest) is 2 +- 0.1 on every path",
             .kind = CheckKind::kDeterministic,
             .run = [](const CheckContext& ctx) { return run_first_order(ctx, false); }});
    reg.add({.name = "differential.hslt.walk.first_order.sign_error.negative_control",
             .description = "J^-1 delta from hslt_blocks_sign_error (k >= 3) must fail the slope test on most paths",
             .kind = CheckKind::kDeterministic,
             .run = [](const CheckContext& ctx) { return run_first_order(ctx, true); }});
    reg.add({.name = "differential.hslt.walk.statistics",
             .description = "Walk status counts and average iterations over all families and delta 1e-4 .. 0.3 (the "
                            "analogue of Table 3): no NaN, every converged walk passes the on-surface recheck, >= 90% "
                            "converged at delta 1e-3",
             .kind = CheckKind::kDeterministic,
             .run = [](const CheckContext& ctx) { return run_statistics(ctx, production_walk, false); }});
    reg.add({.name = "differential.hslt.walk.statistics.no_projection.negative_control",
             .description = "The statistics of the walk without projection must be caught (on-surface recheck)",
             .kind = CheckKind::kDeterministic,
             .run = [](const CheckContext& ctx) { return run_statistics(ctx, no_projection_walk, true); }});
  }
};
const HsltWalkChecks hslt_walk_checks;

}  // namespace
}  // namespace tb
