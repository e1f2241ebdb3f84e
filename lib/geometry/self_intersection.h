// Diagnostic for robust ray spawning: fires rays from surface points of one shape (alone in a
// scene) and counts self-intersections. Points are drawn by area sampling, directions
// uniformly over the hemisphere on the outside of ng, and for closed shapes alternately on the
// inside. A self-intersection is a hit of the same shape whose distance from the spawned
// point is below `self_distance` times the shape's size (spurious re-hits lie within the
// offset, ~1e-15 of the size for analytic shapes, ~1e-6 for float triangles; a genuine re-hit
// that close needs a direction within that angle of the tangent plane), or, for meshes, a
// re-hit of the same triangle. For closed shapes an inward ray that escapes is a leak; for
// convex shapes any hit of an outward ray counts as a self-intersection.
#pragma once

#include <cstdint>

#include "lib/geometry/scene.h"

namespace tb {

struct SelfIntersectionStats {
  int64_t rays = 0;
  int64_t self_hits = 0;     // must be 0
  int64_t leaks = 0;         // inward rays of closed shapes that hit nothing; must be 0
  int64_t first_bad = -1;    // index of the first offending ray (reproducer)
};

struct SelfIntersectionOptions {
  int64_t rays = 100000;
  uint64_t seed = 1;
  uint64_t key = 0;
  bool closed = false;          // also fire inward rays and count leaks
  bool convex = false;          // outward rays must hit nothing at all (counted as self hits)
  double size = 1.0;            // shape size (bounding-box diagonal)
  double self_distance = 1e-9;  // relative to size
  // Negative control: spawn rays from the unoffset surface point (no error-bound offset).
  bool disable_offset = false;
};

// Counts over rays i = 0..rays-1, each from the stream (seed, key, i); parallel and
// deterministic.
SelfIntersectionStats count_self_intersections(const Scene& scene, uint32_t shape_id,
                                               const SelfIntersectionOptions& options);

}  // namespace tb
