#include "validate/mcmc/path_space/proposal_projections.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "lib/core/frame.h"
#include "lib/differential/hslt_constraints.h"
#include "lib/mcmc/path_space/path_state.h"
#include "lib/geometry/spawn.h"
#include "lib/mcmc/path_space/start_paths.h"
#include "lib/path/dirac.h"
#include "lib/path/measure.h"
#include "lib/path/path.h"

namespace tb::path_space {

namespace {
BidirectionalMutation::Way way_of(const MltPath& x) {
  const int k = x.segments();
  return {k - 3, k - 1, 2};
}
const PathVertex& sampling_vertex(const MltPath& x, int s) {
  const int k = x.segments();
  return s == 1 ? x.v[k - 3] : x.v[k - 1];
}
}  // namespace

std::optional<Vec3> BidirWayProjection::sample(Uniforms& u) const {
  const auto y = mut->propose_way(x, way_of(x), s, u);
  if (!y) return std::nullopt;
  return glm::normalize(y->v[x.segments() - 2].hit.p - sampling_vertex(x, s).hit.p);
}

namespace {
// x with x_{k-2} replaced by the first hit along w from `from`, and the area factor |cos| / d^2
// there (0 when nothing is hit).
std::pair<MltPath, double> with_new_vertex(const PathContext& ctx, const MltPath& x, const PathVertex& from,
                                           const Vec3& w) {
  const auto hit = ctx.world->geometry().intersect(spawn_ray(from.hit, w));
  if (!hit) return {x, 0.0};
  MltPath y = x;
  PathVertex& v = y.v[x.segments() - 2];
  v = PathVertex{};
  v.kind = VertexKind::kSurface;
  v.hit = *hit;
  v.bsdf = ctx.world->surface(hit->shape_id).bsdf;
  v.light = ctx.world->surface(hit->shape_id).emitter;
  const double area = solid_angle_to_area(1.0, from.hit.p, v.hit.p, v.hit.ng);
  return {std::move(y), area};
}

// Is p the first hit from `from` towards it (to 1e-4 of the distance: the two points come from
// different rays)?
bool seen_from(const PathContext& ctx, const PathVertex& from, const Vec3& p) {
  const double dist = glm::length(p - from.hit.p);
  if (!(dist > 0.0)) return false;
  const auto hit = ctx.world->geometry().intersect(spawn_ray(from.hit, (p - from.hit.p) / dist));
  return hit && glm::length(hit->p - p) <= 1e-4 * std::max(1.0, dist);
}
}  // namespace

double BidirWayProjection::pdf(const Vec3& w) const {
  const auto [y, area] = with_new_vertex(mut->context(), x, sampling_vertex(x, s), w);
  if (!(area > 0.0)) return 0.0;
  const double p = split_density ? split_density(y, way_of(x).l, 1, s) : mut->split_density(y, way_of(x).l, 1, s);
  return p / area;
}

std::optional<Vec3> BidirVertexProjection::sample(Uniforms& u) const {
  const auto y = mutation->propose(x, u);
  if (!y) return std::nullopt;
  const auto w = structure->way_between(x, *y);
  const BidirectionalMutation::Way one = way_of(x);
  if (!w || w->l != one.l || w->m != one.m || w->ka != one.ka) return std::nullopt;
  const Vec3 p = y->v[x.segments() - 2].hit.p;
  if (!seen_from(*ctx, sampling_vertex(x, 1), p) || !(PathTarget{ctx}.density(*y) > 0.0)) return std::nullopt;
  return glm::normalize(p - sampling_vertex(x, 1).hit.p);
}

double BidirVertexProjection::pdf(const Vec3& w) const {
  const auto [y, area] = with_new_vertex(*ctx, x, sampling_vertex(x, 1), w);
  if (!(area > 0.0) || !(PathTarget{ctx}.density(y) > 0.0)) return 0.0;
  return mutation->density(x, y) / area;
}

std::optional<Vec2> LensOffsetProjection::sample(Uniforms& u) const {
  const auto y = mutation ? mutation->propose(x, u) : lens->propose(x, u);
  if (!y) return std::nullopt;
  const auto rx = path_raster(*ctx, x), ry = path_raster(*ctx, *y);
  if (!rx || !ry) return std::nullopt;
  const Vec2 d = *ry - *rx;
  double phi = std::atan2(d.y, d.x);
  if (phi < 0) phi += 2 * kPi;
  return Vec2(phi, 0.5 * std::log(glm::dot(d, d)));
}

double LensOffsetProjection::pdf(const Vec2& q) const {
  const double r = std::exp(q.y);
  const Vec2 d(r * std::cos(q.x), r * std::sin(q.x));
  const auto y = lens->perturb(x, d);
  if (!y) return 0.0;
  const double jac = lens->raster_jacobian(*y);
  return jac > 0.0 ? (mutation ? mutation->density(x, *y) : lens->density(x, *y)) / jac * r * r : 0.0;
}

Vec2 LensOffsetProjection::chart_lo() const { return {0.0, std::log(lens->r1()) - 0.2}; }
Vec2 LensOffsetProjection::chart_hi() const { return {2 * kPi, std::log(lens->r2()) + 0.2}; }

std::optional<Vec2> CausticAngleProjection::sample(Uniforms& u) const {
  const auto y = mutation ? mutation->propose(x, u) : caustic->propose(x, u);
  if (!y) return std::nullopt;
  const int i = caustic->perturbed_index(x);
  const Vec3 o = caustic->apex(x);
  const Vec3 w0 = glm::normalize(x.v[i].hit.p - o);
  const Vec3 local = Frame::from_z(w0).to_local(glm::normalize(y->v[i].hit.p - o));
  double phi = std::atan2(local.y, local.x);
  if (phi < 0) phi += 2 * kPi;
  return Vec2(phi, std::log(caustic->angle(x, *y)));
}

double CausticAngleProjection::pdf(const Vec2& q) const {
  const double theta = std::exp(q.y);
  const auto y = caustic->perturb(x, theta, q.x);
  if (!y) return 0.0;
  const double g = caustic->area_factor(*y);
  return g > 0.0 ? (mutation ? mutation->density(x, *y) : caustic->density(x, *y)) / g * std::sin(theta) * theta : 0.0;
}

Vec2 CausticAngleProjection::chart_lo() const { return {0.0, std::log(caustic->theta1()) - 0.2}; }
Vec2 CausticAngleProjection::chart_hi() const { return {2 * kPi, std::log(caustic->theta2()) + 0.2}; }

namespace {
// The first two uniforms fixed (the multi-chain offset), the rest from the stream.
class OffsetFixedUniforms final : public Uniforms {
 public:
  OffsetFixedUniforms(Vec2 first, Uniforms& rest) : first_(first), rest_(&rest) {}
  double next() override {
    const int i = i_++;
    return i == 0 ? first_.x : i == 1 ? first_.y : rest_->next();
  }

