// Path differentials of the path tracer's forward map X(U) (Zirr & Dachsbacher 2020, "Path
// Differential-Informed Stratified MCMC and Adaptive Forward Path Sampling", Sec. 6.2-6.4 and
// App. B). docs/zirr2020.md has the derivations and the checks.
//
// The forward map. U = (u_0, u_1, ..., u_{k-1}): u_0 = the film uniforms within a fixed pixel
// (raster = pixel + u_0, as the path tracer's CameraDim::kFilmX, kFilmY), u_j = the two direction uniforms of the BSDF sample at vertex x_j.
// X(U) = (x_1, ..., x_k), the first k surface vertices, traced exactly as the path tracer does
// (Camera::generate_primary_ray, Scene::intersect, SurfaceScatter::sample, spawn_ray), except that
// each vertex is moved from the offset ray's hit to the un-offset ray's: analytic shapes are
// re-intersected along the un-offset ray (with the hit's differential geometry), mesh hits are
// stepped to the triangle's plane along the ray. The spawn offset (up to ~1e-6 on float meshes)
// follows rounding-error bounds, and the offset hit lies offset / cos away along the surface, so
// its normal would enter dX/dU at ~1e-5 relative; a mesh hit near an edge also has its
// barycentrics clamped into the triangle Embree's float test chose. Discrete
// lobe selection (reflection vs. transmission) is not part of U: it is held fixed per bounce, as
// the derivative of App. B is the derivative within one lobe (the dimension-matched map X(A) of
// App. B.1 restricted to that lobe's subset of A). trace_forward realises a fixed lobe through
// the lobe uniform: 0 selects the reflection lobe whenever it has positive probability,
// 1 - 2^-53 the transmission lobe; a path whose lobes or hit shapes differ from the requested
// ones is reported as invalid. Only the pinhole camera is supported (no lens dimensions).
//
// The Jacobian (App. B.1). Each vertex x_j moves in its tangent plane; positions are tracked as
// 2D coordinates xi_j in an orthonormal tangent basis T_j (dx_j = T_j dxi_j). The sampling step
// at x_j is the map x_{j+1} = G_j(x_{j-1}, x_j, u_j); its 2x2 blocks
//   g_prev = dxi_{j+1}/dxi_{j-1},  g_cur = dxi_{j+1}/dxi_j,  g_u = dxi_{j+1}/du_j
// are those of Eq. 43 solved for x_{j+1}: with A_j = du_j/dx_{j+1}, B_j = du_j/dx_j,
// C_j = du_j/dx_{j-1}, g_u = A_j^-1, g_cur = -A_j^-1 B_j, g_prev = -A_j^-1 C_j, so that Eq. 44
// reads dx_{j+1}/du_i = g_prev dx_{j-1}/du_i + g_cur dx_j/du_i (+ g_u for i = j). The forward form
// stays valid for delta lobes, where g_u = 0 and A_j does not exist.
// Each block is the chain of: the change of wo with x_{j-1} and x_j; the change of the shading
// normal with x_j (curvature, dn/dx = [dn/du dn/dv] [dp/du dp/dv]^+); the direction sampling
// derivative dwi = S_wo dwo + S_n dn + S_u du (reflection, refraction with eta, microfacet normal
// sampling, cosine-weighted hemisphere sampling, the frame's dependence on n); and the transfer
// to the next tangent plane, dx_{j+1} = (I - wi N^T / (N.wi)) (dx_j + t dwi) (Igehy 1999).
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Dense>

#include "lib/geometry/hit.h"
#include "lib/scene/world.h"

