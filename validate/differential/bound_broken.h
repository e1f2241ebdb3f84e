// A deliberately broken variance-bounding ratio for the negative control of the bound checks
// (validate/checks/differential_bound_checks.cpp): Eq. 21 of Zirr & Dachsbacher 2020 without the
// camera density p(i_1), r' = 1 + sum_i 1 / (p(i_i) |di_i/di_1|). It drops the factor that makes
// r~ compare the BSDF's spread with the camera's (per pixel), so it is no longer conservative.
#pragma once

#include <Eigen/Dense>

#include "lib/differential/path_differential.h"

namespace tb::bound {

double ratio_eq21_without_camera_density(const World& world, const Vec2& pixel, const Eigen::VectorXd& U,
                                         const differential::ForwardPath& path);

}  // namespace tb::bound
