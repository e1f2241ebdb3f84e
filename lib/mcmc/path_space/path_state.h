// The state of Veach's path-space Metropolis light transport (Veach 1997, Ch. 11; Veach & Guibas
// 1997): a light path x_0 .. x_k of the shared representation (lib/path/path.h), x_0 on an
// emitter and x_k the camera vertex. The target is the luminance of the measurement contribution,
//   pi(x) = Y(f(x)),  f of Veach 1997 Eq. 8.7 with visibility tested on every segment,
// a density with respect to the path measure mu (product of the vertices' area measures, Eq. 8.5)
// on the disjoint union of the spaces of paths of each length. Every mutation of this folder
// states its proposal density T(x -> y) with respect to the same measure (see docs/mlt-path-space.md).
//
// Dirac (specular) vertices: f uses the Dirac coefficients of lib/path/dirac.h
// (DiracPolicy::kCoefficient), and every mutation states T in the same convention (the delta
// dropped from f and from the densities alike; Veach 1997, Sec. 10.3.5 and 11.4). A vertex's
// `delta` flag is is_dirac_surface(), a property of its material. The camera must have a Dirac
// lens position (pinhole): the camera vertex x_k is never regenerated.
#pragma once

#include <optional>
#include <vector>

#include "lib/core/spectrum.h"
#include "lib/path/path.h"

namespace tb::path_space {

struct MltPath {
  std::vector<PathVertex> v;  // x_0 (emitter) .. x_k (camera)
  int segments() const { return static_cast<int>(v.size()) - 1; }
};

// pi(x) = luminance(f(x)) with visibility: the Target of estimators/mcmc/concepts.h.
struct PathTarget {
  using State = MltPath;
  const PathContext* ctx = nullptr;
  Rgb contribution(const MltPath& x) const;
  double density(const MltPath& x) const;
};

// Vertices are "the same" when a mutation kept them: bitwise-equal positions and the same kind.
// Regenerated vertices coincide with old ones with probability zero (continuous densities); the
// camera vertex (Dirac lens) is never regenerated and Dirac light positions are never deleted.
bool same_vertex(const PathVertex& a, const PathVertex& b);

// The path vertex at a surface hit: its material, emitter and Dirac flag (is_dirac_surface).
PathVertex surface_vertex(const PathContext& ctx, const Hit& hit);

// The lobe of the Dirac vertex x_i (0 < i < k): transmission or reflection between its
// neighbours, seen from the camera side (radiance mode: wo towards x_{i+1}) or from the light
// side (importance mode: wo towards x_{i-1}).
bool transmits_from_camera_side(const MltPath& x, int i);
bool transmits_from_light_side(const MltPath& x, int i);

// Raster position of the path: where the ray from the lens vertex x_k towards x_{k-1} meets the
// film (nothing when outside the image).
std::optional<Vec2> path_raster(const PathContext& ctx, const MltPath& x);

}  // namespace tb::path_space
