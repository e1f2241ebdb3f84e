#include "lib/geometry/scene.h"

#include <cstring>
#include <mutex>
#include <stdexcept>
#include <string>

#include <embree3/rtcore.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace tb {

struct Scene::Entry {
  std::variant<TriangleMesh, ShapeInstance> shape;
  uint32_t id = 0;
};

namespace {

RTCDevice device() {
  // One device for the process (a device owns Embree's thread pool); never released.
  static RTCDevice dev = [] {
    RTCDevice d = rtcNewDevice(nullptr);
    if (!d) throw std::runtime_error("Embree: rtcNewDevice failed (error " + std::to_string(rtcGetDeviceError(nullptr)) + ")");
    return d;
  }();
  return dev;
}

// The intersect context extended with the double ray and the nearest analytic hit so far
// (Embree 3 "ray extensions" through the context: the callbacks receive this pointer).
struct QueryContext {
  RTCIntersectContext base;
  const Ray* ray;
  // Nearest accepted analytic hit; valid when the final geomID is an analytic shape.
  std::optional<Hit> analytic_hit;
};

float to_float_tfar(double t) {
  if (!(t < static_cast<double>(std::numeric_limits<float>::max()))) return std::numeric_limits<float>::infinity();
  return static_cast<float>(t);
}

// Largest float <= t: Embree's tfar after an analytic hit at t, so that a triangle is accepted
// only if it lies strictly in front of that hit.
float float_below(double t) {
  float f = static_cast<float>(t);
  if (static_cast<double>(f) > t) f = std::nextafter(f, -INFINITY);
  return f;
}

void bounds_fn(const RTCBoundsFunctionArguments* args) {
  const auto* e = static_cast<const Scene::Entry*>(args->geometryUserPtr);
  const Bounds3 b = std::get<ShapeInstance>(e->shape).world_bounds();
  // Round outward to float.
  args->bounds_o->lower_x = std::nextafter(static_cast<float>(b.lo.x), -INFINITY);
  args->bounds_o->lower_y = std::nextafter(static_cast<float>(b.lo.y), -INFINITY);
  args->bounds_o->lower_z = std::nextafter(static_cast<float>(b.lo.z), -INFINITY);
  args->bounds_o->upper_x = std::nextafter(static_cast<float>(b.hi.x), INFINITY);
  args->bounds_o->upper_y = std::nextafter(static_cast<float>(b.hi.y), INFINITY);
  args->bounds_o->upper_z = std::nextafter(static_cast<float>(b.hi.z), INFINITY);
}

void intersect_fn(const RTCIntersectFunctionNArguments* args) {
  auto* ctx = reinterpret_cast<QueryContext*>(args->context);
  const auto* e = static_cast<const Scene::Entry*>(args->geometryUserPtr);
  const ShapeInstance& s = std::get<ShapeInstance>(e->shape);
  RTCRayN* ray = RTCRayHitN_RayN(args->rayhit, args->N);
  RTCHitN* hit = RTCRayHitN_HitN(args->rayhit, args->N);
  for (unsigned i = 0; i < args->N; ++i) {
    if (!args->valid[i]) continue;
    const double tnear = std::max(0.0, ctx->ray->t_min);
    double tfar = RTCRayN_tfar(ray, args->N, i);
    // The float tfar may have rounded below a previous analytic hit; compare in double.
    if (ctx->analytic_hit) tfar = std::min(ctx->analytic_hit->t, static_cast<double>(std::nextafter(
                                                                       RTCRayN_tfar(ray, args->N, i), INFINITY)));
    std::optional<Hit> h = s.intersect(*ctx->ray, tnear, tfar);
    if (!h) continue;
    h->shape_id = e->id;
    RTCRayN_tfar(ray, args->N, i) = float_below(h->t);
    RTCHitN_Ng_x(hit, args->N, i) = static_cast<float>(h->ng.x);
    RTCHitN_Ng_y(hit, args->N, i) = static_cast<float>(h->ng.y);
    RTCHitN_Ng_z(hit, args->N, i) = static_cast<float>(h->ng.z);
    RTCHitN_u(hit, args->N, i) = static_cast<float>(h->uv.x);
    RTCHitN_v(hit, args->N, i) = static_cast<float>(h->uv.y);
    RTCHitN_primID(hit, args->N, i) = args->primID;
    RTCHitN_geomID(hit, args->N, i) = args->geomID;
    RTCHitN_instID(hit, args->N, i, 0) = args->context->instID[0];
    ctx->analytic_hit = std::move(h);
  }
}

void occluded_fn(const RTCOccludedFunctionNArguments* args) {
  auto* ctx = reinterpret_cast<QueryContext*>(args->context);
  const auto* e = static_cast<const Scene::Entry*>(args->geometryUserPtr);
  const ShapeInstance& s = std::get<ShapeInstance>(e->shape);
  for (unsigned i = 0; i < args->N; ++i) {
    if (!args->valid[i]) continue;
    const double tnear = std::max(0.0, ctx->ray->t_min), tfar = RTCRayN_tfar(args->ray, args->N, i);
    if (s.intersects(*ctx->ray, tnear, tfar)) RTCRayN_tfar(args->ray, args->N, i) = -INFINITY;
  }
}

// static_cast<float>(x) read with a scalar 8-byte load. Rays are mostly built just before they
// are traced, component by component (8-byte stores); GCC's vectorised conversion of (x, y) loads
// 16 bytes spanning two such stores, which the store buffer cannot forward: perf put a third of
// Scene::intersect_point's samples on that stall. Same rounding (to nearest) either way.
inline float to_float_scalar_load(const double& x) {
#if defined(__SSE2__)
  return _mm_cvtss_f32(_mm_cvtsd_ss(_mm_setzero_ps(), _mm_load_sd(&x)));
#else
  return static_cast<float>(x);
#endif
}

void fill_ray(const Ray& r, double tmax, RTCRay* out) {
  tmax = std::min(tmax, r.t_max);
  out->org_x = to_float_scalar_load(r.o.x);
  out->org_y = to_float_scalar_load(r.o.y);
  out->org_z = to_float_scalar_load(r.o.z);
  out->dir_x = to_float_scalar_load(r.d.x);
  out->dir_y = to_float_scalar_load(r.d.y);
  out->dir_z = to_float_scalar_load(r.d.z);
  out->tnear = static_cast<float>(std::max(0.0, r.t_min));
  out->tfar = to_float_tfar(tmax);
  out->time = 0.0f;
  out->mask = 0xffffffffu;
  out->id = 0;
  out->flags = 0;
}

}  // namespace

