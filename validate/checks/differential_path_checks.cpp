// Registered checks of the path differentials and variance-bounding ratios of lib/differential
// (Zirr & Dachsbacher 2020, Sec. 6 and App. B; docs/zirr2020.md):
//   differential.path.jacobian.<scene>      dX/dU (Eq. 44 recurrence) against finite differences
//                                           of the forward map X(U): central h and h/2, Ridders
//                                           (Ceres), Taylor slope 2 +- 0.1; paths of 1..8 vertices
//   differential.path.jacobian.halfvector.<scene>   the half-vector blocks (App. B.3) against
//                                           finite differences of the half-vector map
//   differential.path.incremental           App. B.2's O(k) endpoint covariance == the O(k^2)
//                                           recurrence (Eq. 18), relative 1e-10
//   differential.path.variance_ratio.planar Eq. 21 (derivative-free) against Eq. 20 (full half-
//                                           vector differentials) on paths of planar vertices
//   differential.path.variance_ratio.curved r~ >= 1 on paths with curved vertices (Eq. 21 reported)
// and one negative control per check, each a broken copy of one piece, which must be caught:
//   differential.path.jacobian.negative_control.dropped_curvature   dn/dx = 0 in the blocks
//   differential.path.jacobian.negative_control.missing_eta         refraction derivative with eta = 1
//   differential.path.jacobian.negative_control.transposed_block    g_u = A_j^-1 transposed
//   differential.path.jacobian.halfvector.negative_control          half vector fixed in world space
//   differential.path.incremental.negative_control                  B.2 update without A_j^-1 A_j^-T
//   differential.path.variance_ratio.negative_control               Eq. 21 with the whole-image camera density
//   differential.path.variance_ratio.curved.negative_control        Sigma_d from another parameterisation
#include <algorithm>
#include <array>
#include <functional>
#include <cmath>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "lib/core/frame.h"
#include "lib/core/hash.h"
#include "lib/geometry/spawn.h"
#include "lib/material/half_vector.h"
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
using DMat4 = differential::Mat4;

constexpr int kMaxVertices = 8;           // paths of 1..8 vertices
constexpr double kFdTolerance = 1e-6;     // relative, Ridders (fd_jacobian.h default)
constexpr double kCentralTolerance = 1e-5;  // relative, central differences (see fd_pass)
constexpr double kSlopeTolerance = 0.1;   // Taylor slope 2 +- 0.1
constexpr double kDirectionTolerance = 1e-9;  // recomputed wi vs sampled wi
constexpr double kIncrementalTolerance = 1e-10;
// Rounding of the O(k^2) sums whose terms cancel (measured worst 5.9e-16 of their magnitude).
constexpr double kUncancelledTolerance = 1e-13;
constexpr int kAttempts = 1024;            // draws per path before a length counts as not sampled
// r~ of Eq. 20 comes from determinants of 2x2 projections of near-singular 4x4 covariances:
// comparisons allow this relative rounding (all-delta paths give r_full = 1 + 8e-9).
constexpr double kRatioRounding = 1e-6;
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

