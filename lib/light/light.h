// Emitters. Every emitter answers the two questions a bidirectional renderer asks, with its
// densities in stated measures:
//  - next-event estimation from a reference point: sample_li / pdf_li (solid angle at the
//    reference point; 1 for lights with a delta in position or direction);
//  - emission for light tracing: sample_le / pdf_le, a position (area measure on the emitter;
//    1 for a point light) and a direction (solid angle; 1 for a delta direction).
// Radiance conventions: area lights emit radiance Le on their front side (normal side), or on
// both sides when two_sided; point and spot lights have intensity I [W/sr]; a directional
// light has irradiance E [W/m^2] on surfaces facing it; the constant environment radiance L.
#pragma once

#include <optional>
#include <string_view>

#include "lib/core/frame.h"
#include "lib/core/math.h"
#include "lib/core/ray.h"
#include "lib/core/spectrum.h"
#include "lib/geometry/hit.h"

namespace tb {

namespace light_flags {
inline constexpr uint32_t kDeltaPosition = 1u << 0;  // point, spot
inline constexpr uint32_t kDeltaDirection = 1u << 1; // directional
inline constexpr uint32_t kArea = 1u << 2;
inline constexpr uint32_t kInfinite = 1u << 3;       // directional, environment
}  // namespace light_flags

// A sphere bounding the scene: infinite lights emit from a disk of this radius.
struct SceneSphere {
  Vec3 center{0.0};
  double radius = 1.0;
};

// A light sample for next-event estimation without the emitter point's differential geometry
// (what a path tracer needs: sample_li_point).
struct LightLiPoint {
  Vec3 wi{0, 0, 1};      // unit direction from the reference point towards the light
  Rgb li{0.0};           // radiance (or I/d^2, E for delta lights) arriving at the reference point
  double pdf = 0.0;      // solid angle at the reference point; 1 for delta lights
  Vec3 p_light{0.0};     // the point on the light (far away along wi for infinite lights)
  Vec3 n_light{0.0};     // its normal (zero for point lights and infinite lights)
  double distance = kInfinity;  // to p_light, for the shadow ray
  double pdf_area = 0.0; // area density of p_light on the emitter (area lights only)
};

struct LightLiSample : LightLiPoint {
  Hit hit;               // the emitter point: full geometry for area lights (shadow-ray spawning,
                         // path vertices), p and n only for other lights
};

struct LightLeSample {
  Ray ray;               // origin on the emitter, unit direction
  Vec3 n{0.0};           // emitter normal at the origin (zero for point lights)
  Rgb le{0.0};           // emitted radiance / intensity along the ray
  double pdf_pos = 0.0;  // area measure (1 for delta position)
  double pdf_dir = 0.0;  // solid angle (1 for delta direction)
  Hit hit;               // the emission point: full geometry for area lights (spawn the ray with
                         // spawn_ray(hit, ray.d) to leave the surface robustly), p and n otherwise
};

class Light {
 public:
  virtual ~Light() = default;
  virtual std::string_view name() const = 0;
  virtual uint32_t flags() const = 0;
  bool is_delta() const { return (flags() & (light_flags::kDeltaPosition | light_flags::kDeltaDirection)) != 0; }

  virtual std::optional<LightLiSample> sample_li(const Vec3& ref, const Vec2& u) const = 0;
  // The same sample (same uniforms, same values) without the Hit: lights whose sample_li builds
  // a full Hit (area lights) override it with a lean version; the default slices sample_li.
  virtual std::optional<LightLiPoint> sample_li_point(const Vec3& ref, const Vec2& u) const;
  // Solid-angle density at `ref` of sample_li producing direction wi (unit) that reaches the
  // emitter at `on_light` (a hit on an area light; null for infinite lights). 0 for delta lights.
  virtual double pdf_li(const Vec3& ref, const Vec3& wi, const SurfacePoint* on_light) const = 0;

  virtual std::optional<LightLeSample> sample_le(const Vec2& u_pos, const Vec2& u_dir) const = 0;
  // Densities of sample_le producing a ray from `at` (a point on the emitter: a hit on an area
  // light, the position of a point light, a point of the emission disk of an infinite light)
  // in unit direction w: position (area measure) and direction (solid angle).
  virtual void pdf_le(const Hit& at, const Vec3& w, double* pdf_pos, double* pdf_dir) const = 0;

  // Radiance leaving a point of this emitter with normal n towards w (area lights), or arriving
  // along a ray escaping the scene in direction w (environment). Zero otherwise.
  virtual Rgb le(const Vec3& n, const Vec3& w) const = 0;
  // Total emitted power [W], for light selection proportional to power.
  virtual Rgb power() const = 0;
  // Called once the scene bounds are known (infinite lights need them).
  virtual void set_scene_sphere(const SceneSphere&) {}
};

// Samples an emission direction about n: cosine-weighted on the front side (or on a random
// side for two-sided emitters, each chosen with probability 1/2). Density in solid angle.
Vec3 sample_emission_direction(const Vec3& n, bool two_sided, const Vec2& u);
double pdf_emission_direction(const Vec3& n, bool two_sided, const Vec3& w);

}  // namespace tb