Scene::Scene() {
  RTCScene s = rtcNewScene(device());
  rtcSetSceneFlags(s, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(s, RTC_BUILD_QUALITY_HIGH);
  scene_ = s;
}

Scene::~Scene() { rtcReleaseScene(static_cast<RTCScene>(scene_)); }

uint32_t Scene::add(TriangleMesh mesh) {
  if (committed_) throw std::logic_error("Scene::add after commit");
  auto e = std::make_unique<Entry>(Entry{std::move(mesh), static_cast<uint32_t>(entries_.size())});
  const TriangleMesh& m = std::get<TriangleMesh>(e->shape);
  RTCGeometry g = rtcNewGeometry(device(), RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* v = static_cast<float*>(
      rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), m.positions().size()));
  for (size_t i = 0; i < m.positions().size(); ++i)
    for (int k = 0; k < 3; ++k) v[3 * i + static_cast<size_t>(k)] = static_cast<float>(m.positions()[i][k]);
  auto* idx = static_cast<unsigned*>(
      rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), m.triangle_count()));
  for (size_t i = 0; i < m.triangle_count(); ++i)
    for (int k = 0; k < 3; ++k) idx[3 * i + static_cast<size_t>(k)] = m.triangles()[i][k];
  rtcCommitGeometry(g);
  rtcAttachGeometryByID(static_cast<RTCScene>(scene_), g, e->id);
  rtcReleaseGeometry(g);
  entries_.push_back(std::move(e));
  return entries_.back()->id;
}

