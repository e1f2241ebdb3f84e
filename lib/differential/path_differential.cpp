#include "lib/differential/path_differential.h"

#include <cmath>
#include <stdexcept>

#include "lib/core/frame.h"
#include "lib/core/rng.h"
#include "lib/geometry/spawn.h"
#include "lib/material/half_vector.h"
#include "lib/material/rough_conductor.h"
#include "lib/material/rough_dielectric.h"
#include "lib/path/scattering.h"

namespace tb::differential {

namespace {

Eigen::Vector3d ev(const Vec3& v) { return {v.x, v.y, v.z}; }

Mat32 columns(const Vec3& a, const Vec3& b) {
  Mat32 m;
  m.col(0) = ev(a);
  m.col(1) = ev(b);
  return m;
}

Mat3 columns3(const Vec3& a, const Vec3& b, const Vec3& c) {
  Mat3 m;
  m.col(0) = ev(a);
  m.col(1) = ev(b);
  m.col(2) = ev(c);
  return m;
}

// d(unit(v))/dv * |v| for unit w = v/|v|: the projector I - w w^T.
Mat3 projector(const Vec3& w) { return Mat3::Identity() - ev(w) * ev(w).transpose(); }

// Cosine-weighted hemisphere sample (Shirley & Chiu 1997 concentric map lifted by Malley's
// method, as lib/material/lambert.cpp) and its derivative with respect to u.
Vec3 cosine_hemisphere_derivative(const Vec2& u, Mat32* dw) {
  const double a = 2.0 * u.x - 1.0, b = 2.0 * u.y - 1.0;
  double x, y;
  Eigen::Matrix2d dd;  // d(x, y)/d(a, b)
  if (std::abs(a) > std::abs(b)) {
    const double r = a, phi = kPiOver4 * b / a;
    const double c = std::cos(phi), s = std::sin(phi);
    const double dphi_da = -kPiOver4 * b / (a * a), dphi_db = kPiOver4 / a;
    x = r * c;
    y = r * s;
    dd << c - r * s * dphi_da, -r * s * dphi_db, s + r * c * dphi_da, r * c * dphi_db;
  } else {
    const double r = b, phi = kPiOver4 * a / b;
    const double c = std::cos(phi), s = std::sin(phi);
    const double dphi_da = kPiOver4 / b, dphi_db = -kPiOver4 * a / (b * b);
    x = r * s;
    y = r * c;
    dd << r * c * dphi_da, s + r * c * dphi_db, -r * s * dphi_da, c - r * s * dphi_db;
  }
  const double z = std::sqrt(std::max(0.0, 1.0 - x * x - y * y));
  dd *= 2.0;  // d(a, b)/du = 2 I
  dw->row(0) = dd.row(0);
  dw->row(1) = dd.row(1);
  dw->row(2) = -(x * dd.row(0) + y * dd.row(1)) / z;
  return {x, y, z};
}

// Microfacet normal sampled from D cos (Walter et al. 2007, Eq. 28-29 Beckmann, 35-36 GGX, as
// MicrofacetDistribution::sample_m) and its derivative with respect to u.
Vec3 microfacet_normal_derivative(const MicrofacetDistribution& dist, const Vec2& u, Mat32* dm) {
  const double a2 = dist.alpha() * dist.alpha();
  const double om = 1.0 - u.x;
  const bool beckmann = dist.type() == MicrofacetType::kBeckmann;
  const double tan2 = beckmann ? -a2 * std::log(om) : a2 * u.x / om;
  const double dtan2 = beckmann ? a2 / om : a2 / (om * om);
  const double cos_t = 1.0 / std::sqrt(1.0 + tan2);
  const double sin_t = std::sqrt(std::max(0.0, 1.0 - cos_t * cos_t));
  const double dcos = -0.5 * cos_t * cos_t * cos_t * dtan2;  // d/du of (1 + tan2)^-1/2
  const double dsin = -cos_t * dcos / sin_t;
  const double phi = 2.0 * kPi * u.y;
  const double c = std::cos(phi), s = std::sin(phi);
  dm->col(0) = Eigen::Vector3d(dsin * c, dsin * s, dcos);
  dm->col(1) = Eigen::Vector3d(-sin_t * s, sin_t * c, 0.0) * (2.0 * kPi);
  return {sin_t * c, sin_t * s, cos_t};
}

}  // namespace

namespace {
constexpr double kMinSegment = 1e-4;  // scene units
}  // namespace

double lobe_uniform(bool transmission) { return transmission ? 1.0 - 0x1p-53 : 0.0; }

std::optional<Hit> next_vertex(const Scene& scene, const Ray& ray, const Vec3& origin, bool offset) {
  std::optional<Hit> hit = scene.intersect(ray);
  if (!hit) return std::nullopt;
  // The vertex on the un-offset ray: one step to the tangent plane at the hit removes the
  // spawn offset along ng (at most p_error, position-dependent only through rounding bounds)
  // and, on meshes, the clamping of barycentrics into the triangle Embree's float test chose.
  // Analytic shapes are re-intersected along the un-offset ray, so that the normal and its
  // derivatives belong to the moved point too (the offset hit lies up to offset / cos away).
  const double t_plane = glm::dot(hit->p - origin, hit->ng) / glm::dot(ray.d, hit->ng);
  if (offset && !scene.is_mesh(hit->shape_id)) {
    const uint32_t id = hit->shape_id;
    const auto exact = scene.analytic(id).intersect(Ray{origin, ray.d}, 0.5 * t_plane, 2.0 * t_plane);
    if (!exact) return std::nullopt;
    hit = *exact;
    hit->shape_id = id;
  } else {
    hit->p = origin + t_plane * ray.d;
  }
  return hit;
}

std::optional<ForwardPath> trace_forward(const World& world, const Vec2& pixel, const Eigen::VectorXd& U, int k,
                                         const std::vector<double>& lobe) {
  auto path = trace_forward_prefix(world, pixel, U, k, lobe);
  if (!path || static_cast<int>(path->vertices.size()) != k) return std::nullopt;
  return path;
}

std::optional<ForwardPath> trace_forward_prefix(const World& world, const Vec2& pixel, const Eigen::VectorXd& U, int k,
                                                const std::vector<double>& lobe) {
  const Camera& cam = world.camera();
  if (cam.name() != "pinhole") throw std::invalid_argument("path differentials: only the pinhole camera");
  if (U.size() != 2 * k || static_cast<int>(lobe.size()) < k - 1)
    throw std::invalid_argument("trace_forward: U needs 2k entries and lobe k-1");
  const Vec2 raster = pixel + Vec2(U[0], U[1]);
  const CameraPrimaryRay cr = cam.generate_primary_ray(raster, Vec2(0.5));
  if (!(cr.weight > 0)) return std::nullopt;
  ForwardPath path;
  path.raster = raster;
  path.eye = cr.ray.o;
  path.camera_dir = cr.ray.d;
  Ray ray = cr.ray;
  const Scene& scene = world.geometry();
  for (int j = 1; j <= k; ++j) {
    const std::optional<Hit> hit = next_vertex(scene, ray, j == 1 ? path.eye : path.vertices.back().p, j > 1);
    if (!hit) break;
    path.vertices.push_back(*hit);
    if (j == k) break;
    const SurfaceInfo& surf = world.surface(hit->shape_id);
    if (!surf.bsdf) break;
    const SurfaceScatter scatter(path.vertices.back(), *surf.bsdf);
    const auto bs = scatter.sample(-ray.d, lobe[j - 1], Vec2(U[2 * j], U[2 * j + 1]), TransportMode::kRadiance);
    if (!bs || is_black(bs->weight)) break;
    path.wi.push_back(bs->wi);
    path.flags.push_back(bs->flags);
    path.pdf.push_back(bs->pdf);
    path.weight.push_back(bs->weight);
    ray = spawn_ray(path.vertices.back(), bs->wi);
  }
  return path;
}

std::optional<SampledPath> sample_path(const World& world, int k, uint64_t seed, uint64_t key, uint64_t index,
                                       double margin, int attempts) {
  Rng rng = Rng::for_sample(seed, key, index);
  const Camera& cam = world.camera();
  for (int a = 0; a < attempts; ++a) {
    SampledPath s;
    s.pixel = Vec2(std::floor(rng.uniform() * cam.width()), std::floor(rng.uniform() * cam.height()));
    s.U.resize(2 * k);
    for (int i = 0; i < 2 * k; ++i) s.U[i] = margin + (1.0 - 2.0 * margin) * rng.uniform();
    for (int j = 0; j < k - 1; ++j) s.lobe.push_back(rng.uniform());
    const auto drawn = trace_forward(world, s.pixel, s.U, k, s.lobe);
    if (!drawn) continue;
    for (int j = 0; j < k - 1; ++j) s.lobe[j] = lobe_uniform((drawn->flags[j] & bsdf_flags::kTransmission) != 0);
    auto held = trace_forward(world, s.pixel, s.U, k, s.lobe);
    if (!held || held->flags != drawn->flags || vertex_vector(*held) != vertex_vector(*drawn)) continue;
    // Degenerate paths (two vertices within 1e-4, e.g. a grazing ray re-hitting its own surface):
    // the direction derivatives divide by the segment length.
    bool degenerate = glm::length(held->vertices[0].p - held->eye) < kMinSegment;
    for (int j = 1; j < k; ++j)
      degenerate = degenerate || glm::length(held->vertices[j].p - held->vertices[j - 1].p) < kMinSegment;
    if (degenerate) continue;
    s.path = std::move(*held);
    return s;
  }
  return std::nullopt;
}

Eigen::VectorXd vertex_vector(const ForwardPath& path) {
  Eigen::VectorXd x(3 * static_cast<Eigen::Index>(path.vertices.size()));
  for (size_t j = 0; j < path.vertices.size(); ++j) x.segment<3>(3 * static_cast<Eigen::Index>(j)) = ev(path.vertices[j].p);
  return x;
}

VertexGeometry vertex_geometry(const Hit& hit) {
  VertexGeometry g;
  g.p = hit.p;
  g.ng = hit.ng;
  Vec3 s, t;
  coordinate_system(hit.ng, &s, &t);
  g.tangent = columns(s, t);
  // Curvature: dn = [dn/du dn/dv] (du, dv) with [dp/du dp/dv] (du, dv) = dx (least squares; exact
  // for tangent dx), i.e. the Weingarten map of the shading normal applied to dx.
  const Mat32 M = columns(hit.dpdu, hit.dpdv);
  const Mat32 N = columns(hit.dndu, hit.dndv);
  g.dn_dx = N * (M.transpose() * M).inverse() * M.transpose();
  return g;
}

void frame_derivative(const Vec3& n, Mat3* ds, Mat3* dt) {
  // coordinate_system: sign = copysign(1, n.z), a = -1/(sign + n.z), b = n.x n.y a,
  // s = (1 + sign n.x^2 a, sign b, -sign n.x), t = (b, sign + n.y^2 a, -n.y); da/dn.z = a^2.
  const double sg = std::copysign(1.0, n.z);
  const double a = -1.0 / (sg + n.z), a2 = a * a;
  const double x = n.x, y = n.y;
  *ds << 2 * sg * x * a, 0.0, sg * x * x * a2,  //
      sg * y * a, sg * x * a, sg * x * y * a2,  //
      -sg, 0.0, 0.0;
  *dt << y * a, x * a, x * y * a2,  //
      0.0, 2 * y * a, y * y * a2,   //
      0.0, -1.0, 0.0;
}

void reflect_derivative(const Vec3& w, const Vec3& m, Mat3* d_w, Mat3* d_m) {
  const double c = glm::dot(w, m);
  *d_w = -Mat3::Identity() + 2.0 * ev(m) * ev(m).transpose();
  *d_m = 2.0 * (ev(m) * ev(w).transpose() + c * Mat3::Identity());
}

void refract_derivative(const Vec3& w, const Vec3& m, double eta, Mat3* d_w, Mat3* d_m) {
  // wi = -w/eta + (c/eta - ct) m, c = w.m, ct = sqrt(1 - (1 - c^2)/eta^2), dct/dc = c/(eta^2 ct).
  const double c = glm::dot(w, m);
  const double ct = std::sqrt(std::max(0.0, 1.0 - (1.0 - c * c) / (eta * eta)));
  const double kappa = 1.0 / eta - c / (eta * eta * ct);
  *d_w = -Mat3::Identity() / eta + kappa * ev(m) * ev(m).transpose();
  *d_m = kappa * ev(m) * ev(w).transpose() + (c / eta - ct) * Mat3::Identity();
}

SamplingDerivative sampling_derivative(const Bsdf& bsdf, const Hit& hit, const Vec3& wo, const Vec2& u,
                                       uint32_t flags) {
  // SurfaceScatter::frame_for: BSDFs without transmission shade on wo's side of ng.
  const bool transmissive = (bsdf.flags() & bsdf_flags::kTransmission) != 0;
  const double sn = (!transmissive && glm::dot(wo, hit.ng) < 0) ? -1.0 : 1.0;
  const Vec3 nf = sn * hit.n;
  const Frame F = Frame::from_z(nf);
  Mat3 dS, dT;
  frame_derivative(nf, &dS, &dT);
  const Mat3 basis = columns3(F.s, F.t, F.n);
  const double s = glm::dot(wo, nf) > 0 ? 1.0 : -1.0;  // the BSDFs' own side flip (wo_local.z < 0)
  SamplingDerivative out;
  const std::string_view name = bsdf.name();
  if (name == "lambert") {
    Mat32 dl;
    const Vec3 l = cosine_hemisphere_derivative(u, &dl);
    const Vec3 wl(l.x, l.y, s * l.z);
    out.kind = LobeKind::kDiffuse;
    out.wi = F.to_world(wl);
    out.d_n = sn * (wl.x * dS + wl.y * dT + wl.z * Mat3::Identity());
    dl.row(2) *= s;
    out.d_u = basis * dl;
    return out;
  }
  Vec3 ml(0, 0, 1);
  Mat32 dml = Mat32::Zero();
  if (const auto* rc = dynamic_cast<const RoughConductorBsdf*>(&bsdf)) {
    if (rc->visible_normals()) throw std::invalid_argument("path differentials: no visible-normal sampling");
    ml = microfacet_normal_derivative(rc->distribution(), u, &dml);
  } else if (const auto* rd = dynamic_cast<const RoughDielectricBsdf*>(&bsdf)) {
    if (rd->visible_normals()) throw std::invalid_argument("path differentials: no visible-normal sampling");
    ml = microfacet_normal_derivative(rd->distribution(), u, &dml);
  } else if (name != "smooth_conductor" && name != "smooth_dielectric") {
    throw std::invalid_argument("path differentials: no sampling derivative for BSDF " + std::string(name));
  }
  // Facet normal on wo's side: m = s frame(nf) ml.
  out.m = s * F.to_world(ml);
  const Mat3 dm_dnf = s * (ml.x * dS + ml.y * dT + ml.z * Mat3::Identity());
  const Mat32 dm_du = s * basis * dml;
  Mat3 r_w, r_m;
  if (flags & bsdf_flags::kTransmission) {
    out.kind = LobeKind::kRefract;
    out.eta = s > 0 ? bsdf.eta() : 1.0 / bsdf.eta();  // eta_other_side / eta_wo_side
    refract_derivative(wo, out.m, out.eta, &r_w, &r_m);
    out.wi = refract(wo, out.m, out.eta).value_or(Vec3(0.0));
  } else {
    out.kind = LobeKind::kReflect;
    reflect_derivative(wo, out.m, &r_w, &r_m);
    out.wi = reflect(wo, out.m);
  }
  out.dm_dn = sn * dm_dnf;
  out.dm_du = dm_du;
  out.d_wo = r_w;
  out.d_n = r_m * out.dm_dn;
  out.d_u = r_m * dm_du;
  return out;
}

SamplingDerivative halfvector_derivative(const Bsdf& bsdf, const Hit& hit, const Vec3& wo, const Vec3& wi,
                                         uint32_t flags, double pdf) {
  const bool transmissive = (bsdf.flags() & bsdf_flags::kTransmission) != 0;
  const double sn = (!transmissive && glm::dot(wo, hit.ng) < 0) ? -1.0 : 1.0;
  const Vec3 nf = sn * hit.n;
  const Frame F = Frame::from_z(nf);
  Mat3 dS, dT;
  frame_derivative(nf, &dS, &dT);
  SamplingDerivative out;
  out.wi = wi;
  Mat3 r_w, r_m;
  if (flags & bsdf_flags::kTransmission) {
    out.kind = LobeKind::kRefract;
    out.eta = glm::dot(wo, nf) > 0 ? bsdf.eta() : 1.0 / bsdf.eta();
    out.m = generalized_half_vector(wi, wo, out.eta, 1.0, wo);  // on wo's side
    refract_derivative(wo, out.m, out.eta, &r_w, &r_m);
  } else {
    out.kind = LobeKind::kReflect;
    out.m = glm::normalize(wo + wi);
    reflect_derivative(wo, out.m, &r_w, &r_m);
  }
  const Vec3 ml = F.to_local(out.m);  // held fixed in the frame
  out.dm_dn = sn * (ml.x * dS + ml.y * dT + ml.z * Mat3::Identity());
  out.d_wo = r_w;
  out.d_n = r_m * out.dm_dn;
  if (!(flags & bsdf_flags::kDelta)) {
    Vec3 b1, b2;
    coordinate_system(out.m, &b1, &b2);
    const double scale = std::sqrt(half_vector_jacobian(wo, wi, 1.0, out.eta) / pdf);
    out.dm_du = columns(b1, b2) * scale;
    out.d_u = r_m * out.dm_du;
  }
  return out;
}

Mat32 camera_direction_derivative(const Camera& camera, const Vec2& raster) {
  // PinholeCamera::direction_through: d = unit(c), c = right px + up py + forward, with
  // (px, py) = plane_from_raster(raster) affine in the raster position.
  const PerspectiveProjection& pr = camera.projection();
  const Vec2 p = pr.plane_from_raster(raster);
  const Vec3 c = pr.to_world_dir(Vec3(p.x, p.y, 1.0));
  const double len = glm::length(c);
  const Mat32 dc = columns(pr.right() * (2.0 * pr.tan_half_x() / pr.width()),
                           -pr.up() * (2.0 * pr.tan_half_y() / pr.height()));
  return projector(c / len) * dc / len;
}

Mat3 transfer_matrix(const Vec3& wi, const Vec3& n_next) {
  return Mat3::Identity() - ev(wi) * ev(n_next).transpose() / glm::dot(n_next, wi);
}

StepBlocks step_blocks(const ForwardPath& path, const PathDifferential& d, int j) {
  const Hit& x = path.vertices[j - 1];
  const Hit& next = path.vertices[j];
  const Vec3 prev = j == 1 ? path.eye : path.vertices[j - 2].p;
  const Vec3 e = prev - x.p;
  const double len = glm::length(e);
  const Mat3 dwo = projector(e / len) / len;  // dwo = dwo (dx_{j-1} - dx_j)
  const SamplingDerivative& s = d.sampling[j - 1];
  const Vec3& wi = path.wi[j - 1];
  const double t = glm::length(next.p - x.p);
  const Mat23 tq = d.geometry[j].tangent.transpose() * transfer_matrix(wi, next.ng);
  const Mat32& T = d.geometry[j - 1].tangent;
  StepBlocks b;
  if (j > 1) b.g_prev = tq * (t * s.d_wo * dwo) * d.geometry[j - 2].tangent;
  b.g_cur = tq * (Mat3::Identity() - t * s.d_wo * dwo + t * s.d_n * d.geometry[j - 1].dn_dx) * T;
  b.g_u = tq * (t * s.d_u);
  return b;
}

StepBlocks camera_blocks(const ForwardPath& path, const PathDifferential& d) {
  const Hit& x1 = path.vertices[0];
  const double t = glm::length(x1.p - path.eye);
  StepBlocks b;
  b.g_u = d.geometry[0].tangent.transpose() * transfer_matrix(path.camera_dir, x1.ng) * (t * d.camera_d_dir);
  return b;
}

PathDifferential differentiate(const World& world, const Vec2& pixel, const ForwardPath& path,
                              const Eigen::VectorXd& U, BounceParameterisation param) {
  PathDifferential d;
  d.k = static_cast<int>(path.vertices.size());
  for (const Hit& h : path.vertices) d.geometry.push_back(vertex_geometry(h));
  d.camera_d_dir = camera_direction_derivative(world.camera(), pixel + Vec2(U[0], U[1]));
  for (int j = 1; j < d.k; ++j) {
    const Hit& h = path.vertices[j - 1];
    const Vec3 wo = -(j == 1 ? path.camera_dir : path.wi[j - 2]);
    const Bsdf& bsdf = *world.surface(h.shape_id).bsdf;
    d.sampling.push_back(param == BounceParameterisation::kHalfVector
                             ? halfvector_derivative(bsdf, h, wo, path.wi[j - 1], path.flags[j - 1], path.pdf[j - 1])
                             : sampling_derivative(bsdf, h, wo, Vec2(U[2 * j], U[2 * j + 1]), path.flags[j - 1]));
    d.max_direction_mismatch =
        std::max(d.max_direction_mismatch, glm::length(d.sampling.back().wi - path.wi[j - 1]));
  }
  d.blocks.push_back(camera_blocks(path, d));
  for (int j = 1; j < d.k; ++j) d.blocks.push_back(step_blocks(path, d, j));
  return d;
}

std::vector<std::vector<Mat2>> propagate_full(const std::vector<StepBlocks>& blocks) {
  const int k = static_cast<int>(blocks.size());
  std::vector<std::vector<Mat2>> phi(k, std::vector<Mat2>(k + 1, Mat2::Zero()));
  for (int i = 0; i < k; ++i) {
    phi[i][i + 1] = blocks[i].g_u;  // Eq. 44: dx_{i+1}/du_i = A_i^-1, dx_i/du_i = 0
    for (int j = i + 1; j < k; ++j) phi[i][j + 1] = blocks[j].g_prev * phi[i][j - 1] + blocks[j].g_cur * phi[i][j];
  }
  return phi;
}

Eigen::MatrixXd vertex_jacobian(const std::vector<VertexGeometry>& geometry, const std::vector<StepBlocks>& blocks) {
  const int k = static_cast<int>(blocks.size());
  const auto phi = propagate_full(blocks);
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(3 * k, 2 * k);
  for (int i = 0; i < k; ++i)
    for (int j = i + 1; j <= k; ++j) J.block<3, 2>(3 * (j - 1), 2 * i) = geometry[j - 1].tangent * phi[i][j];
  return J;
}

Eigen::MatrixXd vertex_jacobian(const PathDifferential& d) { return vertex_jacobian(d.geometry, d.blocks); }

EndpointMap endpoint_map(const ForwardPath& path, const PathDifferential& d) {
  const int k = d.k;
  const Vec3 xk = path.vertices[k - 1].p;
  const Vec3 prev = k == 1 ? path.eye : path.vertices[k - 2].p;
  const Vec3 e = prev - xk;
  const double len = glm::length(e);
  const Vec3 o = e / len;
  Vec3 s, t;
  coordinate_system(o, &s, &t);
  const Mat23 E = columns(s, t).transpose();
  const Mat3 dob = projector(o) / len;  // do = dob (dx_{k-1} - dx_k), Eq. 45
  EndpointMap m;
  m.p_x = E * d.geometry[k - 1].tangent;
  if (k > 1) m.d_prev = E * dob * d.geometry[k - 2].tangent;
  m.d_cur = -E * dob * d.geometry[k - 1].tangent;
  return m;
}

namespace {
Mat42 endpoint_columns(const EndpointMap& e, const Mat2& phi_k, const Mat2& phi_km1) {
  Mat42 J;
  J.topRows<2>() = e.p_x * phi_k;
  J.bottomRows<2>() = e.d_prev * phi_km1 + e.d_cur * phi_k;
  return J;
}
}  // namespace

EndpointCovariance endpoint_covariance_full(const std::vector<StepBlocks>& blocks, const EndpointMap& e) {
  const int k = static_cast<int>(blocks.size());
  const auto phi = propagate_full(blocks);
  EndpointCovariance c;
  for (int i = 0; i < k; ++i) {
    const Mat42 J = endpoint_columns(e, phi[i][k], phi[i][k - 1]);
    c.sigma += J * J.transpose();  // Eq. 18
    if (i == 0) c.sigma_camera = J * J.transpose();
  }
  return c;
}

EndpointCovariance endpoint_covariance_incremental(const std::vector<StepBlocks>& blocks, const EndpointMap& e) {
  // App. B.2 in the forward form: with a = dxi_{j-1}/du_i, b = dxi_j/du_i (both 0 for i = j),
  //   [Phi_{j+1} Phi_j^T] = g_prev [Phi_j Phi_{j-1}^T]^T + g_cur [Phi_j^2],
  //   [Phi_{j+1}^2] = g_prev [Phi_{j-1}^2] g_prev^T + g_prev [.]^T g_cur^T + g_cur [.] g_prev^T
  //                   + g_cur [Phi_j^2] g_cur^T + g_u g_u^T.
  // The last term, A_j^-1 A_j^-T, is u_j's own spread; the printed equation leaves it out.
  IncrementalSums z;
  Mat2 &s_cur = z.s_cur, &s_prev = z.s_prev, &x = z.x;  // [Phi_j^2], [Phi_{j-1}^2], [Phi_j Phi_{j-1}^T]
  Mat2 &c_cur = z.c_cur, &c_prev = z.c_prev;             // camera columns dxi/du_0
  for (size_t j = 0; j < blocks.size(); ++j) {
    const StepBlocks& b = blocks[j];
    const Mat2 xn = b.g_prev * x.transpose() + b.g_cur * s_cur;
    const Mat2 sn = b.g_prev * s_prev * b.g_prev.transpose() + b.g_prev * x.transpose() * b.g_cur.transpose() +
                    b.g_cur * x * b.g_prev.transpose() + b.g_cur * s_cur * b.g_cur.transpose() +
                    b.g_u * b.g_u.transpose();
    const Mat2 cn = b.g_prev * c_prev + b.g_cur * c_cur + (j == 0 ? b.g_u : Mat2::Zero());
    s_prev = s_cur;
    s_cur = sn;
    x = xn;
    c_prev = c_cur;
    c_cur = cn;
  }
  return endpoint_covariance_from_sums(z, e);
}

EndpointCovariance endpoint_covariance_from_sums(const IncrementalSums& z, const EndpointMap& e) {
  EndpointCovariance c;
  // The block triple of App. B.2: [Phi_k^2] -> positions, [Theta_k^2] -> directions, and the mixed block.
  c.sigma.topLeftCorner<2, 2>() = e.p_x * z.s_cur * e.p_x.transpose();
  c.sigma.bottomRightCorner<2, 2>() = e.d_prev * z.s_prev * e.d_prev.transpose() +
                                      e.d_prev * z.x.transpose() * e.d_cur.transpose() +
                                      e.d_cur * z.x * e.d_prev.transpose() + e.d_cur * z.s_cur * e.d_cur.transpose();
  c.sigma.topRightCorner<2, 2>() = e.p_x * (z.x * e.d_prev.transpose() + z.s_cur * e.d_cur.transpose());
  c.sigma.bottomLeftCorner<2, 2>() = c.sigma.topRightCorner<2, 2>().transpose();
  const Mat42 J = endpoint_columns(e, z.c_cur, z.c_prev);
  c.sigma_camera = J * J.transpose();
  return c;
}

}  // namespace tb::differential