// Half-vector blocks with the half vector held fixed in world space instead of the local frame
// (its dependence on the normal, dm/dn, dropped).
std::vector<StepBlocks> halfvector_blocks_world_fixed(const ForwardPath& path, const PathDifferential& d) {
  PathDifferential broken = d;
  for (SamplingDerivative& s : broken.sampling) s.d_n.setZero();  // BROKEN: d_n = dwi/dm dm/dn
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

// --- the half-vector map (App. B.3) ---------------------------------------------------------------

// The frozen base quantities of the half-vector parameterisation at each bounce: the half vector
// in the local frame, the local basis orthogonal to it, and the density-preserving scale.
struct HalfVectorBase {
  std::vector<Vec3> ml0, b1, b2;
  std::vector<double> scale;
};

Frame scatter_frame(const Bsdf& bsdf, const Hit& hit, const Vec3& wo) {
  const bool transmissive = (bsdf.flags() & bsdf_flags::kTransmission) != 0;
  const double sn = (!transmissive && glm::dot(wo, hit.ng) < 0) ? -1.0 : 1.0;
  return Frame::from_z(sn * hit.n);
}

HalfVectorBase halfvector_base(const World& world, const ForwardPath& p) {
  HalfVectorBase b;
  for (size_t j = 0; j + 1 < p.vertices.size(); ++j) {
    const Hit& h = p.vertices[j];
    const Bsdf& bsdf = *world.surface(h.shape_id).bsdf;
    const Vec3 wo = -(j == 0 ? p.camera_dir : p.wi[j - 1]);
    const SamplingDerivative sd = halfvector_derivative(bsdf, h, wo, p.wi[j], p.flags[j], p.pdf[j]);
    const Frame F = scatter_frame(bsdf, h, wo);
    Vec3 t1, t2;
    coordinate_system(sd.m, &t1, &t2);
    b.ml0.push_back(F.to_local(sd.m));
    b.b1.push_back(F.to_local(t1));
    b.b2.push_back(F.to_local(t2));
    b.scale.push_back((p.flags[j] & bsdf_flags::kDelta) ? 0.0
                                                        : std::sqrt(half_vector_jacobian(wo, p.wi[j], 1.0, sd.eta) / p.pdf[j]));
  }
  return b;
}

// X(u_0, h_1, ..., h_{k-1}): the camera as in trace_forward; bounce j scatters wo about the half
// vector m = frame(n) unit(ml0 + scale (h_1 b1 + h_2 b2)), held in the local frame (Sec. 6.4).
std::optional<ForwardPath> trace_halfvector(const World& world, const SampledPath& sp, const HalfVectorBase& hb,
                                            const Eigen::VectorXd& V, int k) {
  const Camera& cam = world.camera();
  const CameraPrimaryRay cr = cam.generate_primary_ray(sp.pixel + Vec2(V[0], V[1]), Vec2(0.5));
  ForwardPath path;
  path.eye = cr.ray.o;
  path.camera_dir = cr.ray.d;
  Ray ray = cr.ray;
  for (int j = 1; j <= k; ++j) {
    const auto hit = next_vertex(world.geometry(), ray, j == 1 ? path.eye : path.vertices.back().p, j > 1);
    if (!hit) return std::nullopt;
    path.vertices.push_back(*hit);
    if (j == k) break;
    const Bsdf* bsdf = world.surface(hit->shape_id).bsdf;
    if (!bsdf) return std::nullopt;
    const size_t b = static_cast<size_t>(j - 1);
    const Vec3 wo = -ray.d;
    const Frame F = scatter_frame(*bsdf, *hit, wo);
    const Vec3 m = F.to_world(glm::normalize(hb.ml0[b] + hb.scale[b] * (V[2 * j] * hb.b1[b] + V[2 * j + 1] * hb.b2[b])));
    Vec3 wi;
    if (sp.path.flags[b] & bsdf_flags::kTransmission) {
      const double eta = glm::dot(wo, F.n) > 0 ? bsdf->eta() : 1.0 / bsdf->eta();
      const auto t = refract(wo, m, eta);
      if (!t) return std::nullopt;
      wi = *t;
    } else {
      wi = reflect(wo, m);
    }
    path.wi.push_back(wi);
    path.flags.push_back(sp.path.flags[b]);
    path.pdf.push_back(sp.path.pdf[b]);
    ray = spawn_ray(path.vertices.back(), wi);
  }
  return path;
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
                         const BlockBuilder& builder, bool halfvector = false) {
  JacobianRun run;
  run.configs = ctx.size(64, 512);
  const uint64_t key = hash_string(key_name);
  stats::FdOptions opt;
  opt.tolerance = kCentralTolerance;
  opt.ridders_tolerance = kFdTolerance;
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
    const HalfVectorBase hb = halfvector ? halfvector_base(world, base) : HalfVectorBase{};
    // The forward map: X(U) of the path tracer, or the half-vector map of (u_0, h), h = 0 at the base.
    const auto forward = [&](const Eigen::VectorXd& U) {
      if (!halfvector) return trace_forward(world, sp->pixel, U, k, sp->lobe);
      return trace_halfvector(world, *sp, hb, U, k);
    };
    // Local coordinates v = 1 + (U - U0)/s, f~(v) = X(U)/s, so that df~/dv = dX/dU. Three passes:
    // central differences (h, h/2) at s = 2^-5 (at s = 1 their truncation error behind several
    // curved mirrors reaches 1e-5, while Ridders and Taylor agree with J to 1e-10; even at s = 2^-5
    // one of 489 full-size paths reaches 3.5e-6, and at 2^-3, 2^-4, 2^-7 one or more others do:
    // central differences are held to kCentralTolerance, Ridders' extrapolation to kFdTolerance); Ridders (Ceres: initial step 1e-2 |v|) at s = 2^-12
    // and the Taylor test (steps 1e-2 2^-k) at s = 2^-8, so that their larger steps stay where
    // the path keeps its structure (shapes hit, lobes); at s = 1 they cross structure changes;
    // at s = 2^-12 the central differences would drown in rounding. A skip in any pass skips the path.
    Eigen::VectorXd U0 = sp->U;
    if (halfvector) U0.tail(2 * k - 2).setZero();
    bool jumped = false;  // a structure change inside a stencil
    const auto fd_pass = [&](double scale, bool central, bool ridders, bool taylor) {
      const auto to_u = [&U0, scale](const Eigen::VectorXd& v) -> Eigen::VectorXd {
        return U0 + scale * (v.array() - 1.0).matrix();
      };
      const auto f = [&, scale](const Eigen::VectorXd& v) -> Eigen::VectorXd {
        const auto p = forward(to_u(v));
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
        const auto p = forward(U);
        if (!p) return Eigen::MatrixXd::Constant(3 * k, 2 * k, std::nan(""));
        const PathDifferential d =
            halfvector ? differentiate(world, sp->pixel, *p, U, BounceParameterisation::kHalfVector)
                       : differentiate(world, sp->pixel, *p, U);
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

CheckResult jacobian_check(const std::string& scene_name, const CheckContext& ctx, bool halfvector = false) {
  const std::string key = std::string("differential.path.jacobian.") + (halfvector ? "halfvector." : "") + scene_name;
  const JacobianRun r = run_jacobian(scene(scene_name), key, ctx, correct_blocks, halfvector);
  CheckResult out;
  // Every length 1..8 must have been checked at least once.
  const bool all_lengths = static_cast<int>(r.per_length.size()) == kMaxVertices;
  out.passed = r.failed == 0 && r.checked > 0 && all_lengths && r.worst_direction < kDirectionTolerance;
  out.statistic_name = "max rel. error";
  out.statistic = r.worst_rel;
  out.samples = r.checked;
  out.message = fmt::format(
      "{}: {} of {} paths (1..{} vertices) checked, {} failed, {} skipped (discontinuity), {} not sampled; worst "
      "central {:.2g} (tol {:g}), Ridders {:.2g} (tol {:g}), worst |Taylor slope - 2| {:.3f} (tol {}), direction "
      "recomputation {:.1e}; vertices: {}",
      scene_name, r.checked, r.configs, kMaxVertices, r.failed, r.skipped, r.configs - r.sampled, r.worst_rel,
      kCentralTolerance, r.worst_ridders, kFdTolerance, r.worst_slope_dev, kSlopeTolerance, r.worst_direction, lobe_summary(r));
  if (!all_lengths) out.message += "; not every path length was checked";
  out.details = run_details(r);
  return out;
}

CheckResult jacobian_negative_control(const std::string& scene_name, const std::string& what,
                                      const BlockBuilder& broken, const CheckContext& ctx, bool halfvector = false) {
  const JacobianRun r =
      run_jacobian(scene(scene_name), "differential.path.jacobian.negative_control." + what, ctx, broken, halfvector);
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
  IncrementalSums z;
  Mat2 &s_cur = z.s_cur, &s_prev = z.s_prev, &x = z.x, &c_cur = z.c_cur, &c_prev = z.c_prev;
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
  return endpoint_covariance_from_sums(z, e);
}

// The two forms sum the same terms in different orders; rounding is relative to the terms before
// they cancel, in the recurrence (g_prev Phi_{j-1} + g_cur Phi_j, e.g. focusing through a glass
// sphere) and at the endpoint (d_prev Phi_{k-1} + d_cur Phi_k, a short last segment): the same
// recurrence and sums on entrywise absolute values give the scale (its largest entry).
double uncancelled_magnitude(const std::vector<StepBlocks>& blocks, const EndpointMap& e, bool camera_only) {
  const int k = static_cast<int>(blocks.size());
  DMat4 s = DMat4::Zero();
  for (int i = 0; i < (camera_only ? 1 : k); ++i) {
    std::vector<Mat2> a(static_cast<size_t>(k + 1), Mat2::Zero());
    a[i + 1] = blocks[i].g_u.cwiseAbs();
    for (int j = i + 1; j < k; ++j) a[j + 1] = blocks[j].g_prev.cwiseAbs() * a[j - 1] + blocks[j].g_cur.cwiseAbs() * a[j];
    Mat42 J;
    J.topRows<2>() = e.p_x.cwiseAbs() * a[k];
    J.bottomRows<2>() = e.d_prev.cwiseAbs() * a[k - 1] + e.d_cur.cwiseAbs() * a[k];
    s += J * J.transpose();
  }
  return s.maxCoeff();
}

double scaled_difference(const DMat4& a, const DMat4& b, double scale) {
  return (a - b).cwiseAbs().maxCoeff() / std::max(1e-300, scale);
}

struct IncrementalRun {
  int64_t paths = 0, over = 0;
  double worst = 0;
  double max_growth = 0;  // max over paths of the uncancelled scale / max |Sigma|
  double worst_uncancelled = 0;  // worst error relative to the uncancelled scale
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
      // Judged relative to max |Sigma| (resp. |Sigma_d|); the error relative to the uncancelled
      // terms is reported beside it, to tell rounding from a wrong recurrence.
      const double scale = uncancelled_magnitude(d.blocks, e, false);
      const double err = std::max(
          scaled_difference(inc.sigma, full.sigma, full.sigma.cwiseAbs().maxCoeff()),
          scaled_difference(inc.sigma_camera, full.sigma_camera, full.sigma_camera.cwiseAbs().maxCoeff()));
      const double err_unc = std::max(scaled_difference(inc.sigma, full.sigma, scale),
                                      scaled_difference(inc.sigma_camera, full.sigma_camera,
                                                        uncancelled_magnitude(d.blocks, e, true)));
      run.worst_uncancelled = std::max(run.worst_uncancelled, err_unc);
      run.max_growth = std::max(run.max_growth, scale / std::max(1e-300, full.sigma.cwiseAbs().maxCoeff()));
      ++run.paths;
      // Over tolerance: beyond 1e-10 of max |Sigma| and beyond rounding of the terms that cancel
      // into it (kUncancelledTolerance of their magnitude): the recurrences disagree.
      if (!(err <= kIncrementalTolerance) && !(err_unc <= kUncancelledTolerance)) ++run.over;
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
      "O(k) incremental (App. B.2) vs O(k^2) recurrence (Eq. 44, 18): {} of {} paths over {:g} relative to max "
      "|Sigma| and over {:g} of the uncancelled terms; worst {:.2g} of max |Sigma| at {}; relative to the "
      "uncancelled terms (up to {:.2g} x max |Sigma|) worst {:.2g}",
      r.over, r.paths, kIncrementalTolerance, kUncancelledTolerance, r.worst, r.worst_where, r.max_growth, r.worst_uncancelled);
  out.details = {{"paths", r.paths},
                 {"over_tolerance", r.over},
                 {"worst", r.worst},
                 {"worst_at", r.worst_where},
                 {"max_scale_over_sigma", r.max_growth},
                 {"worst_relative_to_uncancelled", r.worst_uncancelled}};
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

// Copy of variance_ratio_derivative_free with the camera density of the whole image (pdf_dir
// alone, without the pixel count): p(i_1) per unit image instead of per unit raster area.
double free_ratio_whole_image_density(const World& world, const ForwardPath& path) {
  const double p1 = world.camera().pdf_we(Ray{path.eye, path.camera_dir}).dir;  // BROKEN: no pixel count
  double r = 1.0, compression = 1.0;
  for (size_t j = 0; j < path.wi.size(); ++j) {
    const Hit& h = path.vertices[j];
    const Vec3 wo = -(j == 0 ? path.camera_dir : path.wi[j - 1]);
    if (path.flags[j] & bsdf_flags::kTransmission) {
      const double eta_b = world.surface(h.shape_id).bsdf->eta();
      const double eta = glm::dot(wo, h.n) > 0 ? eta_b : 1.0 / eta_b;
      Vec3 m = glm::normalize(eta * path.wi[j] + wo);
      if (glm::dot(m, wo) < 0) m = -m;
      compression *= refraction_solid_angle_ratio(wo, path.wi[j], m, eta);
    }
    if (!(path.flags[j] & bsdf_flags::kDelta)) r += p1 / (path.pdf[j] * compression);
  }
  return r;
}

// Paths whose every vertex lies on a plane (dn/du = dn/dv = 0): there the linearised geometry
// of Sec. 6.5 is the actual geometry.
bool planar_path(const ForwardPath& p) {
  for (const Hit& h : p.vertices)
    if (glm::length(h.dndu) > 0 || glm::length(h.dndv) > 0) return false;
  return true;
}

struct RatioStats {
  int64_t paths = 0, below = 0, outside_factor = 0, full_below_one = 0, nonfinite = 0;
  double min_pca = kInfinity, max_pca = 0, min_dir = kInfinity, max_dir = 0;  // r_free / r_full
  double max_full = 0;
};

struct RatioRun {
  RatioStats planar, curved;
  std::map<std::string, std::array<int64_t, 2>> per_scene;  // planar, curved paths
};

// Over sampled paths of 2..8 vertices on every scene: r_full (Eq. 20, half-vector bounces of App.
// B.3, PCA plane and the direction plane) against r_free (Eq. 21).
// The endpoint covariances of a path; the curved check's negative control replaces this.
using PathCovarianceFn = std::function<EndpointCovariance(const World&, const SampledPath&)>;

EndpointCovariance halfvector_covariance(const World& world, const SampledPath& sp) {
  const PathDifferential d = differentiate(world, sp.pixel, sp.path, sp.U, BounceParameterisation::kHalfVector);
  return endpoint_covariance_incremental(d.blocks, endpoint_map(sp.path, d));
}

// Broken: Sigma from the half-vector blocks, Sigma_d from the primary-sample blocks (two
// parameterisations mixed, so Sigma_d is no longer part of Sigma).
EndpointCovariance mixed_covariance(const World& world, const SampledPath& sp) {
  EndpointCovariance c = halfvector_covariance(world, sp);
  const PathDifferential d = differentiate(world, sp.pixel, sp.path, sp.U, BounceParameterisation::kPrimarySample);
  c.sigma_camera = endpoint_covariance_incremental(d.blocks, endpoint_map(sp.path, d)).sigma_camera;  // BROKEN
  return c;
}

RatioRun run_ratios(const CheckContext& ctx, const FreeRatioFn& freefn, const std::string& key_name,
                    const PathCovarianceFn& covfn = halfvector_covariance) {
  RatioRun run;
  const int64_t per_scene = ctx.size(128, 1024);
  for (const std::string& name : jacobian_scenes()) {
    const World& world = scene(name);
    const uint64_t key = hash_string(key_name + "." + name);
    auto& ps = run.per_scene[name];
    ps = {0, 0};
    for (int64_t i = 0; i < per_scene; ++i) {
      const int k = 2 + static_cast<int>(i % (kMaxVertices - 1));
      const auto sp = sample_path(world, k, ctx.seed, key, static_cast<uint64_t>(i));
      if (!sp) continue;
      const bool planar = planar_path(sp->path);
      RatioStats& st = planar ? run.planar : run.curved;
      ++ps[planar ? 0 : 1];
      const EndpointCovariance cv = covfn(world, *sp);
      const double full = variance_ratio(cv).r;
      const double dir = variance_ratio(cv, direction_plane()).r;
      const double fr = freefn(world, sp->path);
      if (!std::isfinite(full) || !std::isfinite(dir) || !std::isfinite(fr)) {
        ++st.nonfinite;
        continue;
      }
      ++st.paths;
      if (full < 1.0 - kRatioRounding) ++st.full_below_one;
      const double q = fr / full, qd = fr / dir;
      if (q < 1.0 - kRatioRounding) ++st.below;
      if (qd > kPaperFactor || qd < 1.0 / kPaperFactor) ++st.outside_factor;
      st.min_pca = std::min(st.min_pca, q);
      st.max_pca = std::max(st.max_pca, q);
      st.min_dir = std::min(st.min_dir, qd);
      st.max_dir = std::max(st.max_dir, qd);
      st.max_full = std::max(st.max_full, full);
    }
  }
  return run;
}

nlohmann::json stats_json(const RatioStats& s) {
  return {{"paths", s.paths},
          {"free_below_full_pca", s.below},
          {"free_over_full_direction_outside_factor_4", s.outside_factor},
          {"full_below_one", s.full_below_one},
          {"nonfinite", s.nonfinite},
          {"free_over_full_pca", {s.min_pca, s.max_pca}},
          {"free_over_full_direction_plane", {s.min_dir, s.max_dir}},
          {"max_full", s.max_full}};
}

std::string stats_line(const RatioStats& s) {
  return fmt::format(
      "{} paths: r_free < r_full(PCA) on {}, r_free/r_full(direction plane) outside [1/{:g}, {:g}] on {}, r_full < 1 on "
      "{}, non-finite {}; r_free/r_full(PCA) in [{:.3g}, {:.3g}], r_free/r_full(direction) in [{:.3g}, {:.3g}]",
      s.paths, s.below, kPaperFactor, kPaperFactor, s.outside_factor, s.full_below_one, s.nonfinite, s.min_pca,
      s.max_pca, s.min_dir, s.max_dir);
}

nlohmann::json ratio_details(const RatioRun& r) {
  nlohmann::json per = nlohmann::json::object();
  for (const auto& [name, v] : r.per_scene) per[name] = {{"planar_paths", v[0]}, {"curved_paths", v[1]}};
  return {{"planar", stats_json(r.planar)}, {"curved", stats_json(r.curved)}, {"per_scene", per}};
}

bool planar_claims_hold(const RatioStats& s) {
  return s.paths > 0 && s.below == 0 && s.outside_factor == 0 && s.full_below_one == 0 && s.nonfinite == 0;
}

CheckResult variance_ratio_planar_check(const CheckContext& ctx) {
  const RatioRun r = run_ratios(ctx, free_ratio, "differential.path.variance_ratio");
  CheckResult out;
  out.passed = planar_claims_hold(r.planar);
  out.statistic_name = "min r_free / r_full(PCA)";
  out.statistic = r.planar.min_pca;
  out.samples = r.planar.paths;
  out.message = "planar " + stats_line(r.planar);
  out.details = ratio_details(r);
  return out;
}

CheckResult variance_ratio_curved_check(const CheckContext& ctx) {
  const RatioRun r = run_ratios(ctx, free_ratio, "differential.path.variance_ratio");
  CheckResult out;
  // Asserted: r_full >= 1 (Sigma - Sigma_d is PSD) and finite. The claims of Sec. 6.5 are
  // reported, not asserted: Eq. 21 ignores curvature, which focuses or spreads the camera's beam.
  out.passed = r.curved.paths > 0 && r.curved.full_below_one == 0 && r.curved.nonfinite == 0;
  out.statistic_name = "paths with r_free < r_full(PCA)";
  out.statistic = static_cast<double>(r.curved.below);
  out.samples = r.curved.paths;
  out.message = "curved " + stats_line(r.curved);
  out.details = ratio_details(r);
  return out;
}

CheckResult variance_ratio_curved_negative_control(const CheckContext& ctx) {
  const RatioRun r = run_ratios(ctx, free_ratio, "differential.path.variance_ratio", mixed_covariance);
  CheckResult out;
  out.passed = r.curved.full_below_one > 0 || r.curved.nonfinite > 0;
  out.statistic_name = "curved paths with r_full < 1";
  out.statistic = static_cast<double>(r.curved.full_below_one);
  out.samples = r.curved.paths;
  out.message = "Sigma_d from the primary-sample blocks, Sigma from the half-vector ones: " + stats_line(r.curved) +
                " -> " + (out.passed ? "caught" : "NOT caught");
  out.details = ratio_details(r);
  return out;
}

CheckResult variance_ratio_negative_control(const CheckContext& ctx) {
  const RatioRun r = run_ratios(ctx, free_ratio_whole_image_density, "differential.path.variance_ratio");
  CheckResult out;
  out.passed = !planar_claims_hold(r.planar);
  out.statistic_name = "planar paths with r_free < r_full(PCA)";
  out.statistic = static_cast<double>(r.planar.below);
  out.samples = r.planar.paths;
  out.message = "Eq. 21 with the whole-image camera density: " + stats_line(r.planar) + " -> " +
                (out.passed ? "caught" : "NOT caught");
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
                              " against central differences (h, h/2; tol 1e-5), Ridders (tol 1e-6) and a Taylor slope of 2 +- 0.1, "
                              "paths of 1..8 vertices",
               .kind = CheckKind::kDeterministic,
               .run = [s](const CheckContext& ctx) { return jacobian_check(s, ctx); }});
    for (const std::string s : {"cornell-box", "glossy", "dg-glass"})
      reg.add({.name = "differential.path.jacobian.halfvector." + s,
               .description = "Half-vector blocks (App. B.3) on " + s +
                              " against finite differences of the half-vector map (camera u_0, then h per bounce, half "
                              "vectors held in the local frame): central (tol 1e-5), Ridders (tol 1e-6), Taylor slope 2 +- 0.1",
               .kind = CheckKind::kDeterministic,
               .run = [s](const CheckContext& ctx) { return jacobian_check(s, ctx, true); }});
    reg.add({.name = "differential.path.jacobian.halfvector.negative_control",
             .description = "Half-vector blocks with the half vector fixed in world space (dm/dn dropped) on glossy must fail",
             .kind = CheckKind::kDeterministic,
             .run = [](const CheckContext& ctx) {
               return jacobian_negative_control("glossy", "half vector fixed in world space",
                                                halfvector_blocks_world_fixed, ctx, true);
             }});
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
    reg.add({.name = "differential.path.variance_ratio.planar",
             .description = "On paths whose vertices all lie on planes: derivative-free r~ (Eq. 21) >= r~ from full "
                            "half-vector differentials (Eq. 20, PCA plane) and within a factor 4 of Eq. 20 in the "
                            "direction plane (Sec. 6.5, App. C.1); r~ >= 1",
             .kind = CheckKind::kDeterministic,
             .run = variance_ratio_planar_check});
    reg.add({.name = "differential.path.variance_ratio.curved",
             .description = "On paths with a curved vertex: r~ (Eq. 20) >= 1 and finite; Eq. 21 against Eq. 20 reported",
             .kind = CheckKind::kDeterministic,
             .run = variance_ratio_curved_check});
    reg.add({.name = "differential.path.variance_ratio.curved.negative_control",
             .description = "Sigma and Sigma_d from different bounce parameterisations must give r~ < 1 somewhere",
             .kind = CheckKind::kDeterministic,
             .run = variance_ratio_curved_negative_control});
    reg.add({.name = "differential.path.variance_ratio.negative_control",
             .description = "Eq. 21 with the whole-image instead of the per-pixel camera density must violate the planar claims",
             .kind = CheckKind::kDeterministic,
             .run = variance_ratio_negative_control});
  }
} const differential_path_checks;
}  // namespace

}  // namespace tb
