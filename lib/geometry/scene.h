// The ray-tracing scene: triangle meshes as Embree triangle geometry and analytic shapes as
// Embree user geometry, in one RTCScene. Queries take double rays; Embree's float ray is used
// for traversal only. Analytic shapes are intersected with the double ray inside the Embree
// callback; triangle hits are refined in double afterwards. Every returned Hit carries its
// differential geometry recomputed in double from the shape.
//
// Shape ids: the index returned by add(), equal to the Embree geometry id.
#pragma once

#include <memory>
#include <optional>
#include <variant>
#include <vector>

#include "lib/geometry/area_sample.h"
#include "lib/geometry/hit.h"
#include "lib/geometry/ray.h"
#include "lib/geometry/shape_instance.h"
#include "lib/geometry/triangle_mesh.h"

namespace tb {

class Scene {
 public:
  Scene();
  ~Scene();
  Scene(const Scene&) = delete;
  Scene& operator=(const Scene&) = delete;

  uint32_t add(TriangleMesh mesh);
  uint32_t add(ShapeInstance shape);
  // Builds the BVH; required before queries, and after the last add().
  void commit();

  // Nearest hit with ray.t_min < t < min(ray.t_max, tmax) (rtcIntersect1). Thread-safe after
  // commit().
  std::optional<Hit> intersect(const Ray& ray, double tmax = kInfinity) const;
  // The same Hit written into *out (every field; *out is untouched when there is no hit):
  // returns whether there is one. For callers that keep the record in a larger one (BDPT's
  // PathVertex): no optional is built per query and no 224-byte Hit copied out of it.
  bool intersect(const Ray& ray, Hit* out, double tmax = kInfinity) const;
  // The same query without differential geometry, for the path tracer: the SurfacePoint part of
  // the Hit intersect() would return, except that a triangle hit keeps Embree's float
  // barycentrics (clamped into the triangle) instead of re-intersecting the double ray: the point
  // is the same within float rounding, t is Embree's. Analytic shapes: the same record.
  // Returns whether there is a hit, written field by field into *out: the path tracer keeps one
  // record per path (an optional built per query is zero-filled with `rep stosq`, a copied record
  // read back over narrower stores stalls store forwarding; both showed in profiles).
  bool intersect_point(const Ray& ray, SurfacePoint* out, double tmax = kInfinity) const;
  // Any hit with ray.t_min < t < min(ray.t_max, tmax) (rtcOccluded1). Shadow rays from
  // spawn_ray_to carry t_max = 1 - kShadowEpsilon already.
  bool occluded(const Ray& ray, double tmax = kInfinity) const;

  size_t shape_count() const { return entries_.size(); }
  bool is_mesh(uint32_t shape_id) const;
  const TriangleMesh& mesh(uint32_t shape_id) const;
  const ShapeInstance& analytic(uint32_t shape_id) const;

  // Differential geometry of shape `shape_id` at (prim_id, uv): for re-evaluating a vertex
  // moved in its parameterisation (manifold walks, finite differences).
  Hit surface_at(uint32_t shape_id, uint32_t prim_id, const Vec2& uv) const;
  // Area sampling of one shape; density per unit world area.
  AreaSample sample_area(uint32_t shape_id, const Vec2& u) const;
  // The same point written into *h (no copies of the Hit for meshes); returns pdf_area.
  double sample_area_into(uint32_t shape_id, const Vec2& u, Hit* h) const;
  // The same point without differential geometry (next-event estimation); *pdf_area as above.
  SurfacePoint sample_point(uint32_t shape_id, const Vec2& u, double* pdf_area) const;
  double pdf_area(const SurfacePoint& h) const;

  // The committed RTCScene (as void*, so that this header needs no Embree include), for
  // benchmarks that measure raw Embree throughput next to Scene queries. Raw rtcIntersect1 /
  // rtcOccluded1 calls are valid only on scenes of triangle meshes: the callbacks of analytic
  // shapes expect the extended context that intersect() / occluded() pass.
  void* embree_scene() const { return scene_; }

  struct Entry;

 private:
  std::vector<std::unique_ptr<Entry>> entries_;
  void* scene_ = nullptr;  // RTCScene
  bool committed_ = false;
};

}  // namespace tb
