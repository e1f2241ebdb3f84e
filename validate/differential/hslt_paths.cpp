#include "validate/differential/hslt_paths.h"

#include <cmath>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>

#include "lib/core/hash.h"
#include "lib/core/rng.h"
#include "lib/material/bsdf.h"
#include "validate/render/render_compare.h"

namespace tb {
namespace {

constexpr int kResolution = 64;

bool frame_ok(const HsltVertex& v) {
  return v.area_element() > 1e-4 && glm::length(v.dpdu) > 1e-3 && std::abs(glm::dot(v.n, v.frame_ref)) < 0.99;
}

// A physical configuration at interior vertex i, away from the fold of the constraint: a
// reflection has both directions on one side of the surface, a refraction one on each side,
// neither grazing, and h is not near the tangent plane (where its orientation to the side of n
// flips).
bool interior_vertex_ok(const HsltPath& path, int i) {
  const HsltVertex& x = path.vertices[static_cast<size_t>(i)];
  const HsltHalfVector hv = hslt_half_vector(path, i);
  const double cp = glm::dot(hv.w_prev, x.ng), cn = glm::dot(hv.w_next, x.ng);
  const bool reflection = x.eta_prev == x.eta_next;
  if (std::abs(cp) < 0.05 || std::abs(cn) < 0.05 || (cp * cn > 0) != reflection) return false;
  return hv.H_len >= 0.05 && std::abs(glm::dot(hv.h, x.n)) >= 0.1;
}

// |cos| >= 0.05 of the segment at a surface endpoint (no grazing end segments).
bool endpoint_ok(const HsltVertex& end, const HsltVertex& neighbour) {
  return !end.on_surface || std::abs(glm::dot(glm::normalize(neighbour.p - end.p), end.ng)) >= 0.05;
}

}  // namespace

std::optional<HsltPath> trace_hslt_specular_path(const World& world, uint64_t seed, uint64_t key, int64_t index,
                                                 int max_segments) {
  Rng rng = Rng::for_sample(seed, key, static_cast<uint64_t>(index));
  HsltPath path;
  Ray ray;
  if (index % 2 == 0) {  // from the camera through a uniform raster position
    const Vec2 raster(kResolution * rng.uniform(), kResolution * rng.uniform());
    const CameraRay cr = world.camera().generate_ray(raster, Vec2(0.5));
    path.vertices.push_back(make_point_vertex(cr.ray.o));
    ray = Ray{cr.ray.o, cr.ray.d};
  } else {  // from a point on an area light towards a point on a delta surface
    std::vector<uint32_t> lights, deltas;
    for (uint32_t s = 0; s < world.surface_count(); ++s) {
      const SurfaceInfo& info = world.surface(s);
      if (info.emitter != nullptr) lights.push_back(s);
      if (info.bsdf != nullptr && (info.bsdf->flags() & bsdf_flags::kDelta)) deltas.push_back(s);
    }
    if (lights.empty() || deltas.empty()) return std::nullopt;
    auto pick = [&](const std::vector<uint32_t>& v) {
      return v[std::min(v.size() - 1, static_cast<size_t>(rng.uniform() * static_cast<double>(v.size())))];
    };
    const uint32_t light = pick(lights);
    const Hit l = world.geometry().sample_area(light, rng.uniform2()).hit;
    const uint32_t target = pick(deltas);
    const Vec3 aim = world.geometry().sample_area(target, rng.uniform2()).hit.p;
    const HsltVertex v = make_hslt_vertex(l);
    if (!frame_ok(v)) return std::nullopt;
    path.vertices.push_back(v);
    ray = Ray{l.p, glm::normalize(aim - l.p), 1e-5 * std::max(1.0, glm::length(l.p)), kInfinity};
  }
  double eta_here = 1.0;  // index of the medium the ray travels in (the camera is in air)
  for (int depth = 1; depth <= max_segments; ++depth) {
    const std::optional<Hit> hit = world.geometry().intersect(ray);
    if (!hit) return std::nullopt;
    const Bsdf* bsdf = world.surface(hit->shape_id).bsdf;
    if (bsdf == nullptr) return std::nullopt;  // an emitter
    if (!(bsdf->flags() & bsdf_flags::kDelta)) {
      if (depth < 2) return std::nullopt;  // no specular vertex
      if (glm::length(hit->p - path.vertices.back().p) < 0.01) return std::nullopt;
      path.vertices.push_back(make_hslt_vertex(*hit, eta_here, eta_here));
      // The same physical, non-grazing configurations as the sampled paths.
      for (int i = 1; i < path.segments(); ++i)
        if (!interior_vertex_ok(path, i)) return std::nullopt;
      if (!endpoint_ok(path.vertices.front(), path.vertices[1]) ||
          !endpoint_ok(path.vertices.back(), path.vertices[path.vertices.size() - 2]))
        return std::nullopt;
      return path;
    }
    const Vec3 wo = -ray.d;
    const bool front = glm::dot(wo, hit->n) > 0;
    const Vec3 n = front ? hit->n : -hit->n;  // shading normal on the side of wo
    Vec3 wi = reflect(wo, n);
    double eta_next = eta_here;
    if (bsdf->flags() & bsdf_flags::kTransmission) {
      const double eta_other = front ? bsdf->eta() : 1.0;  // outward normals: front = outside
      const std::optional<Vec3> t = refract(wo, n, eta_other / eta_here);
      if (t && rng.uniform() < 0.5) {
        wi = *t;
        eta_next = eta_other;
      }
    }
    HsltVertex v = make_hslt_vertex(*hit, eta_here, eta_next);
    // Segments shorter than 0.01 (grazing bounces in a corner of the slab) make J entries ~1/length
    // and its finite differences ill-posed at any fixed step; such paths are not built.
    if (!frame_ok(v) || glm::length(v.p - path.vertices.back().p) < 0.01) return std::nullopt;
    path.vertices.push_back(v);
    // From the exact hit point with a small t_min rather than an offset origin (spawn_ray): the
    // next vertex then lies on the line x_i + t wi, so h^perp = 0 holds to rounding; an offset of
    // the float-triangle error bound would tilt the segment by |offset| / distance (~1e-5).
    ray = Ray{hit->p, wi, 1e-5 * std::max(1.0, glm::length(hit->p)), kInfinity};
    eta_here = eta_next;
  }
  return std::nullopt;
}

std::optional<HsltPath> sample_hslt_connected_path(const World& world, HsltVertexMix mix, int segments, uint64_t seed,
                                                   uint64_t key, int64_t index) {
  std::vector<uint32_t> shapes;
  for (uint32_t s = 0; s < world.surface_count(); ++s)
    if (world.surface(s).bsdf != nullptr) shapes.push_back(s);
  Rng rng = Rng::for_sample(seed, key, static_cast<uint64_t>(index));
  HsltPath path;
  // Vertex by vertex; vertex j is redrawn (at most 64 times) until vertex j - 1 is valid.
  for (int j = 0; j <= segments; ++j) {
    bool placed = false;
    for (int attempt = 0; attempt < 64 && !placed; ++attempt) {
      // Consecutive vertices may lie on one shape (a chord through a closed glass object, a
      // reflection inside a concave mirror); the side tests below keep the configuration physical.
      const uint32_t s =
          shapes[std::min(shapes.size() - 1, static_cast<size_t>(rng.uniform() * static_cast<double>(shapes.size())))];
      // Area sampling, kept away from the parameter-domain boundary (poles, seams).
      const Vec2 u(0.05 + 0.9 * rng.uniform(), 0.05 + 0.9 * rng.uniform());
      const Hit h = world.geometry().sample_area(s, u).hit;
      double eta_prev = 1.0, eta_next = 1.0;
      const bool refraction =
          mix == HsltVertexMix::kRefraction || (mix == HsltVertexMix::kMixed && rng.uniform() < 0.5);
      const double eta = rng.uniform() < 0.5 ? 1.5 : 1.33;
      if (refraction) {
        (rng.uniform() < 0.5 ? eta_prev : eta_next) = eta;
      } else if (rng.uniform() < 0.5) {
        eta_prev = eta_next = eta;  // a reflection inside a dense medium
      }
      const HsltVertex v = make_hslt_vertex(h, eta_prev, eta_next);
      if (!frame_ok(v)) continue;
      if (j > 0 && glm::length(v.p - path.vertices.back().p) < 0.05) continue;
      path.vertices.push_back(v);
      if (j >= 2 && !interior_vertex_ok(path, j - 1)) {
        path.vertices.pop_back();
        continue;
      }
      placed = true;
    }
    if (!placed) return std::nullopt;
  }
  return path;
}

std::optional<Vec2> retrace_hslt_specular_endpoint(const World& world, const HsltPath& path, const Vec2& uv1) {
  const Scene& scene = world.geometry();
  const int k = path.segments();
  Vec3 prev = path.vertices[0].p;
  const HsltVertex& v1 = path.vertices[1];
  Hit x = scene.surface_at(v1.shape_id, v1.prim_id, uv1);
  for (int i = 1; i < k; ++i) {
    const HsltVertex& orig = path.vertices[static_cast<size_t>(i)];
    const Vec3 wo = glm::normalize(prev - x.p);
    const bool front = glm::dot(wo, x.n) > 0;
    const Vec3 n = front ? x.n : -x.n;
    Vec3 wi = reflect(wo, n);
    if (orig.eta_prev != orig.eta_next) {
      const std::optional<Vec3> t = refract(wo, n, orig.eta_next / orig.eta_prev);
      if (!t) return std::nullopt;
      wi = *t;
    }
    const std::optional<Hit> next = scene.intersect(Ray{x.p, wi, 1e-5 * std::max(1.0, glm::length(x.p)), kInfinity});
    if (!next || next->shape_id != path.vertices[static_cast<size_t>(i + 1)].shape_id) return std::nullopt;
    prev = x.p;
    x = *next;
  }
  return x.uv;
}

std::vector<int> hslt_free_vertices(const HsltPath& path) {
  std::vector<int> free;
  for (int j = 0; j < static_cast<int>(path.vertices.size()); ++j)
    if (path.vertices[static_cast<size_t>(j)].on_surface) free.push_back(j);
  return free;
}

Eigen::VectorXd hslt_free_coordinates(const HsltPath& path, const std::vector<int>& free) {
  Eigen::VectorXd x(2 * static_cast<Eigen::Index>(free.size()));
  for (size_t j = 0; j < free.size(); ++j) {
    const Vec2 uv = path.vertices[static_cast<size_t>(free[j])].uv;
    x[static_cast<Eigen::Index>(2 * j)] = uv.x;
    x[static_cast<Eigen::Index>(2 * j + 1)] = uv.y;
  }
  return x;
}

HsltPath hslt_path_at(const Scene& scene, const HsltPath& path, const std::vector<int>& free, const Eigen::VectorXd& uv) {
  return hslt_path_at(path, free, uv, [&](const HsltVertex& v, const Vec2& c) {
    return scene.surface_at(v.shape_id, v.prim_id, c);
  });
}

Eigen::MatrixXd hslt_free_columns(const Eigen::MatrixXd& full, const std::vector<int>& free) {
  Eigen::MatrixXd J(full.rows(), 2 * static_cast<Eigen::Index>(free.size()));
  for (size_t j = 0; j < free.size(); ++j) J.middleCols<2>(static_cast<Eigen::Index>(2 * j)) = full.middleCols<2>(2 * free[j]);
  return J;
}

const std::vector<std::string>& hslt_families() {
  static const std::vector<std::string> f{"curved_mirrors", "glass", "mirror_chain", "reflection", "refraction", "mixed"};
  return f;
}

const World& hslt_family_world(const std::string& family) {
  static std::mutex mutex;
  static std::map<std::string, std::unique_ptr<World>> worlds;
  std::string file;
  if (family == "curved_mirrors" || family == "reflection" || family == "mixed") file = "dg-curved-mirrors.json";
  else if (family == "glass" || family == "refraction") file = "dg-glass.json";
  else if (family == "mirror_chain") file = "dg-mirror-chain.json";
  else throw std::invalid_argument("unknown HSLT path family " + family);
  std::lock_guard<std::mutex> lock(mutex);
  auto& w = worlds[file];
  if (!w) w = load_scene_at_resolution(file, kResolution, kResolution);
  return *w;
}

HsltPathSet hslt_path_set(const std::string& family, int count, uint64_t seed) {
  HsltPathSet set;
  set.name = family;
  const World& world = hslt_family_world(family);
  const uint64_t key = hash_string("differential.hslt.paths." + family);
  const bool traced = family == "curved_mirrors" || family == "glass" || family == "mirror_chain";
  const HsltVertexMix mix = family == "reflection"   ? HsltVertexMix::kReflection
                            : family == "refraction" ? HsltVertexMix::kRefraction
                                                     : HsltVertexMix::kMixed;
  const int64_t max_attempts = 2000 * static_cast<int64_t>(count);
  for (int64_t a = 0; a < max_attempts && static_cast<int>(set.paths.size()) < count; ++a) {
    ++set.attempts;
    const int segments = 2 + static_cast<int>(set.paths.size()) % 7;  // k = 2 .. 8 in turn
    std::optional<HsltPath> p = traced ? trace_hslt_specular_path(world, seed, key, a)
                                       : sample_hslt_connected_path(world, mix, segments, seed, key, a);
    if (p) set.paths.push_back(std::move(*p));
  }
  return set;
}

}  // namespace tb

namespace tb {

HsltFdChart hslt_fd_chart(const HsltPath& path, const std::vector<int>& free, double length) {
  HsltFdChart c;
  c.free = free;
  c.length = length;
  c.uv0 = hslt_free_coordinates(path, free);
  c.scale.resize(c.uv0.size());
  for (size_t j = 0; j < free.size(); ++j) {
    const HsltVertex& v = path.vertices[static_cast<size_t>(free[j])];
    c.scale[static_cast<Eigen::Index>(2 * j)] = length / glm::length(v.dpdu);
    c.scale[static_cast<Eigen::Index>(2 * j + 1)] = length / glm::length(v.dpdv);
  }
  return c;
}

}  // namespace tb
