// Registered checks of the path differentials and variance-bounding ratios of lib/differential
// (Zirr & Dachsbacher 2020, Sec. 6 and App. B; docs/zirr2020.md):
//   differential.path.jacobian.<scene>      dX/dU (Eq. 44 recurrence) against finite differences
//                                           of the forward map X(U): central h and h/2, Ridders
//                                           (Ceres), Taylor slope 2 +- 0.1; paths of 1..8 vertices
//   differential.path.incremental           App. B.2's O(k) endpoint covariance == the O(k^2)
//                                           recurrence (Eq. 18), relative 1e-10
//   differential.path.variance_ratio        Eq. 21 (derivative-free) against Eq. 20 (full
//                                           differentials) on sampled paths
// and one negative control per check, each a broken copy of one piece, which must be caught:
//   differential.path.jacobian.negative_control.dropped_curvature   dn/dx = 0 in the blocks
//   differential.path.jacobian.negative_control.missing_eta         refraction derivative with eta = 1
//   differential.path.jacobian.negative_control.transposed_block    g_u = A_j^-1 transposed
//   differential.path.incremental.negative_control                  B.2 update without A_j^-1 A_j^-T
//   differential.path.variance_ratio.negative_control               Eq. 21 without the refraction factor
#include <algorithm>
#include <array>
#include <functional>
#include <cmath>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "lib/core/hash.h"
#include "lib/differential/path_differential.h"
#include "lib/differential/variance_bound.h"
#include "lib/scene/scene_loader.h"
#include "validate/registry.h"
#include "validate/render/render_compare.h"
#include "validate/stats/fd_jacobian.h"

