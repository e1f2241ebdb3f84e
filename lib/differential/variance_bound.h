// The variance-bounding ratio r~ of Zirr & Dachsbacher 2020 (Sec. 5-6): how much wider the
// endpoint distribution of the actual transport is than that of the locally deterministic
// transport (only the camera's random variables), for one sampled path.
//  * variance_ratio: from full path differentials, Eq. 18-20: Sigma = sum_i J_i J_i^T over all
//    u_i, Sigma_d from the camera's u_0; V = the two principal axes of Sigma (PCA, Sec. 6.3);
//    r~ = |V Sigma V^T|^1/2 / |V Sigma_d V^T|^1/2 (>= 1, as Sigma - Sigma_d is PSD).
//  * variance_ratio_derivative_free: Eq. 21 (Sec. 6.5, App. C.1), solid-angle densities only:
//    r~ = p(i_1) (1/p(x_1) |dx_2/di_1|^-1 + sum_i 1/p(i_i) |di_i/di_1|^-1), p(i_1) the camera's
//    solid-angle density per unit raster area, p(x_1) the aperture's (a pinhole has none: the
//    term is absent), p(i_i) the BSDF's solid-angle pdf (delta lobes contribute nothing), and
//    |di_i/di_1| the product of the solid-angle compressions of the refractions before x_i
//    (on planar geometry reflections preserve solid angle).
#pragma once

#include <span>
#include <vector>

#include "lib/differential/path_differential.h"
#include "lib/path/path.h"

namespace tb::differential {

struct VarianceRatio {
  double r = 1.0;
  Eigen::Matrix<double, 2, 4> V = Eigen::Matrix<double, 2, 4>::Zero();  // projection (rows v1, v2)
  double det_full = 0.0, det_camera = 0.0;  // |V Sigma V^T|, |V Sigma_d V^T|
};

// Eq. 20 from the covariances of Eq. 18, V the PCA plane of Sigma (Sec. 6.3).
VarianceRatio variance_ratio(const EndpointCovariance& c);
// Eq. 20 with a fixed projection V (e.g. an axis-aligned one: the position plane rows (I 0), the
// direction plane rows (0 I), the projections App. C.1 bounds Eq. 21 for).
VarianceRatio variance_ratio(const EndpointCovariance& c, const Eigen::Matrix<double, 2, 4>& V);
Eigen::Matrix<double, 2, 4> position_plane();
Eigen::Matrix<double, 2, 4> direction_plane();

struct DerivativeFreeRatio {
  double r = 1.0;
  double camera_density = 0.0;      // p(i_1), solid angle per unit raster area
  std::vector<double> terms;        // p(i_1) / (p(i_i) |di_i/di_1|) per bounce (0 for delta lobes)
};

// Solid-angle compression dw_wi / dw_wo of a refraction with relative index eta = eta_wi/eta_wo
// about the facet normal m: |wo.m| / (eta^2 |wi.m|) (Snell's law, eta_o sin_o = eta_i sin_i).
double refraction_solid_angle_ratio(const Vec3& wo, const Vec3& wi, const Vec3& m, double eta);

// Eq. 21 for a traced path (its vertices, sample flags and pdfs).
DerivativeFreeRatio variance_ratio_derivative_free(const World& world, const ForwardPath& path);

// Eq. 21 for the camera subpath of a bidirectional technique (lib/path/path.h): camera[0] the lens
// vertex, camera[1 ..] the surface vertices reached from it, the first `t` of them used (t < 0:
// all). The sampled directions are those at camera[1 .. t-2] towards camera[2 .. t-1]; their
// solid-angle pdfs are the stored area densities converted back (pdf_fwd d^2 / |cos| at the
// receiving vertex), refractions detected from the two directions at the vertex and compressed
// as in the path-tracer form above. The last camera vertex either lies on an emitter (s = 0) or
// is connected to a light subpath (s >= 1); the connection and the light subpath are treated as
// the (virtual) emitter, as Sec. 6.6 does for the vertex that next-event estimation connects:
// their variance is controlled by the MIS weights, not bounded here. With `mis_reduction` the
// same holds for an s = 0 path's last direction (towards the emitter, which the s = 1 technique
// also samples): its term is left out, so the MIS-weighted direct illumination of a vertex is not
// downweighted (Sec. 6.6). A camera subpath of fewer than three vertices gives r~ = 1; a non-Dirac direction of
// zero density gives r~ = infinity (nothing bounds it: the stratified target is then f / B). Pinhole
// cameras only: the aperture term is absent (a lens camera's would be added to the sum).
double subpath_variance_ratio(const World& world, std::span<const PathVertex> camera, int t, int s,
                              bool mis_reduction);

}  // namespace tb::differential
