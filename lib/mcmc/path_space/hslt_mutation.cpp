#include "lib/mcmc/path_space/hslt_mutation.h"

#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "lib/differential/hslt_block_lu.h"
#include "lib/differential/hslt_constraints.h"
#include "lib/camera/camera.h"
#include "lib/material/bsdf.h"
#include "lib/material/half_vector.h"
#include "lib/path/dirac.h"
#include "lib/mcmc/path_space/mlt.h"
#include "lib/scene/world.h"

namespace tb::path_space {

namespace {

constexpr auto kRelaxed = std::memory_order_relaxed;

// Index of refraction of the medium on the side of `p` of the surface at v (outward normals:
// the geometric normal points outside, Bsdf::eta is the inside index).
double side_eta(const PathVertex& v, const Vec3& p) {
  const double eta = v.bsdf->eta();
  if (eta == 1.0) return 1.0;
  return glm::dot(v.hit.ng, p - v.hit.p) > 0.0 ? 1.0 : eta;
}

}  // namespace

HsltCountsSnapshot snapshot(const HsltCounters& c) {
  HsltCountsSnapshot s;
  s.proposals = c.proposals.load(kRelaxed);
  s.not_applicable = c.not_applicable.load(kRelaxed);
  for (int i = 0; i < kHsltWalkStatusCount; ++i) s.status[static_cast<size_t>(i)] = c.forward_status[static_cast<size_t>(i)].load(kRelaxed);
  s.converged = s.status[static_cast<size_t>(HsltWalkStatus::kConverged)];
  s.iterations_converged = c.iterations_converged.load(kRelaxed);
  s.iterations_all = c.iterations_all.load(kRelaxed);
  s.non_reversible = c.non_reversible.load(kRelaxed);
  s.generated = c.generated.load(kRelaxed);
  s.jump_attempted = c.jump_attempted.load(kRelaxed);
  s.jump_projected = c.jump_projected.load(kRelaxed);
  s.jump_succeeded = c.jump_succeeded.load(kRelaxed);
  return s;
}

HsltMutation::HsltMutation(const PathContext& ctx, double gamma, std::shared_ptr<HsltCounters> counters, bool stratify,
                           double image_fraction, bool jump)
    : ctx_(&ctx), gamma_(gamma), counters_(counters ? std::move(counters) : std::make_shared<HsltCounters>()),
      stratify_(stratify), image_fraction_(image_fraction), jump_(jump) {
  options_.visibility = true;  // the proposal must be a path with f > 0: no shape between vertices
  options_.side = HsltProjectionSide::kHeuristic;  // Sec. 5.1, Table 2
}

bool HsltMutation::applicable(const MltPath& x) const {
  const int k = x.segments();
  if (k < 2 || x.v[static_cast<size_t>(k)].kind != VertexKind::kCamera) return false;
  const PathVertex& e = x.v[0];
  if (e.infinite || e.light == nullptr) return false;
  int non_diffuse = 0, non_dirac = 0;
  for (int i = 1; i < k; ++i) {
    const PathVertex& v = x.v[static_cast<size_t>(i)];
    if (!v.is_surface() || v.bsdf == nullptr) return false;
    const double a = v.bsdf->beckmann_roughness();
    non_diffuse += std::isfinite(a) ? 1 : 0;
    non_dirac += is_dirac_surface(v) ? 0 : 1;
  }
  return non_diffuse >= 1 && non_dirac >= 1;
}

bool hslt_applies(const HsltMutation& m, const MltPath& x) { return m.applicable(x); }

std::optional<HsltPath> HsltMutation::hslt_path(const MltPath& x, const HsltPath* frames_of) const {
  const int k = x.segments();
  if (k < 2) return std::nullopt;
  if (frames_of && frames_of->segments() != k) return std::nullopt;
  HsltPath X;
  X.vertices.reserve(static_cast<size_t>(k + 1));
  const PathVertex& e = x.v[0];
  X.vertices.push_back(e.delta ? make_point_vertex(e.hit.p) : make_hslt_vertex(e.hit));
  for (int i = 1; i < k; ++i) {
    const auto ui = static_cast<size_t>(i);
    const PathVertex& v = x.v[ui];
    if (!v.is_surface() || v.bsdf == nullptr) return std::nullopt;
    HsltVertex h = make_hslt_vertex(v.hit, side_eta(v, x.v[ui - 1].hit.p), side_eta(v, x.v[ui + 1].hit.p));
    if (frames_of) {
      const HsltVertex& r = frames_of->vertices[ui];
      if (r.shape_id != h.shape_id || r.prim_id != h.prim_id || r.eta_prev != h.eta_prev || r.eta_next != h.eta_next)
        return std::nullopt;
      h.frame_ref = r.frame_ref;
    }
    X.vertices.push_back(h);
  }
  X.vertices.push_back(make_point_vertex(x.v[static_cast<size_t>(k)].hit.p));
  if (frames_of) X.vertices.front().frame_ref = frames_of->vertices.front().frame_ref;
  return X;
}

std::vector<double> HsltMutation::sigmas(const MltPath& x) const {
  std::vector<double> s;
  for (int i = 1; i < x.segments(); ++i) {
    const PathVertex& v = x.v[static_cast<size_t>(i)];
    if (is_dirac_surface(v)) {
      s.push_back(0.0);
      continue;
    }
    double a = v.bsdf->beckmann_roughness();
    if (!std::isfinite(a)) a = kDiffuseAlpha;
    // Kaplanyan 2014, Sec. 6.1: expected step gamma alpha / sqrt(pi); a 2D Gaussian of standard
    // deviation sigma per axis has expected step length sigma sqrt(pi / 2).
    s.push_back(gamma_ * a * std::sqrt(2.0) / kPi);
  }
  return s;
}

std::vector<Eigen::Matrix2d> HsltMutation::step_factors(const MltPath& x, const HsltPath& X) const {
  const std::vector<double> s = sigmas(x);
  std::vector<Eigen::Matrix2d> L(s.size());
  for (size_t r = 0; r < s.size(); ++r) L[r] = s[r] * Eigen::Matrix2d::Identity();
  if (!stratify_) return L;
  // Sec. 6.2: the camera ray differentials at x_{k-1}, on its tangent plane, in its (u, v).
  const int k = X.segments();
  const HsltVertex& v = X.vertices[static_cast<size_t>(k - 1)];
  const Camera& cam = ctx_->world->camera();
  const std::optional<Vec2> raster = path_raster(*ctx_, x);
  if (!raster) return L;
  const CameraRay cr = cam.generate_ray(*raster, Vec2(0.5));
  if (!cr.ray.has_differentials) return L;
  const auto on_plane = [&](const Vec3& o, const Vec3& d) -> std::optional<Vec3> {
    const double den = glm::dot(d, v.ng);
    if (!(std::abs(den) > 1e-12)) return std::nullopt;
    return o + d * (glm::dot(v.p - o, v.ng) / den);
  };
  const auto p0 = on_plane(cr.ray.o, cr.ray.d), pu = on_plane(cr.ray.rx_o, cr.ray.rx_d),
             pv = on_plane(cr.ray.ry_o, cr.ray.ry_d);
  if (!p0 || !pu || !pv) return L;
  Eigen::Matrix<double, 3, 2> T;
  T << v.dpdu.x, v.dpdv.x, v.dpdu.y, v.dpdv.y, v.dpdu.z, v.dpdv.z;
  const Eigen::Matrix2d G = T.transpose() * T;
  if (!(std::abs(G.determinant()) > 0)) return L;
  const double scale = image_fraction_ * std::max(cam.width(), cam.height());
  const auto to_uv = [&](const Vec3& d) {
    return Eigen::Vector2d(G.inverse() * (T.transpose() * Eigen::Vector3d(d.x, d.y, d.z)) * scale);
  };
  const Eigen::Vector2d du = to_uv(*pu - *p0), dv = to_uv(*pv - *p0);
  // Eq. 9: D_i = (J^{-1})_{k-1, i}, dx_{k-1} = D_i dh_i (Kaplanyan 2014, Sec. 6.2, Sec. 7).
  std::vector<Eigen::Matrix2d> D;
  if (!hslt_inverse_last_block_row(hslt_constraint_blocks(X), &D)) return L;
  double sum = 0.0;
  for (double si : s) sum += si;
  if (!(sum > 0)) return L;
  for (size_t r = 0; r < s.size(); ++r) {
    if (!(s[r] > 0)) continue;
    if (!(std::abs(D[r].determinant()) > 1e-300)) continue;
    const Eigen::Matrix2d Dinv = D[r].inverse();
    const Eigen::Vector2d hu = Dinv * du, hv = Dinv * dv;
    const double l1 = hu.norm();
    if (!(l1 > 0) || !std::isfinite(l1) || !hv.allFinite()) continue;
    const Eigen::Vector2d e1 = hu / l1, e2(-e1(1), e1(0));
    const double l2 = std::abs(hv.dot(e2));
    const double w = s[r] / sum;  // Sec. 6.3 bandwidth weight
    const double s1 = std::max(std::min(s[r], w * l1), 1e-3 * s[r]);
    const double s2 = std::max(std::min(s[r], w * l2), 1e-3 * s[r]);
    Eigen::Matrix2d E;
    E.col(0) = e1;
    E.col(1) = e2;
    L[r] = E * Eigen::Vector2d(s1, s2).asDiagonal();
  }
  return L;
}

Eigen::VectorXd HsltMutation::perturbed_target(const HsltPath& X, const std::vector<Eigen::Matrix2d>& L, Uniforms& u) const {
  Eigen::VectorXd t = hslt_constraints(X);
  for (size_t r = 0; r < L.size(); ++r) {
    if (L[r].isZero(0.0)) continue;
    const Vec2 w = u.next2();
    const double len = std::sqrt(-2.0 * std::log1p(-w.x));  // Box-Muller
    const double phi = 2.0 * kPi * w.y;
    t.segment<2>(static_cast<Eigen::Index>(2 * r)) += L[r] * Eigen::Vector2d(len * std::cos(phi), len * std::sin(phi));
  }
  return t;
}

bool HsltMutation::perturbation_density(const std::vector<Eigen::Matrix2d>& L, const HsltPath& X, const HsltPath& Y,
                                        double* g, std::vector<bool>* dirac) const {
  const Eigen::VectorXd hx = hslt_constraints(X), hy = hslt_constraints(Y);
  dirac->assign(L.size(), false);
  double log_g = 0.0;
  for (size_t r = 0; r < L.size(); ++r) {
    const Eigen::Vector2d d = hy.segment<2>(static_cast<Eigen::Index>(2 * r)) - hx.segment<2>(static_cast<Eigen::Index>(2 * r));
    if (L[r].isZero(0.0)) {
      (*dirac)[r] = true;
      if (!(d.norm() < kDiracHoldTolerance)) return false;
      continue;
    }
    const Eigen::Vector2d z = L[r].inverse() * d;
    log_g += -std::log(2.0 * kPi * std::abs(L[r].determinant())) - 0.5 * z.squaredNorm();
  }
  *g = std::exp(log_g);
  return true;
}

HsltWalkResult HsltMutation::walk(const HsltPath& X, const Eigen::VectorXd& target) const {
  return hslt_walk(ctx_->world->geometry(), X, target, options_);
}

MltPath HsltMutation::path_at(const MltPath& x, const HsltPath& walked) const {
  MltPath y = x;
  const Scene& scene = ctx_->world->geometry();
  for (int i = 1; i < x.segments(); ++i) {
    const HsltVertex& h = walked.vertices[static_cast<size_t>(i)];
    y.v[static_cast<size_t>(i)] = surface_vertex(*ctx_, scene.surface_at(h.shape_id, h.prim_id, h.uv));
  }
  return y;
}

bool HsltMutation::lands(const HsltPath& X, const HsltPath& Y) const {
  const HsltWalkResult r = walk(X, hslt_constraints(Y));
  return r.status == HsltWalkStatus::kConverged && hslt_max_vertex_distance(r.path, Y) < kLandingTolerance;
}

double HsltMutation::measure_factor(const HsltPath& Y, const std::vector<bool>& dirac) const {
  const HsltBlocks b = hslt_constraint_blocks(Y);
  const HsltBlockLu lu(b);
  if (!lu.ok()) return 0.0;
  // Kaplanyan 2014, Eq. 11 in area measure: det J_area = det J_uv / prod |dp/du x dp/dv|.
  double log_m = lu.log_abs_determinant();
  for (int i = 1; i < Y.segments(); ++i) log_m -= std::log(Y.vertices[static_cast<size_t>(i)].area_element());
  double m = std::exp(log_m);
  for (int i = 1; i < Y.segments(); ++i) {
    if (!dirac[static_cast<size_t>(i - 1)]) continue;
    const HsltVertex& v = Y.vertices[static_cast<size_t>(i)];
    const HsltHalfVector hv = hslt_half_vector(Y, i);
    // |dh / d omega_prev| at fixed omega_next (Eq. 10 with the roles of the directions swapped);
    // dh^perp = |<h, n>| dh (App. A).
    const double dh_dw = half_vector_jacobian(hv.w_next, hv.w_prev, v.eta_next, v.eta_prev);
    m /= dh_dw * std::abs(glm::dot(hv.h, v.n));
  }
  return std::isfinite(m) ? m : 0.0;
}

HsltMutation::DensityParts HsltMutation::density_parts(const MltPath& x, const MltPath& y) const {
  DensityParts p;
  const int k = x.segments();
  if (y.segments() != k || !applicable(x) || !applicable(y)) return p;
  if (!same_vertex(x.v[0], y.v[0]) || !same_vertex(x.v[static_cast<size_t>(k)], y.v[static_cast<size_t>(k)])) return p;
  const std::optional<HsltPath> X = hslt_path(x);
  if (!X) return p;
  const std::optional<HsltPath> Y = hslt_path(y, &*X);
  if (!Y) return p;
  std::vector<bool> dirac;
  double g = 0.0;
  if (!perturbation_density(step_factors(x, *X), *X, *Y, &g, &dirac)) return p;
  p.structure = true;
  p.perturbation = g;
  p.measure = measure_factor(*Y, dirac);
  if (!(p.perturbation > 0.0) || !(p.measure > 0.0)) return p;
  p.forward_lands = lands(*X, *Y);
  if (!p.forward_lands) return p;
  // Sec. 5.2: the reverse walk, from y in its own frames to H^perp(x) in the same frames.
  const std::optional<HsltPath> Y2 = hslt_path(y);
  const std::optional<HsltPath> X2 = Y2 ? hslt_path(x, &*Y2) : std::nullopt;
  p.reverse_lands = X2 && lands(*Y2, *X2);
  return p;
}

double HsltMutation::density(const MltPath& x, const MltPath& y) const {
  const DensityParts p = density_parts(x, y);
  if (p.structure && p.forward_lands && p.reverse_lands) {
    // The regular branch is taken only when the first prediction towards h* = H(y) does not jump.
    if (jump_ && jump_applicable(x)) {
      const std::optional<HsltPath> X = hslt_path(x);
      const std::optional<HsltPath> Y = hslt_path(y, &*X);
      if (jump_preempts(x, *X, hslt_constraints(*Y))) return 0.0;
    }
    return p.perturbation * p.measure;
  }
  // Sec. 5.2: the two branches are exclusive (the jump needs both landings to fail).
  return jump_ ? jump_density(x, y) : 0.0;
}

std::optional<MltPath> HsltMutation::jump_proposal(const MltPath& x, const HsltPath& X, const Eigen::VectorXd& target) const {
  std::optional<JumpPrediction> jp = jump_predict(x, X, target);
  if (!jp || !jump_applicable(jp->y) || !bidirectionally_invalid(x, jp->y)) return std::nullopt;
  return std::move(jp->y);
}

bool HsltMutation::jump_preempts(const MltPath& x, const HsltPath& X, const Eigen::VectorXd& target) const {
  return jump_proposal(x, X, target).has_value();
}

bool HsltMutation::jump_applicable(const MltPath& x) const {
  if (!applicable(x)) return false;
  for (int i = 1; i < x.segments(); ++i)
    if (is_dirac_surface(x.v[static_cast<size_t>(i)])) return false;
  return true;
}

namespace {

// Unit normal of the tangent plane of an HsltVertex (the plane the predictor moves on).
Vec3 tangent_plane_normal(const HsltVertex& v) { return glm::normalize(glm::cross(v.dpdu, v.dpdv)); }

// |cos| / d^2 at the receiving point b of a ray from a (the solid-angle-to-area factor; the
// cosine at a cancels in the ratio of Sec. 5.2).
double receiving_g(const Vec3& a, const Vec3& b, const Vec3& nb) {
  const Vec3 d = b - a;
  const double l2 = glm::dot(d, d);
  return std::abs(glm::dot(nb, d)) / (std::sqrt(l2) * l2);
}

}  // namespace

std::optional<HsltMutation::JumpPrediction> HsltMutation::jump_predict(const MltPath& x, const HsltPath& X,
                                                                        const Eigen::VectorXd& target) const {
  const int k = X.segments();
  const HsltBlocks b = hslt_constraint_blocks(X);
  const HsltBlockLu lu(b);
  if (!lu.ok()) return std::nullopt;
  // The walk's first predictor step (hslt_walk.cpp, lambda = 1): Delta = -J^{-1} (H(X) - h*).
  const Eigen::VectorXd F = hslt_constraints(X) - target;
  const Eigen::VectorXd delta = -lu.solve(F);
  if (!delta.allFinite()) return std::nullopt;
  JumpPrediction jp;
  jp.y = x;
  jp.predicted.assign(X.vertices.size(), Vec3(0.0));
  for (int i = 1; i < k; ++i) {
    const HsltVertex& v = X.vertices[static_cast<size_t>(i)];
    const Eigen::Index c = 2 * (i - 1);
    jp.predicted[static_cast<size_t>(i)] = v.p + v.dpdu * delta[c] + v.dpdv * delta[c + 1];
  }
  jp.from_start = !(hslt_projection_side_ratio(b) < 1.0);  // the walk's heuristic side (Table 2)
  const Scene& scene = ctx_->world->geometry();
  for (int step = 1; step < k; ++step) {
    const int i = jp.from_start ? step : k - step;
    const int prev = jp.from_start ? i - 1 : i + 1;
    const Vec3 o = jp.y.v[static_cast<size_t>(prev)].hit.p;
    const Vec3 d = jp.predicted[static_cast<size_t>(i)] - o;
    const double len = glm::length(d);
    if (!(len > 0) || !std::isfinite(len)) return std::nullopt;
    const Ray ray{o, d / len, 1e-5 * std::max(1.0, glm::length(o)), kInfinity};
    const std::optional<Hit> hit = scene.intersect(ray);
    if (!hit) return std::nullopt;
    // Grazing rays (a previous vertex on the tangent plane of x_i, e.g. two vertices on one plane):
    // G ~ 0, and x'_i is not recoverable from the pair; rejected here and hence in the density.
    if (!(std::abs(glm::dot(ray.d, tangent_plane_normal(X.vertices[static_cast<size_t>(i)]))) >= kJumpMinCos) ||
        !(std::abs(glm::dot(ray.d, hit->ng)) >= kJumpMinCos))
      return std::nullopt;
    PathVertex pv = surface_vertex(*ctx_, *hit);
    if (!pv.is_surface() || pv.bsdf == nullptr) return std::nullopt;
    jp.y.v[static_cast<size_t>(i)] = std::move(pv);
  }
  const int a = jp.from_start ? k - 1 : 1, e = jp.from_start ? k : 0;
  const Vec3 pa = jp.y.v[static_cast<size_t>(a)].hit.p, pe = jp.y.v[static_cast<size_t>(e)].hit.p;
  const double len = glm::length(pe - pa);
  if (!(len > 0)) return std::nullopt;
  const Ray closing{pa, (pe - pa) / len, 1e-5 * std::max(1.0, glm::length(pa)), len * (1 - 1e-6)};
  if (scene.occluded(closing)) return std::nullopt;
  return jp;
}

bool HsltMutation::bidirectionally_invalid(const MltPath& x, const MltPath& y) const {
  const std::optional<HsltPath> X = hslt_path(x);
  const std::optional<HsltPath> Yx = X ? hslt_path(y, &*X) : std::nullopt;
  if (X && Yx && lands(*X, *Yx)) return false;
  const std::optional<HsltPath> Y = hslt_path(y);
  const std::optional<HsltPath> Xy = Y ? hslt_path(x, &*Y) : std::nullopt;
  return !(Y && Xy && lands(*Y, *Xy));
}

HsltMutation::JumpParts HsltMutation::jump_parts(const MltPath& x, const MltPath& y) const {
  JumpParts p;
  const int k = x.segments();
  if (y.segments() != k || !jump_applicable(x) || !jump_applicable(y)) return p;
  if (!same_vertex(x.v[0], y.v[0]) || !same_vertex(x.v[static_cast<size_t>(k)], y.v[static_cast<size_t>(k)])) return p;
  const std::optional<HsltPath> X = hslt_path(x);
  if (!X) return p;
  const HsltBlocks b = hslt_constraint_blocks(*X);
  const bool from_start = !(hslt_projection_side_ratio(b) < 1.0);
  // x'_i: the line y_prev -> y_i meets the tangent plane of x_i (the inverse of the ray cast).
  Eigen::VectorXd duv(2 * (k - 1));
  double log_g = 0.0;
  for (int step = 1; step < k; ++step) {
    const int i = from_start ? step : k - step;
    const int prev = from_start ? i - 1 : i + 1;
    const HsltVertex& v = X->vertices[static_cast<size_t>(i)];
    const Vec3 o = y.v[static_cast<size_t>(prev)].hit.p, yi = y.v[static_cast<size_t>(i)].hit.p;
    const Vec3 nt = tangent_plane_normal(v);
    const Vec3 d = yi - o;
    const double den = glm::dot(d, nt);
    if (!(std::abs(den) > 0)) return p;
    const double t = glm::dot(v.p - o, nt) / den;
    if (!(t > 0) || !std::isfinite(t)) return p;
    const Vec3 xp = o + d * t;
    const Vec3 r = xp - v.p;
    const double g11 = glm::dot(v.dpdu, v.dpdu), g12 = glm::dot(v.dpdu, v.dpdv), g22 = glm::dot(v.dpdv, v.dpdv);
    const double det = g11 * g22 - g12 * g12;
    if (!(det > 0)) return p;
    const double ru = glm::dot(r, v.dpdu), rv = glm::dot(r, v.dpdv);
    duv[2 * (i - 1)] = (g22 * ru - g12 * rv) / det;
    duv[2 * (i - 1) + 1] = (g11 * rv - g12 * ru) / det;
    // Sec. 5.2, second equation: G(y_prev, y_i) / G(y_prev, x'_i) (area of the surface at y_i,
    // geometric normal; area of the tangent plane at x'_i).
    log_g += std::log(receiving_g(o, yi, y.v[static_cast<size_t>(i)].hit.ng)) - std::log(receiving_g(o, xp, nt));
  }
  const Eigen::VectorXd dh = hslt_dense_jacobian(b) * duv;
  p.target = hslt_constraints(*X) + dh;
  const std::vector<Eigen::Matrix2d> L = step_factors(x, *X);
  double log_n = 0.0;
  for (size_t r = 0; r < L.size(); ++r) {
    const Eigen::Vector2d z = L[r].inverse() * dh.segment<2>(static_cast<Eigen::Index>(2 * r));
    log_n += -std::log(2.0 * kPi * std::abs(L[r].determinant())) - 0.5 * z.squaredNorm();
  }
  p.structure = true;
  p.perturbation = std::exp(log_n);
  p.measure = measure_factor(*X, std::vector<bool>(L.size(), false));
  p.g_ratio = std::exp(log_g);
  if (!(p.perturbation > 0) || !(p.measure > 0) || !std::isfinite(p.g_ratio)) return p;
  const std::optional<JumpPrediction> jp = jump_predict(x, *X, p.target);
  if (!jp) return p;
  double dist = 0.0;
  for (int i = 1; i < k; ++i)
    dist = std::max(dist, glm::length(jp->y.v[static_cast<size_t>(i)].hit.p - y.v[static_cast<size_t>(i)].hit.p));
  p.replay_lands = dist < kLandingTolerance;
  if (!p.replay_lands) return p;
  p.bidirectionally_invalid = bidirectionally_invalid(x, y);
  return p;
}

double HsltMutation::jump_density(const MltPath& x, const MltPath& y) const {
  const JumpParts p = jump_parts(x, y);
  if (!p.structure || !p.replay_lands || !p.bidirectionally_invalid) return 0.0;
  const double t = p.perturbation * p.measure * p.g_ratio;
  return std::isfinite(t) ? t : 0.0;
}

std::optional<MltPath> HsltMutation::propose(const MltPath& x, Uniforms& u) const {
  HsltCounters& c = *counters_;
  if (!applicable(x)) {
    c.not_applicable.fetch_add(1, kRelaxed);
    return std::nullopt;
  }
  const std::optional<HsltPath> X = hslt_path(x);
  if (!X) {
    c.not_applicable.fetch_add(1, kRelaxed);
    return std::nullopt;
  }
  c.proposals.fetch_add(1, kRelaxed);
  // Fig. 12: mutate_half_vectors (Sec. 6.1), h_to_positions (Sec. 5), reverse check (Sec. 5.2).
  const Eigen::VectorXd target = perturbed_target(*X, step_factors(x, *X), u);
  // Sec. 5.2: the subspace jump from the walk's first prediction, taken when the prediction is a
  // valid path and the pair is bidirectionally invalid (a condition on the pair alone).
  if (jump_ && jump_applicable(x)) {
    c.jump_attempted.fetch_add(1, kRelaxed);
    std::optional<JumpPrediction> jp = jump_predict(x, *X, target);
    if (jp && jump_applicable(jp->y)) {
      c.jump_projected.fetch_add(1, kRelaxed);
      if (bidirectionally_invalid(x, jp->y)) {
        c.jump_succeeded.fetch_add(1, kRelaxed);
        c.generated.fetch_add(1, kRelaxed);
        return std::move(jp->y);
      }
    }
  }
  const HsltWalkResult r = walk(*X, target);
  c.forward_status[static_cast<size_t>(r.status)].fetch_add(1, kRelaxed);
  c.iterations_all.fetch_add(r.iterations, kRelaxed);
  if (r.status != HsltWalkStatus::kConverged) return std::nullopt;
  c.iterations_converged.fetch_add(r.iterations, kRelaxed);
  MltPath y = path_at(x, r.path);
  const std::optional<HsltPath> Y2 = applicable(y) ? hslt_path(y) : std::nullopt;
  const std::optional<HsltPath> X2 = Y2 ? hslt_path(x, &*Y2) : std::nullopt;
  if (!X2 || !hslt_path(y, &*X) || !lands(*Y2, *X2)) {
    c.non_reversible.fetch_add(1, kRelaxed);
    return std::nullopt;
  }
  c.generated.fetch_add(1, kRelaxed);
  return y;
}

PathMutationList make_hslt_mixture(const PathContext& ctx, const PathMutationSettings& s,
                                   const std::shared_ptr<HsltCounters>& counters, double gamma, bool stratify,
                                   bool jump) {
  const PathMutationInfo* bidir = find_path_mutation("bidirectional");
  const PathMutationInfo* hslt = find_path_mutation("hslt");
  PathMutationList out;
  out.push_back(bidir->make(ctx, s, bidir->weight));
  out.push_back(std::make_shared<const PathProposalMutation<HsltMutation>>(
      "hslt", hslt->weight, HsltMutation(ctx, gamma, counters, stratify, HsltMutation::kImageFraction, jump),
      hslt_applies));
  return out;
}

}  // namespace tb::path_space