uint32_t Scene::add(ShapeInstance shape) {
  if (committed_) throw std::logic_error("Scene::add after commit");
  auto e = std::make_unique<Entry>(Entry{std::move(shape), static_cast<uint32_t>(entries_.size())});
  RTCGeometry g = rtcNewGeometry(device(), RTC_GEOMETRY_TYPE_USER);
  rtcSetGeometryUserPrimitiveCount(g, 1);
  rtcSetGeometryUserData(g, e.get());
  rtcSetGeometryBoundsFunction(g, bounds_fn, nullptr);
  rtcSetGeometryIntersectFunction(g, intersect_fn);
  rtcSetGeometryOccludedFunction(g, occluded_fn);
  rtcCommitGeometry(g);
  rtcAttachGeometryByID(static_cast<RTCScene>(scene_), g, e->id);
  rtcReleaseGeometry(g);
  entries_.push_back(std::move(e));
  return entries_.back()->id;
}

void Scene::commit() {
  rtcCommitScene(static_cast<RTCScene>(scene_));
  const RTCError err = rtcGetDeviceError(device());
  if (err != RTC_ERROR_NONE) throw std::runtime_error("Embree: scene commit failed (error " + std::to_string(err) + ")");
  committed_ = true;
}

namespace {

// rtcIntersect1 with the double ray in the extended context; rh->hit.geomID names the nearest shape.
void trace(void* scene, const Ray& ray, double tmax, QueryContext* ctx, RTCRayHit* rh) {
  rtcInitIntersectContext(&ctx->base);
  ctx->ray = &ray;
  fill_ray(ray, tmax, &rh->ray);
  rh->hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh->hit.primID = RTC_INVALID_GEOMETRY_ID;
  rh->hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(static_cast<RTCScene>(scene), &ctx->base, rh);
}

}  // namespace

namespace {

// Barycentrics (b1, b2) moved into the triangle: negative ones to 0, a sum above 1 scaled to 1.
Vec2 clamp_to_triangle(Vec2 uv) {
  uv = glm::max(uv, Vec2(0.0));
  const double s = uv.x + uv.y;
  return s > 1 ? uv / s : uv;
}

// Traces the ray and returns the entry of the nearest shape, nullptr for none; Embree's hit is in
// *rh. For an analytic shape, ctx->analytic_hit holds its full double hit, computed by its Embree
// callback (the last one accepted has the smallest t among analytic shapes, and it is the final
// one since geomID names an analytic shape), checked to lie before min(tmax, ray.t_max).
const Scene::Entry* trace_nearest(void* scene, const std::vector<std::unique_ptr<Scene::Entry>>& entries,
                                  const Ray& ray, double tmax, QueryContext* ctx, RTCRayHit* rh) {
  trace(scene, ray, tmax, ctx, rh);
  if (rh->hit.geomID == RTC_INVALID_GEOMETRY_ID) return nullptr;
  const Scene::Entry* e = entries[rh->hit.geomID].get();
  if (std::holds_alternative<TriangleMesh>(e->shape)) return e;
  if (!ctx->analytic_hit || ctx->analytic_hit->shape_id != e->id) throw std::logic_error("Scene: lost analytic hit");
  if (!(ctx->analytic_hit->t < std::min(tmax, ray.t_max))) return nullptr;  // float tfar rounded up past tmax
  return e;
}

}  // namespace

std::optional<Hit> Scene::intersect(const Ray& ray, double tmax) const {
  std::optional<Hit> h(std::in_place);  // filled in place by the query below: no copy of the Hit
  if (!intersect(ray, &*h, tmax)) return std::nullopt;
  return h;
}

bool Scene::intersect(const Ray& ray, Hit* out, double tmax) const {
  if (!committed_) throw std::logic_error("Scene::intersect before commit");
  QueryContext ctx;
  RTCRayHit rh;
  const Entry* e = trace_nearest(scene_, entries_, ray, tmax, &ctx, &rh);
  if (!e) return false;
  if (const auto* m = std::get_if<TriangleMesh>(&e->shape)) {
    m->refine_hit(rh.hit.primID, ray, rh.ray.tfar, Vec2(rh.hit.u, rh.hit.v), out);
    out->shape_id = e->id;
  } else {
    *out = *ctx.analytic_hit;
  }
  return true;
}