namespace tb::differential {

using Mat2 = Eigen::Matrix2d;
using Mat3 = Eigen::Matrix3d;
using Mat32 = Eigen::Matrix<double, 3, 2>;
using Mat23 = Eigen::Matrix<double, 2, 3>;
using Mat4 = Eigen::Matrix4d;
using Mat42 = Eigen::Matrix<double, 4, 2>;

// The uniform that selects the reflection (false) or transmission (true) lobe.
double lobe_uniform(bool transmission);

// How the sampled direction depends on the scattering geometry.
enum class LobeKind : uint8_t {
  kDiffuse,  // wi = frame(n) * cosine-hemisphere(u)
  kReflect,  // wi = reflect(wo, m), m = n (delta) or a sampled microfacet normal
  kRefract,  // wi = refract(wo, m, eta), m as above
};

// One traced path: vertices x_1..x_k with their differential geometry, and what each sampling
// step chose.
struct ForwardPath {
  Vec3 eye{0.0};                 // x_0 (pinhole)
  Vec3 camera_dir{0.0};          // unit direction of the primary ray
  Vec2 raster{0.0};              // its raster position
  std::vector<Hit> vertices;     // x_1..x_k
  std::vector<Vec3> wi;          // wi_j, j = 1..k-1 (index j-1)
  std::vector<uint32_t> flags;   // BSDF sample flags at x_j, j = 1..k-1
  std::vector<double> pdf;       // solid-angle pdf (delta: discrete lobe probability)
  std::vector<Rgb> weight;       // the sample's f |cos wi| / pdf at x_j (the path tracer's throughput factor)
};

// The next vertex of a path: the hit of `ray` (spawned from `origin`, with the spawn offset when
// `offset`) moved onto the un-offset ray from `origin` as described above.
std::optional<Hit> next_vertex(const Scene& scene, const Ray& ray, const Vec3& origin, bool offset);

// Traces X(U). U has 2k entries (u_0 = film uniforms in `pixel`, then 2 per bounce); `lobe` has k-1 uniforms
// (lobe_uniform(...) to hold a lobe fixed, or any uniform for a freshly sampled path). Returns
// nothing when the path cannot be extended to k vertices.
std::optional<ForwardPath> trace_forward(const World& world, const Vec2& pixel, const Eigen::VectorXd& U, int k,
                                         const std::vector<double>& lobe);
// The same trace, stopped at its first failure instead of discarded: the longest prefix of X(U) of
// at most k vertices (possibly none; nothing only when the camera gives no primary ray). Its first
// j vertices, for any j <= vertices.size(), are trace_forward(..., j, ...) of U's first 2j entries
// bit for bit (the prefixes of one traced path, the candidates of Zirr & Dachsbacher 2020, Sec. 7.2).
std::optional<ForwardPath> trace_forward_prefix(const World& world, const Vec2& pixel, const Eigen::VectorXd& U, int k,
                                                const std::vector<double>& lobe);

// A path of k vertices sampled for checks and benchmarks: a pixel and U (film and bounce
// uniforms in [margin, 1 - margin]^2), lobes drawn with a uniform and then held fixed
// (lobe_uniform), so that trace_forward(world, pixel, U, k, lobe) reproduces `path`. Up to `attempts`
// draws from the stream of (seed, key, index); nothing when none gives k vertices. Paths with
// two consecutive vertices (or x_1 and the eye) closer than 1e-4 are not returned.
struct SampledPath {
  Vec2 pixel{0.0};
  Eigen::VectorXd U;
  std::vector<double> lobe;
  ForwardPath path;
};
std::optional<SampledPath> sample_path(const World& world, int k, uint64_t seed, uint64_t key, uint64_t index,
                                       double margin = 0.02, int attempts = 64);

// X(U) as a vector (x_1, ..., x_k) of 3k coordinates.
Eigen::VectorXd vertex_vector(const ForwardPath& path);

// The ingredients of the blocks at one vertex, in world space.
struct VertexGeometry {
  Vec3 p{0.0};
  Mat32 tangent;          // T_j: orthonormal basis of the geometric tangent plane
  Vec3 ng{0.0};           // geometric normal (the transfer's constraint plane)
  Mat3 dn_dx;             // curvature: d(shading normal)/dx for tangent dx
};

// The direction sampling derivative at one vertex: dwi = d_wo dwo + d_n dn + d_u du.
struct SamplingDerivative {
  Mat3 d_wo = Mat3::Zero();
  Mat3 d_n = Mat3::Zero();
  Mat32 d_u = Mat32::Zero();
  Vec3 wi{0.0};            // the direction the derivative was taken at (recomputed, see below)
  LobeKind kind = LobeKind::kDiffuse;
  double eta = 1.0;        // eta_wi_side / eta_wo_side (refraction)
  Vec3 m{0.0};             // facet normal on wo's side (reflect / refract)
  Mat3 dm_dn = Mat3::Zero();    // dm/dn (shading normal), reflect / refract
  Mat32 dm_du = Mat32::Zero();  // dm/du (microfacet normal sampling), reflect / refract
};

VertexGeometry vertex_geometry(const Hit& hit);

// d(s, t)/dn of the Duff et al. 2017 frame Frame::from_z(n) (lib/core/frame.h): ds, dt (3x3).
void frame_derivative(const Vec3& n, Mat3* ds, Mat3* dt);
// Derivatives of reflect(w, m) = -w + 2 (w.m) m and of refract(w, m, eta) (lib/material/bsdf.h).
void reflect_derivative(const Vec3& w, const Vec3& m, Mat3* d_w, Mat3* d_m);
void refract_derivative(const Vec3& w, const Vec3& m, double eta, Mat3* d_w, Mat3* d_m);

// The sampling derivative of SurfaceScatter::sample at `hit` for (wo, u) and the lobe `flags`
// chosen there. Throws std::invalid_argument for BSDFs without a derivative (visible-normal
// sampling). The direction it recomputes must equal the sampled one (checked by the caller).
SamplingDerivative sampling_derivative(const Bsdf& bsdf, const Hit& hit, const Vec3& wo, const Vec2& u,
                                       uint32_t flags);

// The half-vector parameterisation of a bounce (Sec. 6.4 "Practical Halfvector Derivatives",
// App. B.3): the (generalised) half vector m of (wo, wi) is held fixed in the local shading frame
// and moved by two coordinates h in the plane orthogonal to it, wi = reflect / refract(wo, m(h)).
// The columns are scaled isotropically by sqrt(|dh/di| / p(i)) so that |dx/du| = |dx/dh| |dh/di|
// / p(i) (App. B.3, densities preserved): dx_k/du_i ~ dx_k/dh_i |dh_i/di_i|^1/2 / sqrt(p(i_i)).
// Delta lobes have no random variable (d_u = 0). For peaky lobes this approximates the PSS
// derivative; for a diffuse lobe it differs (in PSS the sampled wi does not follow wo at all).
SamplingDerivative halfvector_derivative(const Bsdf& bsdf, const Hit& hit, const Vec3& wo, const Vec3& wi,
                                         uint32_t flags, double pdf);

// Camera derivative d(unit primary direction)/d raster (= d/d film uniform; pinhole), 3x2.
Mat32 camera_direction_derivative(const Camera& camera, const Vec2& raster);

// The blocks of one sampling step (j = 0: the camera, only g_u).
struct StepBlocks {
  Mat2 g_prev = Mat2::Zero();
  Mat2 g_cur = Mat2::Zero();
  Mat2 g_u = Mat2::Zero();
};

// Everything the recurrences need for one path, computed once.
struct PathDifferential {
  int k = 0;
  std::vector<VertexGeometry> geometry;   // x_1..x_k (index j-1)
  std::vector<SamplingDerivative> sampling;  // j = 1..k-1 (index j-1)
  Mat32 camera_d_dir;                     // d camera direction / d raster
  std::vector<StepBlocks> blocks;         // step j = 0..k-1 produces x_{j+1}
  double max_direction_mismatch = 0.0;    // |wi recomputed - wi sampled|, over the path
};

// Transfer of a ray moving by (dx origin, t dwi) onto the tangent plane at the hit:
// Q = I - wi N^T / (N . wi) (the transfer of Igehy 1999, "Tracing Ray Differentials", onto a plane).
Mat3 transfer_matrix(const Vec3& wi, const Vec3& n_next);

// The blocks of step j (>= 1) from the path's geometry and sampling derivatives (Eq. 43-44).
StepBlocks step_blocks(const ForwardPath& path, const PathDifferential& d, int j);
// The camera step (j = 0).
StepBlocks camera_blocks(const ForwardPath& path, const PathDifferential& d);

// How a bounce's two random variables enter the blocks.
enum class BounceParameterisation : uint8_t {
  kPrimarySample,  // the BSDF sampling routine's uniforms (exact derivative of X(U))
  kHalfVector,     // halfvector_derivative (App. B.3)
};

// Geometry, sampling derivatives and the blocks of every step.
PathDifferential differentiate(const World& world, const Vec2& pixel, const ForwardPath& path,
                              const Eigen::VectorXd& U,
                              BounceParameterisation param = BounceParameterisation::kPrimarySample);

// The full recurrence, Eq. 44, one column pair u_i at a time (O(k^2)): phi[i][j] = dxi_j/du_i
// (2x2, j = 0..k; j = 0 is the fixed eye), for blocks of any origin.
std::vector<std::vector<Mat2>> propagate_full(const std::vector<StepBlocks>& blocks);

// dX/dU (3k x 2k) from the full recurrence.
Eigen::MatrixXd vertex_jacobian(const PathDifferential& d);
Eigen::MatrixXd vertex_jacobian(const std::vector<VertexGeometry>& geometry, const std::vector<StepBlocks>& blocks);

// The endpoint (x_k^perp, o_k) in the plane orthogonal to o_k = unit(x_{k-1} - x_k) (Sec. 6.2):
// d x_perp = p_x dxi_k, d o = d_prev dxi_{k-1} + d_cur dxi_k (Eq. 45).
struct EndpointMap {
  Mat2 p_x = Mat2::Zero();
  Mat2 d_prev = Mat2::Zero();
  Mat2 d_cur = Mat2::Zero();
};
EndpointMap endpoint_map(const ForwardPath& path, const PathDifferential& d);

// Endpoint covariances (Eq. 18) with identity covariance per u_i: sigma over all u_i, and
// sigma_camera over the camera's u_0 alone (the locally deterministic transport of Sec. 6.4).
struct EndpointCovariance {
  Mat4 sigma = Mat4::Zero();
  Mat4 sigma_camera = Mat4::Zero();
};
// From the full recurrence (O(k^2)).
EndpointCovariance endpoint_covariance_full(const std::vector<StepBlocks>& blocks, const EndpointMap& e);
// The incremental form of App. B.2 (O(k), constant storage): the block triple
// ([Phi_j^2], [Phi_{j-1}^2], [Phi_j Phi_{j-1}^T]) and the camera columns propagated together.
EndpointCovariance endpoint_covariance_incremental(const std::vector<StepBlocks>& blocks, const EndpointMap& e);

// The state of the incremental form after the last bounce: [Phi_k^2], [Phi_{k-1}^2],
// [Phi_k Phi_{k-1}^T] and the camera columns dxi_k/du_0, dxi_{k-1}/du_0; and the endpoint
// covariances it gives (App. B.2, the block triple mapped by Eq. 45).
struct IncrementalSums {
  Mat2 s_cur = Mat2::Zero(), s_prev = Mat2::Zero(), x = Mat2::Zero();
  Mat2 c_cur = Mat2::Zero(), c_prev = Mat2::Zero();
};
EndpointCovariance endpoint_covariance_from_sums(const IncrementalSums& sums, const EndpointMap& e);

}  // namespace tb::differential