namespace tb::path_space {

void print_walk_statistics(const char* label, const char* mutation, const char* what, const HsltCounters& counters,
                           const MltStats& stats) {
  const HsltCountsSnapshot c = snapshot(counters);
  double acc = 0.0, acc_generated = 0.0;
  for (const auto& m : stats.mutations)
    if (m.name == mutation) {
      acc = m.acceptance_rate();
      acc_generated = m.proposed > m.failed ? double(m.accepted) / double(m.proposed - m.failed) : 0.0;
    }
  // Kaplanyan 2014, Table 3 (per proposal of the mutation on a path it applies to).
  fmt::print("{}: {} {} proposals ({} selected on paths it does not apply to); iterations "
             "{:.2f} per converged walk / {:.2f} per walk; generation rate {:.1f}%; non-reversible {} = {:.3f}% of the "
             "converged walks; acceptance {:.1f}% of the generated ({:.1f}% of the selected); {:.3g} mutations/s (all "
             "mutations)\n",
             label, c.proposals, what, c.not_applicable, c.iterations_per_converged(), c.iterations_per_walk(),
             100.0 * c.generation_rate(), c.non_reversible, 100.0 * c.non_reversible_fraction(), 100.0 * acc_generated,
             100.0 * acc, stats.mutations_per_second());
}

}  // namespace tb::path_space

