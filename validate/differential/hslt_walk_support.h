// Helpers for the checks of the predictor-corrector walk (lib/differential/hslt_walk.h;
// Kaplanyan, Hanika, Dachsbacher 2014, Sec. 5.1, 5.2): targets on a small disk around every half
// vector, the walk options of a path family, and an independent on-surface / constraint test
// of a walk's result.
#pragma once

#include <cstdint>
#include <string>

#include <Eigen/Dense>

#include "lib/differential/hslt_walk.h"
#include "lib/geometry/scene.h"

namespace tb {

// h* = h^perp(X) + delta (cos phi_i, sin phi_i) at every interior vertex i, phi_i uniform from
// (seed, key, index): each half vector moves by exactly delta ("sampling on a small disk around
// each individual half vector", Sec. 5.1). The same phi_i for every delta of a sweep.
Eigen::VectorXd hslt_walk_target(const HsltPath& path, double delta, uint64_t seed, uint64_t key, int64_t index);
// The unit-disk directions themselves (delta = 1, without h^perp(X)).
Eigen::VectorXd hslt_walk_direction(const HsltPath& path, uint64_t seed, uint64_t key, int64_t index);

// Traced families (real, unoccluded ray paths): visibility on; sampled families (connected
// through other shapes, Sec. 4 constraints are geometric): visibility off.
HsltWalkOptions hslt_walk_options_for(const std::string& family);

// Whether the ray-casting corrector reproduces the path itself from both endpoints (a zero
// predictor step returns X within 1e-7): sampled paths whose segments cross their own shape
// (a chord through a sphere towards its far side) are not paths the walk can represent.
bool hslt_walk_start_ok(const Scene& scene, const HsltPath& path, bool visibility);

// The independent test of a walk result: every interior vertex rebuilt from its shape at its
// (u, v) (Scene::surface_at); `surface_distance` = max |p - surface_at(uv).p|, `constraint_error`
// = |H^perp(rebuilt path) - target|_2. A vertex that is not on its surface fails both.
struct HsltOnSurface {
  double surface_distance = 0, constraint_error = 0;
};
HsltOnSurface hslt_walk_on_surface(const Scene& scene, const HsltPath& path, const Eigen::VectorXd& target);

}  // namespace tb