namespace tb {
namespace {

using namespace differential;
using DMat3 = differential::Mat3;

constexpr int kMaxVertices = 8;           // paths of 1..8 vertices
constexpr double kFdTolerance = 1e-6;     // relative, fd_jacobian.h defaults (central, Ridders)
constexpr double kSlopeTolerance = 0.1;   // Taylor slope 2 +- 0.1
constexpr double kDirectionTolerance = 1e-9;  // recomputed wi vs sampled wi
constexpr double kIncrementalTolerance = 1e-10;
constexpr int kAttempts = 1024;            // draws per path before a length counts as not sampled
constexpr double kPaperFactor = 4.0;      // Sec. 6.5 / App. C.1: "approximation factor of 4"

const World& scene(const std::string& name) {
  static std::map<std::string, std::unique_ptr<World>> cache;
  auto& w = cache[name];
  if (!w) w = load_world(scenes_dir() + "/" + name + ".json");
  return *w;
}

const std::vector<std::string>& jacobian_scenes() {
  static const std::vector<std::string> v = {"dg-curved-mirrors", "dg-glass", "dg-mirror-chain",
                                             "cornell-box", "glossy", "caustic"};
  return v;
}

// The blocks of a path; the broken variants replace this.
using BlockBuilder = std::function<std::vector<StepBlocks>(const ForwardPath&, const PathDifferential&)>;

std::vector<StepBlocks> correct_blocks(const ForwardPath&, const PathDifferential& d) { return d.blocks; }

// --- broken copies of step_blocks (lib/differential/path_differential.cpp) -------------------

// Copy of step_blocks with the curvature term t S_n dn/dx dropped from g_cur.
StepBlocks step_blocks_without_curvature(const ForwardPath& path, const PathDifferential& d, int j) {
  const Hit& x = path.vertices[j - 1];
  const Hit& next = path.vertices[j];
  const Vec3 prev = j == 1 ? path.eye : path.vertices[j - 2].p;
  const Vec3 e = prev - x.p;
  const double len = glm::length(e);
  const Eigen::Vector3d o(e.x / len, e.y / len, e.z / len);
  const DMat3 dwo = (DMat3::Identity() - o * o.transpose()) / len;
  const SamplingDerivative& s = d.sampling[j - 1];
  const double t = glm::length(next.p - x.p);
  const Mat23 tq = d.geometry[j].tangent.transpose() * transfer_matrix(path.wi[j - 1], next.ng);
  StepBlocks b;
  if (j > 1) b.g_prev = tq * (t * s.d_wo * dwo) * d.geometry[j - 2].tangent;
  b.g_cur = tq * (DMat3::Identity() - t * s.d_wo * dwo) * d.geometry[j - 1].tangent;  // BROKEN: no curvature
  b.g_u = tq * (t * s.d_u);
  return b;
}

std::vector<StepBlocks> blocks_without_curvature(const ForwardPath& path, const PathDifferential& d) {
  std::vector<StepBlocks> b{d.blocks[0]};
  for (int j = 1; j < d.k; ++j) b.push_back(step_blocks_without_curvature(path, d, j));
  return b;
}

// The sampling derivatives with the refraction derivative taken at eta = 1, then the correct blocks.
std::vector<StepBlocks> blocks_without_eta(const ForwardPath& path, const PathDifferential& d) {
  PathDifferential broken = d;
  for (int j = 1; j < d.k; ++j) {
    SamplingDerivative& s = broken.sampling[j - 1];
    if (s.kind != LobeKind::kRefract) continue;
    const Vec3 wo = -(j == 1 ? path.camera_dir : path.wi[j - 2]);
    DMat3 r_w, r_m;
    refract_derivative(wo, s.m, 1.0, &r_w, &r_m);  // BROKEN: eta missing
    s.d_wo = r_w;
    s.d_n = r_m * s.dm_dn;
    s.d_u = r_m * s.dm_du;
  }
  std::vector<StepBlocks> b{d.blocks[0]};
  for (int j = 1; j < d.k; ++j) b.push_back(step_blocks(path, broken, j));
  return b;
}

// g_u = A_j^-1 of every bounce transposed.
std::vector<StepBlocks> blocks_transposed(const ForwardPath&, const PathDifferential& d) {
  std::vector<StepBlocks> b = d.blocks;
  for (size_t j = 1; j < b.size(); ++j) b[j].g_u.transposeInPlace();  // BROKEN
  return b;
}

// --- the finite-difference check --------------------------------------------------------------

struct JacobianRun {
  int64_t configs = 0, sampled = 0, checked = 0, skipped = 0, failed = 0, nonfinite = 0;
  double worst_rel = 0, worst_ridders = 0, worst_slope_dev = 0, worst_direction = 0;
  int64_t worst_index = -1;
  std::map<int, int64_t> per_length;          // checked configurations per path length
  std::map<std::string, int64_t> lobe_counts;  // sampled scattering vertices per kind
};

std::string lobe_name(const Bsdf& bsdf, uint32_t flags) {
  if (flags & bsdf_flags::kDiffuse) return "diffuse";
  const std::string kind = (flags & bsdf_flags::kTransmission) ? "refract" : "reflect";
  return std::string((flags & bsdf_flags::kDelta) ? "specular_" : "glossy_") + kind + "(" + std::string(bsdf.name()) + ")";
}

JacobianRun run_jacobian(const World& world, const std::string& key_name, const CheckContext& ctx,
                         const BlockBuilder& builder) {
  JacobianRun run;
  run.configs = ctx.size(64, 512);
  const uint64_t key = hash_string(key_name);
  stats::FdOptions opt;
  opt.tolerance = opt.ridders_tolerance = kFdTolerance;
  opt.slope_tolerance = kSlopeTolerance;
  opt.seed = hash_values(ctx.seed, key);
  for (int64_t i = 0; i < run.configs; ++i) {
    const int k = 1 + static_cast<int>(i % kMaxVertices);
    const auto sp = sample_path(world, k, ctx.seed, key, static_cast<uint64_t>(i), 0.02, kAttempts);
    if (!sp) continue;
    ++run.sampled;
    for (int j = 0; j < k - 1; ++j)
      ++run.lobe_counts[lobe_name(*world.surface(sp->path.vertices[j].shape_id).bsdf, sp->path.flags[j])];
    const ForwardPath& base = sp->path;
    const Eigen::VectorXd base_x = vertex_vector(base);
    // Local coordinates v = 1 + (U - U0)/s, f~(v) = X(U)/s, so that df~/dv = dX/dU. Three passes:
    // central differences (h, h/2) at s = 2^-5 (at s = 1 their truncation error behind several
    // curved mirrors reaches 1e-5, while Ridders and Taylor agree with J to 1e-10); Ridders (Ceres: initial step 1e-2 |v|) at s = 2^-12
    // and the Taylor test (steps 1e-2 2^-k) at s = 2^-8, so that their larger steps stay where
    // the path keeps its structure (shapes hit, lobes); at s = 1 they cross structure changes;
    // at s = 2^-12 the central differences would drown in rounding. A skip in any pass skips the path.
    const Eigen::VectorXd U0 = sp->U;
    bool jumped = false;  // a structure change inside a stencil
    const auto fd_pass = [&](double scale, bool central, bool ridders, bool taylor) {
      const auto to_u = [&U0, scale](const Eigen::VectorXd& v) -> Eigen::VectorXd {
        return U0 + scale * (v.array() - 1.0).matrix();
      };
      const auto f = [&, scale](const Eigen::VectorXd& v) -> Eigen::VectorXd {
        const auto p = trace_forward(world, sp->pixel, to_u(v), k, sp->lobe);
        bool same = p.has_value() && p->flags == base.flags;
        // Triangles of one mesh face are coplanar only up to float rounding: a change of triangle
        // is a (1e-7) kink, counted as a structure change too.
        for (int j = 0; same && j < k; ++j)
          same = p->vertices[j].shape_id == base.vertices[j].shape_id && p->vertices[j].prim_id == base.vertices[j].prim_id;
        // A changed path structure is a jump: the h / h/2 comparison flags it as a discontinuity.
        if (!same) {
          jumped = true;
          return Eigen::VectorXd((base_x.array() + 1e3) / scale);
        }
        return vertex_vector(*p) / scale;
      };
      const auto jac = [&](const Eigen::VectorXd& v) -> Eigen::MatrixXd {
        const Eigen::VectorXd U = to_u(v);
        const auto p = trace_forward(world, sp->pixel, U, k, sp->lobe);
        if (!p) return Eigen::MatrixXd::Constant(3 * k, 2 * k, std::nan(""));
        const PathDifferential d = differentiate(world, sp->pixel, *p, U);
        run.worst_direction = std::max(run.worst_direction, d.max_direction_mismatch);
        return vertex_jacobian(d.geometry, builder(*p, d));
      };
      stats::FdOptions o = opt;
      if (!central) o.tolerance = kInfinity;
      o.ridders = ridders;
      o.taylor = taylor;
      return stats::check_jacobian_at(f, jac, Eigen::VectorXd::Ones(2 * k), o, static_cast<uint64_t>(i));
    };
    const stats::FdPointResult pc = fd_pass(0x1p-5, true, false, false);
    const stats::FdPointResult pr = fd_pass(0x1p-12, false, true, false);
    const stats::FdPointResult pt = fd_pass(0x1p-8, false, false, true);
    stats::FdPointResult r = pc;
    r.skipped = pc.skipped || pr.skipped || pt.skipped || jumped;
    r.nonfinite = pc.nonfinite || pr.nonfinite || pt.nonfinite;
    r.passed = pc.passed && pr.passed && pt.passed;
    r.ridders_rel_error = pr.ridders_rel_error;
    r.taylor_slope = pt.taylor_slope;
    if (r.skipped) {
      ++run.skipped;
      continue;
    }
    ++run.checked;
    ++run.per_length[k];
    if (r.nonfinite) ++run.nonfinite;
    if (!r.passed || r.nonfinite) ++run.failed;
    if (r.rel_error > run.worst_rel || run.worst_index < 0) {
      run.worst_rel = std::max(run.worst_rel, r.rel_error);
      run.worst_index = i;
    }
    run.worst_ridders = std::max(run.worst_ridders, r.ridders_rel_error);
    if (std::isfinite(r.taylor_slope)) run.worst_slope_dev = std::max(run.worst_slope_dev, std::abs(r.taylor_slope - 2));
    ctx.progress(static_cast<double>(i + 1) / static_cast<double>(run.configs));
  }
  return run;
}

nlohmann::json run_details(const JacobianRun& r) {
  nlohmann::json per_length = nlohmann::json::object(), lobes = nlohmann::json::object();
  for (const auto& [k, n] : r.per_length) per_length[std::to_string(k)] = n;
  for (const auto& [k, n] : r.lobe_counts) lobes[k] = n;
  return {{"configs", r.configs},          {"sampled", r.sampled},
          {"checked", r.checked},          {"skipped", r.skipped},
          {"failed", r.failed},            {"nonfinite", r.nonfinite},
          {"worst_rel_error", r.worst_rel}, {"worst_ridders_rel_error", r.worst_ridders},
          {"worst_taylor_slope_deviation", r.worst_slope_dev},
          {"worst_direction_mismatch", r.worst_direction},
          {"worst_index", r.worst_index},  {"checked_per_length", per_length},
          {"scattering_vertices", lobes}};
}

std::string lobe_summary(const JacobianRun& r) {
  std::string s;
  for (const auto& [k, n] : r.lobe_counts) s += fmt::format("{}{} {}", s.empty() ? "" : ", ", n, k);
  return s;
}

CheckResult jacobian_check(const std::string& scene_name, const CheckContext& ctx) {
  const JacobianRun r = run_jacobian(scene(scene_name), "differential.path.jacobian." + scene_name, ctx, correct_blocks);
  CheckResult out;
  // Every length 1..8 must have been checked at least once.
  const bool all_lengths = static_cast<int>(r.per_length.size()) == kMaxVertices;
  out.passed = r.failed == 0 && r.checked > 0 && all_lengths && r.worst_direction < kDirectionTolerance;
  out.statistic_name = "max rel. error";
  out.statistic = r.worst_rel;
  out.samples = r.checked;
  out.message = fmt::format(
      "{}: {} of {} paths (1..{} vertices) checked, {} failed, {} skipped (discontinuity), {} not sampled; worst "
      "central {:.2g}, Ridders {:.2g} (tol {:g}), worst |Taylor slope - 2| {:.3f} (tol {}), direction "
      "recomputation {:.1e}; vertices: {}",
      scene_name, r.checked, r.configs, kMaxVertices, r.failed, r.skipped, r.configs - r.sampled, r.worst_rel,
      r.worst_ridders, kFdTolerance, r.worst_slope_dev, kSlopeTolerance, r.worst_direction, lobe_summary(r));
  if (!all_lengths) out.message += "; not every path length was checked";
  out.details = run_details(r);
  return out;
}

CheckResult jacobian_negative_control(const std::string& scene_name, const std::string& what,
                                      const BlockBuilder& broken, const CheckContext& ctx) {
  const JacobianRun r =
      run_jacobian(scene(scene_name), "differential.path.jacobian.negative_control." + what, ctx, broken);
  CheckResult out;
  out.passed = r.failed > 0;  // the broken Jacobian must be caught
  out.statistic_name = "failed configurations";
  out.statistic = static_cast<double>(r.failed);
  out.samples = r.checked;
  out.message = fmt::format("{} on {}: {} of {} checked paths rejected (worst rel. error {:.2g}, tol {:g}) -> {}",
                            what, scene_name, r.failed, r.checked, r.worst_rel, kFdTolerance,
                            out.passed ? "caught" : "NOT caught");
  out.details = run_details(r);
  return out;
}

// --- incremental vs full ------------------------------------------------------------------------

using CovarianceFn = std::function<EndpointCovariance(const std::vector<StepBlocks>&, const EndpointMap&)>;

// Copy of endpoint_covariance_incremental with the update as printed in App. B.2, i.e. without
// the A_j^-1 A_j^-T of the bounce's own u_j (kept for the camera step, which starts the sums).
EndpointCovariance incremental_as_printed(const std::vector<StepBlocks>& blocks, const EndpointMap& e) {
  Mat2 s_cur = Mat2::Zero(), s_prev = Mat2::Zero(), x = Mat2::Zero(), c_cur = Mat2::Zero(), c_prev = Mat2::Zero();
  for (size_t j = 0; j < blocks.size(); ++j) {
    const StepBlocks& b = blocks[j];
    const Mat2 xn = b.g_prev * x.transpose() + b.g_cur * s_cur;
    Mat2 sn = b.g_prev * s_prev * b.g_prev.transpose() + b.g_prev * x.transpose() * b.g_cur.transpose() +
              b.g_cur * x * b.g_prev.transpose() + b.g_cur * s_cur * b.g_cur.transpose();
    if (j == 0) sn += b.g_u * b.g_u.transpose();  // BROKEN for j >= 1
    const Mat2 cn = b.g_prev * c_prev + b.g_cur * c_cur + (j == 0 ? b.g_u : Mat2::Zero());
    s_prev = s_cur;
    s_cur = sn;
    x = xn;
    c_prev = c_cur;
    c_cur = cn;
  }
  EndpointCovariance c;
  c.sigma.topLeftCorner<2, 2>() = e.p_x * s_cur * e.p_x.transpose();
  c.sigma.bottomRightCorner<2, 2>() = e.d_prev * s_prev * e.d_prev.transpose() +
                                      e.d_prev * x.transpose() * e.d_cur.transpose() +
                                      e.d_cur * x * e.d_prev.transpose() + e.d_cur * s_cur * e.d_cur.transpose();
  c.sigma.topRightCorner<2, 2>() = e.p_x * (x * e.d_prev.transpose() + s_cur * e.d_cur.transpose());
  c.sigma.bottomLeftCorner<2, 2>() = c.sigma.topRightCorner<2, 2>().transpose();
  Mat42 J;
  J.topRows<2>() = e.p_x * c_cur;
  J.bottomRows<2>() = e.d_prev * c_prev + e.d_cur * c_cur;
  c.sigma_camera = J * J.transpose();
  return c;
}

double relative_difference(const Mat4& a, const Mat4& b) {
  return (a - b).cwiseAbs().maxCoeff() / std::max(1e-300, b.cwiseAbs().maxCoeff());
}

struct IncrementalRun {
  int64_t paths = 0, over = 0;
  double worst = 0;
  std::string worst_where;
};

IncrementalRun run_incremental(const CheckContext& ctx, const CovarianceFn& incremental, const std::string& key_name) {
  IncrementalRun run;
  const int64_t per_scene = ctx.size(64, 512);
  for (const std::string& name : jacobian_scenes()) {
    const World& world = scene(name);
    const uint64_t key = hash_string(key_name + "." + name);
    for (int64_t i = 0; i < per_scene; ++i) {
      const int k = 1 + static_cast<int>(i % kMaxVertices);
      const auto sp = sample_path(world, k, ctx.seed, key, static_cast<uint64_t>(i));
      if (!sp) continue;
      const PathDifferential d = differentiate(world, sp->pixel, sp->path, sp->U);
      const EndpointMap e = endpoint_map(sp->path, d);
      const EndpointCovariance full = endpoint_covariance_full(d.blocks, e);
      const EndpointCovariance inc = incremental(d.blocks, e);
      const double err = std::max(relative_difference(inc.sigma, full.sigma),
                                  relative_difference(inc.sigma_camera, full.sigma_camera));
      ++run.paths;
      if (!(err <= kIncrementalTolerance)) ++run.over;
      if (!(err <= run.worst)) {
        run.worst = err;
        run.worst_where = fmt::format("{} path {} (k = {})", name, i, k);
      }
    }
  }
  return run;
}

CheckResult incremental_check(const CheckContext& ctx) {
  const IncrementalRun r = run_incremental(ctx, endpoint_covariance_incremental, "differential.path.incremental");
  CheckResult out;
  out.passed = r.over == 0 && r.paths > 0;
  out.statistic_name = "max rel. difference";
  out.statistic = r.worst;
  out.samples = r.paths;
  out.message = fmt::format(
      "O(k) incremental (App. B.2) vs O(k^2) recurrence (Eq. 44, 18): {} of {} paths over {:g}, worst {:.2g} at {}",
      r.over, r.paths, kIncrementalTolerance, r.worst, r.worst_where);
  out.details = {{"paths", r.paths}, {"over_tolerance", r.over}, {"worst", r.worst}, {"worst_at", r.worst_where}};
  return out;
}

CheckResult incremental_negative_control(const CheckContext& ctx) {
  const IncrementalRun r =
      run_incremental(ctx, incremental_as_printed, "differential.path.incremental.negative_control");
  CheckResult out;
  out.passed = r.over > 0;
  out.statistic_name = "paths over tolerance";
  out.statistic = static_cast<double>(r.over);
  out.samples = r.paths;
  out.message = fmt::format("B.2 update without A^-1 A^-T: {} of {} paths differ by more than {:g} (worst {:.2g}) -> {}",
                            r.over, r.paths, kIncrementalTolerance, r.worst, out.passed ? "caught" : "NOT caught");
  out.details = {{"paths", r.paths}, {"over_tolerance", r.over}, {"worst", r.worst}};
  return out;
}

// --- variance ratios -----------------------------------------------------------------------------

using FreeRatioFn = std::function<double(const World&, const ForwardPath&)>;

double free_ratio(const World& w, const ForwardPath& p) { return variance_ratio_derivative_free(w, p).r; }

// Copy of variance_ratio_derivative_free without the solid-angle compression of refractions.
[[maybe_unused]] double free_ratio_without_refraction(const World& world, const ForwardPath& path) {
  const Camera& cam = world.camera();
  const double p1 = cam.pdf_we(Ray{path.eye, path.camera_dir}).dir * static_cast<double>(cam.pixel_count());
  double r = 1.0;
  for (size_t j = 0; j < path.wi.size(); ++j)
    if (!(path.flags[j] & bsdf_flags::kDelta)) r += p1 / path.pdf[j];  // BROKEN: |di_i/di_1| = 1
  return r;
}

struct RatioRun {
  int64_t paths = 0, below = 0, outside_factor = 0, full_below_one = 0, nonfinite = 0;
  double worst_low = 1.0, worst_high = 1.0;  // min and max of r_free / r_full
  std::map<std::string, std::array<int64_t, 3>> per_scene;  // paths, below, outside factor
};

RatioRun run_ratios(const CheckContext& ctx, const FreeRatioFn& freefn, const std::vector<std::string>& scenes,
                    const std::string& key_name) {
  RatioRun run;
  const int64_t per_scene = ctx.size(128, 1024);
  for (const std::string& name : scenes) {
    const World& world = scene(name);
    const uint64_t key = hash_string(key_name + "." + name);
    auto& ps = run.per_scene[name];
    ps = {0, 0, 0};
    for (int64_t i = 0; i < per_scene; ++i) {
      const int k = 2 + static_cast<int>(i % (kMaxVertices - 1));
      const auto sp = sample_path(world, k, ctx.seed, key, static_cast<uint64_t>(i));
      if (!sp) continue;
      const PathDifferential d = differentiate(world, sp->pixel, sp->path, sp->U);
      const double full = variance_ratio(endpoint_covariance_incremental(d.blocks, endpoint_map(sp->path, d))).r;
      const double fr = freefn(world, sp->path);
      if (!std::isfinite(full) || !std::isfinite(fr)) {
        ++run.nonfinite;
        continue;
      }
      ++run.paths;
      ++ps[0];
      if (full < 1.0 - 1e-9) ++run.full_below_one;
      const double q = fr / full;
      if (q < 1.0 - 1e-9) {
        ++run.below;
        ++ps[1];
      }
      if (q > kPaperFactor || q < 1.0 / kPaperFactor) {
        ++run.outside_factor;
        ++ps[2];
      }
      run.worst_low = std::min(run.worst_low, q);
      run.worst_high = std::max(run.worst_high, q);
    }
  }
  return run;
}

nlohmann::json ratio_details(const RatioRun& r) {
  nlohmann::json per = nlohmann::json::object();
  for (const auto& [name, v] : r.per_scene) per[name] = {{"paths", v[0]}, {"free_below_full", v[1]}, {"outside_factor_4", v[2]}};
  return {{"paths", r.paths},       {"free_below_full", r.below},   {"outside_factor_4", r.outside_factor},
          {"full_below_one", r.full_below_one}, {"nonfinite", r.nonfinite}, {"min_free_over_full", r.worst_low},
          {"max_free_over_full", r.worst_high}, {"per_scene", per}};
}

CheckResult variance_ratio_check(const CheckContext& ctx) {
  const RatioRun r = run_ratios(ctx, free_ratio, jacobian_scenes(), "differential.path.variance_ratio");
  CheckResult out;
  out.passed = r.paths > 0 && r.full_below_one == 0 && r.below == 0 && r.outside_factor == 0 && r.nonfinite == 0;
  out.statistic_name = "min r_free / r_full";
  out.statistic = r.worst_low;
  out.samples = r.paths;
  out.message = fmt::format(
      "{} paths: Eq. 21 below Eq. 20 on {}, outside factor {:g} on {}, r_full < 1 on {}, non-finite {}; r_free/r_full in "
      "[{:.3g}, {:.3g}]",
      r.paths, r.below, kPaperFactor, r.outside_factor, r.full_below_one, r.nonfinite, r.worst_low, r.worst_high);
  out.details = ratio_details(r);
  return out;
}

}  // namespace

// --- registration ----------------------------------------------------------------------------------

namespace {
struct DifferentialPathChecks {
  DifferentialPathChecks() {
    auto& reg = Registry::global();
    for (const std::string& s : jacobian_scenes())
      reg.add({.name = "differential.path.jacobian." + s,
               .description = "dX/dU of the path tracer's forward map by the Eq. 44 recurrence on " + s +
                              " against central differences (h, h/2), Ridders (tol 1e-6) and a Taylor slope of 2 +- 0.1, "
                              "paths of 1..8 vertices",
               .kind = CheckKind::kDeterministic,
               .run = [s](const CheckContext& ctx) { return jacobian_check(s, ctx); }});
    reg.add({.name = "differential.path.jacobian.negative_control.dropped_curvature",
             .description = "Blocks without the dn/dx (curvature) term on dg-curved-mirrors must fail the finite-difference check",
             .kind = CheckKind::kDeterministic,
             .run = [](const CheckContext& ctx) {
               return jacobian_negative_control("dg-curved-mirrors", "dropped curvature", blocks_without_curvature, ctx);
             }});
    reg.add({.name = "differential.path.jacobian.negative_control.missing_eta",
             .description = "Refraction derivative with eta = 1 on dg-glass must fail the finite-difference check",
             .kind = CheckKind::kDeterministic,
             .run = [](const CheckContext& ctx) {
               return jacobian_negative_control("dg-glass", "missing eta", blocks_without_eta, ctx);
             }});
    reg.add({.name = "differential.path.jacobian.negative_control.transposed_block",
             .description = "Transposed A_j^-1 (g_u) blocks on cornell-box must fail the finite-difference check",
             .kind = CheckKind::kDeterministic,
             .run = [](const CheckContext& ctx) {
               return jacobian_negative_control("cornell-box", "transposed block", blocks_transposed, ctx);
             }});
    reg.add({.name = "differential.path.incremental",
             .description = "Endpoint covariance (Eq. 18) by the O(k) incremental form of App. B.2 equals the O(k^2) "
                            "recurrence to 1e-10 relative, on every scene, paths of 1..8 vertices",
             .kind = CheckKind::kDeterministic,
             .run = incremental_check});
    reg.add({.name = "differential.path.incremental.negative_control",
             .description = "The App. B.2 update as printed (without A_j^-1 A_j^-T) must differ from the recurrence",
             .kind = CheckKind::kDeterministic,
             .run = incremental_negative_control});
    reg.add({.name = "differential.path.variance_ratio",
             .description = "Derivative-free r~ (Eq. 21) against r~ from full differentials (Eq. 20) on sampled paths",
             .kind = CheckKind::kDeterministic,
             .run = variance_ratio_check});
  }
} const differential_path_checks;
}  // namespace

}  // namespace tb