bool Scene::intersect_point(const Ray& ray, SurfacePoint* out, double tmax) const {
  if (!committed_) throw std::logic_error("Scene::intersect before commit");
  QueryContext ctx;
  RTCRayHit rh;
  const Entry* e = trace_nearest(scene_, entries_, ray, tmax, &ctx, &rh);
  if (!e) return false;
  if (const auto* m = std::get_if<TriangleMesh>(&e->shape)) {
    // Embree's own barycentrics, not re-intersected in double: the point b0 p0 + b1 p1 + b2 p2
    // is evaluated in double, so it lies on the triangle's plane to double precision and the
    // spawn offset (point_into's float-level bound) is as valid as for an area-sampled point; it
    // sits within float rounding (~1e-7 of the size) of the double ray's exact hit, which moves
    // no estimate measurably. Clamped into the triangle like refine_hit's barycentrics.
    m->point_into(rh.hit.primID, clamp_to_triangle(Vec2(rh.hit.u, rh.hit.v)), rh.ray.tfar, out);
    out->shape_id = e->id;
  } else {
    *out = *ctx.analytic_hit;
  }
  return true;
}

bool Scene::occluded(const Ray& ray, double tmax) const {
  if (!committed_) throw std::logic_error("Scene::occluded before commit");
  QueryContext ctx;
  rtcInitIntersectContext(&ctx.base);
  ctx.ray = &ray;
  RTCRay r;
  fill_ray(ray, tmax, &r);
  rtcOccluded1(static_cast<RTCScene>(scene_), &ctx.base, &r);
  return r.tfar < 0;
}

bool Scene::is_mesh(uint32_t id) const { return std::holds_alternative<TriangleMesh>(entries_.at(id)->shape); }
const TriangleMesh& Scene::mesh(uint32_t id) const { return std::get<TriangleMesh>(entries_.at(id)->shape); }
const ShapeInstance& Scene::analytic(uint32_t id) const { return std::get<ShapeInstance>(entries_.at(id)->shape); }

Hit Scene::surface_at(uint32_t shape_id, uint32_t prim_id, const Vec2& uv) const {
  const Entry& e = *entries_.at(shape_id);
  Hit h = is_mesh(shape_id) ? mesh(shape_id).surface_at(prim_id, uv) : analytic(shape_id).surface_at(uv);
  h.shape_id = e.id;
  return h;
}

AreaSample Scene::sample_area(uint32_t shape_id, const Vec2& u) const {
  AreaSample s = is_mesh(shape_id) ? mesh(shape_id).sample_area(u) : analytic(shape_id).sample_area(u);
  s.hit.shape_id = shape_id;
  return s;
}

double Scene::sample_area_into(uint32_t shape_id, const Vec2& u, Hit* h) const {
  double pdf = 0.0;
  if (is_mesh(shape_id)) {
    pdf = mesh(shape_id).sample_area(u, h);
  } else {
    const AreaSample s = analytic(shape_id).sample_area(u);
    *h = s.hit;
    pdf = s.pdf_area;
  }
  h->shape_id = shape_id;
  return pdf;
}

SurfacePoint Scene::sample_point(uint32_t shape_id, const Vec2& u, double* pdf_area) const {
  const Entry& e = *entries_.at(shape_id);
  if (const auto* m = std::get_if<TriangleMesh>(&e.shape)) {
    SurfacePoint p = m->sample_point(u, pdf_area);
    p.shape_id = shape_id;
    return p;
  }
  const AreaSample s = std::get<ShapeInstance>(e.shape).sample_area(u);
  *pdf_area = s.pdf_area;
  SurfacePoint p = s.hit;
  p.shape_id = shape_id;
  return p;
}

double Scene::pdf_area(const SurfacePoint& h) const {
  return is_mesh(h.shape_id) ? mesh(h.shape_id).pdf_area() : analytic(h.shape_id).pdf_area(h.uv);
}

}  // namespace tb
