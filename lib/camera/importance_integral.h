// Quadrature of the camera importance over the directions through the image, for checking the
// normalisation of We (docs/camera.md): from a lens point p,
//   I(p) = int_{w through the image} We(p, w) cos theta dw,
// computed in spherical coordinates about the camera axis (dw = sin theta dtheta dphi), with the
// image boundary found geometrically: the ray in azimuth phi leaves the image rectangle on the
// plane z = h (h = 1 for the pinhole, the focus distance for the thin lens) at tan theta_max(phi)
// = s(phi) / h, s the distance from p to the rectangle's edge. The phi integral is split at the
// four corners, so both nested Gauss-Kronrod integrals have smooth integrands. Expected:
// I(p) A_lens = 1 for every lens point p (A_lens = 1 for the pinhole).
#pragma once

#include <functional>

#include "lib/camera/camera.h"

namespace tb {

// importance(ray) is the We to integrate (normally camera.importance, or a broken variant);
// lens_point_camera is p in camera space (z = 0) and must lie inside the image rectangle scaled
// to the plane z = h (h tan_x, h tan_y), so that the exit distance is well defined; h is the
// plane_distance above.
double integrate_importance_cos(const Camera& camera, const std::function<double(const Ray&)>& importance,
                                const Vec2& lens_point_camera, double plane_distance, double tolerance = 1e-12);

}  // namespace tb