namespace tb {

int64_t render_hslt(const World& world, const RenderSettings& settings, Film& film) {
  using namespace path_space;
  const auto counters = std::make_shared<HsltCounters>();
  MltOptions o;
  const auto param = [&settings](const char* name, double fallback) {
    const auto it = settings.params.find(name);
    return it == settings.params.end() ? fallback : it->second;
  };
  const double gamma = param("gamma", HsltMutation::kDefaultGamma);
  const bool stratify = param("stratify", 1.0) != 0.0;
  const bool jump = param("jump", HsltMutation::kDefaultJump ? 1.0 : 0.0) != 0.0;
  if (!(gamma > 0.0)) throw std::invalid_argument("hslt: parameter 'gamma' must be > 0");
  o.mutations = [counters, gamma, stratify, jump](const PathContext& ctx, const PathMutationSettings& s) {
    return make_hslt_mixture(ctx, s, counters, gamma, stratify, jump);
  };
  const MltStats stats = run_mlt(world, settings, film, o);
  fill_report(stats, settings.report);
  print_walk_statistics("hslt (Table 3)", "hslt", "half-vector", *counters, stats);
  const HsltCountsSnapshot c = snapshot(*counters);
  // Table 3 "Submanifold jump" (Sec. 5.2).
  fmt::print("hslt subspace jumps (Sec. 5.2, {}): {} attempted (proposals on paths without a specular vertex), {} first "
             "predictions projected to a valid path, {} succeeded (bidirectionally invalid, proposed as jumps) = {:.2f}% of the "
             "attempted\n",
             jump ? "on" : "off", c.jump_attempted, c.jump_projected, c.jump_succeeded, 100.0 * c.jump_success_rate());
  return stats.chains;
}

}  // namespace tb