 private:
  Vec2 first_;
  Uniforms* rest_;
  int i_ = 0;
};

// Direction from the apex at z_i (spawn_ray's origin towards z_{i-1}) to z_{i-1}; the apex.
std::pair<Vec3, Vec3> apex_and_direction(const MltPath& z, int i) {
  const Vec3 o = spawn_ray(z.v[i].hit, direction(z.v[i], z.v[i - 1])).o;
  return {o, glm::normalize(z.v[i - 1].hit.p - o)};
}
}  // namespace

std::optional<Vec2> MultiChainAngleProjection::sample(Uniforms& u) const {
  OffsetFixedUniforms fu(u_offset, u);
  const auto y = mutation ? mutation->propose(x, fu) : sampler->propose(x, fu);
  if (!y) return std::nullopt;
  const int j1 = sampler->levels(x).front();
  const Vec3 wx = apex_and_direction(x, j1).second, wy = apex_and_direction(*y, j1).second;
  const Vec3 local = Frame::from_z(wx).to_local(wy);
  double phi = std::atan2(local.y, local.x);
  if (phi < 0) phi += 2 * kPi;
  const double theta = std::atan2(glm::length(glm::cross(wx, wy)), glm::dot(wx, wy));
  return Vec2(phi, std::log(theta));
}

double MultiChainAngleProjection::jacobian(const MltPath& y, double theta) const {
  const std::vector<int> lv = sampler->levels(x);
  const int k = y.segments(), j1 = lv[0], j2 = lv[1];
  const PathDensities d = path_densities(*ctx, y.v, DiracPolicy::kCoefficientKeptLobe);
  double g = sampler->lens().kernel_density(sampler->lens().sample_offset(u_offset)) *
             static_cast<double>(ctx->world->camera().pixel_count()) * d.pE[k - 1];
  for (int i = k - 1; i > j1; --i) g *= d.pE[i - 1];  // chain 1 (specular y_i -> y_{i-1})
  const Vec3 o = apex_and_direction(y, j1).first;
  g *= solid_angle_to_area(1.0, o, y.v[j1 - 1].hit.p, y.v[j1 - 1].geometric_normal());
  for (int i = j1 - 1; i > j2; --i) g *= d.pE[i - 1];  // chain 2
  return g / (std::sin(theta) * theta);
}

double MultiChainAngleProjection::pdf(const Vec2& q) const {
  const double theta = std::exp(q.y);
  const auto y = sampler->perturb(x, sampler->lens().sample_offset(u_offset), {Vec2(theta, q.x)});
  if (!y) return 0.0;
  const double g = jacobian(*y, theta);
  return g > 0.0 ? (mutation ? mutation->density(x, *y) : stated->density(x, *y)) / g : 0.0;
}

Vec2 MultiChainAngleProjection::chart_lo() const { return {0.0, std::log(1e-4) - 0.2}; }
Vec2 MultiChainAngleProjection::chart_hi() const { return {2 * kPi, std::log(0.1) + 0.2}; }

std::optional<Vec2> RamltLensAngleProjection::sample(Uniforms& u) const {
  const auto y = mutation ? mutation->propose(x, u) : lens->propose(x, u);
  if (!y) return std::nullopt;
  const Vec3 wx = RamltLensPerturbation::primary_direction(x), wy = RamltLensPerturbation::primary_direction(*y);
  const Vec3 local = Frame::from_z(wx).to_local(wy);
  double phi = std::atan2(local.y, local.x);
  if (phi < 0) phi += 2 * kPi;
  return Vec2(phi, std::atan2(glm::length(glm::cross(wx, wy)), glm::dot(wx, wy)));
}

double RamltLensAngleProjection::pdf(const Vec2& q) const {
  const double theta = q.y;
  const Vec3 wx = RamltLensPerturbation::primary_direction(x);
  const Vec3 w = Frame::from_z(wx).to_world(
      Vec3(std::sin(theta) * std::cos(q.x), std::sin(theta) * std::sin(q.x), std::cos(theta)));
  const auto y = lens->perturb(x, w);
  if (!y) return 0.0;
  const int k = y->segments();
  const double g = solid_angle_to_area(1.0, y->v[k].hit.p, y->v[k - 1].hit.p, y->v[k - 1].geometric_normal());
  return g > 0.0 ? (mutation ? mutation->density(x, *y) : lens->density(x, *y)) / g * std::sin(theta) : 0.0;
}

Vec2 RamltLensAngleProjection::chart_lo() const { return {0.0, 0.0}; }
Vec2 RamltLensAngleProjection::chart_hi() const { return {2 * kPi, 0.4}; }

Vec3 RamltMultiChainAngleProjection::primary() const {
  return TruncatedNormalDirection::sample(RamltLensPerturbation::primary_direction(x), u_primary, ramlt->scale().sigma(x));
}

std::optional<Vec2> RamltMultiChainAngleProjection::sample(Uniforms& u) const {
  OffsetFixedUniforms fu(u_primary, u);
  const auto y = mutation->propose(x, fu);
  if (!y) return std::nullopt;
  const int j1 = structure->levels(x).front();
  const Vec3 wx = apex_and_direction(x, j1).second, wy = apex_and_direction(*y, j1).second;
  const Vec3 local = Frame::from_z(wx).to_local(wy);
  double phi = std::atan2(local.y, local.x);
  if (phi < 0) phi += 2 * kPi;
  return Vec2(phi, std::atan2(glm::length(glm::cross(wx, wy)), glm::dot(wx, wy)));
}

double RamltMultiChainAngleProjection::pdf(const Vec2& q) const {
  const double theta = q.y;
  const std::vector<int> lv = structure->levels(x);
  const int k = x.segments(), j1 = lv[0], j2 = lv[1];
  const Vec3 wx = apex_and_direction(x, j1).second;
  const Vec3 w = Frame::from_z(wx).to_world(
      Vec3(std::sin(theta) * std::cos(q.x), std::sin(theta) * std::sin(q.x), std::cos(theta)));
  const Vec3 p0 = primary();
  const auto y = ramlt->perturb(x, p0, {w});
  if (!y) return 0.0;
  const PathDensities d = path_densities(*ctx, y->v, DiracPolicy::kCoefficientKeptLobe);
  // The primary: its truncated-normal density (Otsu Eq. 2) in solid angle, to area at y_{k-1}.
  double g = solid_angle_to_area(
      TruncatedNormalDirection::density(
          TruncatedNormalDirection::angle(RamltLensPerturbation::primary_direction(x), p0), ramlt->scale().sigma(x)),
      y->v[k].hit.p, y->v[k - 1].hit.p, y->v[k - 1].geometric_normal());
  for (int i = k - 1; i > j1; --i) g *= d.pE[i - 1];  // chain 1
  g *= solid_angle_to_area(1.0, apex_and_direction(*y, j1).first, y->v[j1 - 1].hit.p, y->v[j1 - 1].geometric_normal());
  for (int i = j1 - 1; i > j2; --i) g *= d.pE[i - 1];  // chain 2
  return g > 0.0 ? mutation->density(x, *y) / g * std::sin(theta) : 0.0;
}

std::optional<HsltTangentProjection> HsltTangentProjection::at(const HsltMutation* hslt, const PathContext* ctx,
                                                               const MltPath& x, const PathMutation* mutation) {
  const auto X = hslt->hslt_path(x);
  if (!X || X->vertices.size() != 3) return std::nullopt;
  HsltTangentProjection p;
  p.hslt = hslt;
  p.ctx = ctx;
  p.x = x;
  p.mutation = mutation;
  const HsltVertex& v1 = X->vertices[1];
  const HsltFrame fr = hslt_frame(v1);
  p.o = v1.p;
  p.n = v1.n;
  p.s = fr.s;
  p.t = fr.t;
  const HsltBlocks b = hslt_constraint_blocks(*X);
  Eigen::Matrix2d P;
  P << glm::dot(fr.s, v1.dpdu), glm::dot(fr.s, v1.dpdv), glm::dot(fr.t, v1.dpdu), glm::dot(fr.t, v1.dpdv);
  const Eigen::Matrix2d M = P * b.B[0].inverse() * hslt->step_factors(x, *X)[0];
  if (!M.allFinite()) return std::nullopt;
  const Eigen::JacobiSVD<Eigen::Matrix2d> svd(M, Eigen::ComputeFullU);
  const Eigen::Vector2d d = svd.singularValues();
  if (!(d(1) > 0.0)) return std::nullopt;
  p.to_plane = svd.matrixU() * d.asDiagonal();
  p.to_chart = p.to_plane.inverse();
  p.det = d(0) * d(1);
  return p;
}

std::optional<Vec2> HsltTangentProjection::sample(Uniforms& u) const {
  const auto y = mutation->propose(x, u);
  if (!y) return std::nullopt;
  const Vec3 d = y->v[1].hit.p - o;
  const Eigen::Vector2d q = to_chart * Eigen::Vector2d(glm::dot(d, s), glm::dot(d, t));
  if (!(std::abs(q(0)) <= kHalfWidth && std::abs(q(1)) <= kHalfWidth)) return std::nullopt;  // off the chart
  return Vec2(q(0), q(1));
}

double HsltTangentProjection::pdf(const Vec2& q) const {
  // y_1: the point of x_1's shape below o + plane(q) along -n (first hit of that shape).
  const Eigen::Vector2d pl = to_plane * Eigen::Vector2d(q.x, q.y);
  const auto shape = x.v[1].hit.shape_id;
  Ray ray{o + s * pl(0) + t * pl(1) + n * 0.5, -n, 0.0, kInfinity};
  for (int i = 0; i < 16; ++i) {
    const auto h = ctx->world->geometry().intersect(ray);
    if (!h) return 0.0;
    if (h->shape_id == shape) {
      MltPath y = x;
      y.v[1] = surface_vertex(*ctx, *h);
      const double c = std::abs(glm::dot(y.v[1].hit.ng, n));
      return c > 0.0 ? mutation->density(x, y) * det / c : 0.0;
    }
    ray.t_min = h->t + 1e-9;
  }
  return 0.0;
}

MltPath path_with_segments(const PathContext& ctx, int k, int max_depth, uint64_t seed) {
  for (uint64_t i = 0;; ++i) {
    Rng r = Rng::for_sample(seed, 0x7061746873ULL, i);
    RngUniforms u(r);
    auto x = sample_bdpt_path(ctx, u, max_depth, k);
    if (x && x->segments() == k) return *x;
  }
}

}  // namespace tb::path_space
