#include "lib/mcmc/path_space/proposal_projections.h"

#include <cmath>

#include "lib/core/frame.h"
#include "lib/geometry/spawn.h"
#include "lib/mcmc/path_space/start_paths.h"
#include "lib/path/measure.h"

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

double BidirWayProjection::pdf(const Vec3& w) const {
  const PathContext& ctx = mut->context();
  const PathVertex& from = sampling_vertex(x, s);
  const auto hit = ctx.world->geometry().intersect(spawn_ray(from.hit, w));
  if (!hit) return 0.0;
  MltPath y = x;
  PathVertex& v = y.v[x.segments() - 2];
  v = PathVertex{};
  v.kind = VertexKind::kSurface;
  v.hit = *hit;
  v.bsdf = ctx.world->surface(hit->shape_id).bsdf;
  v.light = ctx.world->surface(hit->shape_id).emitter;
  const double area = solid_angle_to_area(1.0, from.hit.p, v.hit.p, v.hit.ng);
  return area > 0.0 ? mut->split_density(y, way_of(x).l, 1, s) / area : 0.0;
}

std::optional<Vec2> LensOffsetProjection::sample(Uniforms& u) const {
  const auto y = lens->propose(x, u);
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
  return jac > 0.0 ? lens->density(x, *y) / jac * r * r : 0.0;
}

Vec2 LensOffsetProjection::chart_lo() const { return {0.0, std::log(lens->r1()) - 0.2}; }
Vec2 LensOffsetProjection::chart_hi() const { return {2 * kPi, std::log(lens->r2()) + 0.2}; }

std::optional<Vec2> CausticAngleProjection::sample(Uniforms& u) const {
  const auto y = caustic->propose(x, u);
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
  return g > 0.0 ? caustic->density(x, *y) / g * std::sin(theta) * theta : 0.0;
}

Vec2 CausticAngleProjection::chart_lo() const { return {0.0, std::log(caustic->theta1()) - 0.2}; }
Vec2 CausticAngleProjection::chart_hi() const { return {2 * kPi, std::log(caustic->theta2()) + 0.2}; }

MltPath path_with_segments(const PathContext& ctx, int k, int max_depth, uint64_t seed) {
  for (uint64_t i = 0;; ++i) {
    Rng r = Rng::for_sample(seed, 0x7061746873ULL, i);
    RngUniforms u(r);
    auto x = sample_bdpt_path(ctx, u, max_depth, k);
    if (x && x->segments() == k) return *x;
  }
}

}  // namespace tb::path_space
