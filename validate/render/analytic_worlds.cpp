#include "validate/render/analytic_worlds.h"

#include <cmath>
#include <stdexcept>

#include <boost/math/quadrature/gauss.hpp>
#include <fmt/format.h>

#include "lib/scene/scene_loader.h"

namespace tb {
namespace {

nlohmann::json rgb_json(const Rgb& c) { return nlohmann::json::array({c.r, c.g, c.b}); }
nlohmann::json vec_json(const Vec3& v) { return nlohmann::json::array({v.x, v.y, v.z}); }

nlohmann::json camera_json(const Vec3& eye, const Vec3& target, const Vec3& up, double fov, int resolution) {
  return {{"type", "pinhole"},     {"position", vec_json(eye)}, {"look_at", vec_json(target)},
          {"up", vec_json(up)},    {"fov", fov},                {"resolution", {resolution, resolution}}};
}

AnalyticScene finish(std::string name, nlohmann::json scene) {
  AnalyticScene s;
  s.name = std::move(name);
  s.scene = std::move(scene);
  s.world = load_world_from_string(s.scene.dump(1), s.name);
  return s;
}

// The point where a camera ray meets the plane z = 0 (the ray must point down).
Vec3 hit_plane_z0(const Ray& ray) {
  if (!(ray.d.z < 0)) throw std::logic_error("analytic one-bounce scene: a camera ray misses the plane");
  const double t = -ray.o.z / ray.d.z;
  return ray.o + t * ray.d;
}

// Tensor Gauss-Legendre on [0, 1]^2 with N points per axis.
template <int N>
Rgb square_average(const std::function<Rgb(const Vec2&)>& f, const Vec2& corner) {
  using Rule = boost::math::quadrature::gauss<double, N>;
  // Rule::abscissa()/weights() hold the non-negative half of the symmetric rule on [-1, 1].
  const auto& xs = Rule::abscissa();
  const auto& ws = Rule::weights();
  std::vector<std::pair<double, double>> nodes;  // (node in [0, 1], weight summing to 1)
  for (size_t i = 0; i < xs.size(); ++i) {
    if (xs[i] == 0.0) {
      nodes.push_back({0.5, 0.5 * ws[i]});
    } else {
      nodes.push_back({0.5 - 0.5 * xs[i], 0.5 * ws[i]});
      nodes.push_back({0.5 + 0.5 * xs[i], 0.5 * ws[i]});
    }
  }
  Rgb sum(0.0);
  for (const auto& [y, wy] : nodes)
    for (const auto& [x, wx] : nodes) sum += (wx * wy) * f(corner + Vec2(x, y));
  return sum;
}

}  // namespace

Rgb furnace_radiance(const Rgb& albedo, const Rgb& emission, int max_depth) {
  Rgb l(0.0);
  for (int c = 0; c < 3; ++c) {
    if (max_depth < 0) {
      l[c] = emission[c] / (1.0 - albedo[c]);
    } else {
      // Horner form of Le (1 + rho (1 + rho (...))): D + 1 terms.
      double s = 1.0;
      for (int k = 0; k < max_depth; ++k) s = 1.0 + albedo[c] * s;
      l[c] = emission[c] * s;
    }
  }
  return l;
}

AnalyticScene make_furnace(const FurnaceParams& p) {
  // The eye is off-centre and looks off-axis so that no symmetry of the set-up hides an error in
  // the camera or sphere parameterisation; every camera ray still meets the sphere.
  nlohmann::json scene = {
      {"description", "white furnace: camera inside a two-sided emitting Lambert sphere (validate/render)"},
      {"camera", camera_json(Vec3(0.2, -0.1, 0.15), Vec3(0.5, 0.3, 1.0), Vec3(0, 1, 0), 70.0, p.resolution)},
      {"materials", {{{"name", "furnace"}, {"type", "lambert"}, {"reflectance", rgb_json(p.albedo)}}}},
      {"shapes",
       {{{"type", "sphere"}, {"radius", 1.0}, {"material", "furnace"}, {"emission", rgb_json(p.emission)},
         {"two_sided", true}, {"name", "furnace"}}}}};
  AnalyticScene s = finish(fmt::format("furnace(D={})", p.max_depth), std::move(scene));
  s.exact.assign(size_t(p.resolution) * size_t(p.resolution), furnace_radiance(p.albedo, p.emission, p.max_depth));
  s.max_depth = p.max_depth;
  s.min_depth = p.max_depth;
  return s;
}

AnalyticScene make_sky_plane(const SkyPlaneParams& p) {
  // Looking down from 1.5 above the plane, 40 degree field of view, slightly tilted: the view's
  // footprint stays within |x|, |y| < 1.2, inside the 2 x 2 half-size rectangle.
  nlohmann::json scene = {
      {"description", "diffuse plane under a constant sky (validate/render)"},
      {"camera", camera_json(Vec3(0.0, 0.0, 1.5), Vec3(0.2, 0.1, 0.0), Vec3(0, 1, 0), 40.0, p.resolution)},
      {"materials", {{{"name", "plane"}, {"type", "lambert"}, {"reflectance", rgb_json(p.albedo)}}}},
      {"shapes", {{{"type", "rectangle"}, {"half_size", {2.0, 2.0}}, {"material", "plane"}, {"name", "plane"}}}},
      {"lights", {{{"type", "environment"}, {"radiance", rgb_json(p.sky)}}}}};
  AnalyticScene s = finish("sky_plane", std::move(scene));
  s.exact.assign(size_t(p.resolution) * size_t(p.resolution), p.albedo * p.sky);
  s.max_depth = -1;
  s.min_depth = 1;
  return s;
}

double sphere_irradiance(double radiance, double radius, const Vec3& centre, const Vec3& p, const Vec3& n) {
  const Vec3 d = centre - p;
  const double dist = glm::length(d);
  const double cos_theta = glm::dot(n, d) / dist;
  if (cos_theta < radius / dist)
    throw std::invalid_argument("sphere_irradiance: the sphere is not fully above the horizon");
  // Nusselt analogue: the projected solid angle of a sphere above the horizon is
  // pi sin^2(alpha) cos theta with sin alpha = r / d.
  return kPi * radiance * (radius / dist) * (radius / dist) * cos_theta;
}

double point_irradiance(double intensity, const Vec3& light, const Vec3& p, const Vec3& n) {
  const Vec3 d = light - p;
  const double dist2 = glm::dot(d, d);
  return intensity * std::max(0.0, glm::dot(n, d)) / std::sqrt(dist2) / dist2;
}

std::vector<Rgb> pixel_averages(int width, int height, const std::function<Rgb(const Vec2&)>& f, int order) {
  std::vector<Rgb> out(size_t(width) * size_t(height));
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const Vec2 corner(x, y);
      Rgb v;
      switch (order) {
        case 5: v = square_average<5>(f, corner); break;
        case 10: v = square_average<10>(f, corner); break;
        case 15: v = square_average<15>(f, corner); break;
        case 20: v = square_average<20>(f, corner); break;
        default: throw std::invalid_argument(fmt::format("pixel_averages: unsupported order {}", order));
      }
      out[size_t(y) * size_t(width) + size_t(x)] = v;
    }
  return out;
}

AnalyticScene make_one_bounce(const OneBounceParams& p) {
  // Camera 1.5 above the plane z = 0 looking straight down with a 40 degree field of view: the
  // footprint is |x|, |y| <= 0.55. The light sits outside the view cone and above every
  // point's horizon (height > radius), so the camera sees only the plane and the plane sees the
  // light whole; the plane cannot see itself, so one bounce is all there is.
  const bool sphere = p.light == OneBounceLight::kSphere;
  if (sphere && !(p.light_position.z > p.light_radius))
    throw std::invalid_argument("make_one_bounce: the sphere light must be above the plane");
  nlohmann::json scene = {
      {"description", fmt::format("Lambert plane lit by a {} light, one bounce (validate/render)",
                                  sphere ? "spherical" : "point")},
      {"camera", camera_json(Vec3(0.0, 0.0, 1.5), Vec3(0.0, 0.0, 0.0), Vec3(0, 1, 0), 40.0, p.resolution)},
      {"materials", {{{"name", "plane"}, {"type", "lambert"}, {"reflectance", rgb_json(p.albedo)}}}},
      {"shapes", {{{"type", "rectangle"}, {"half_size", {3.0, 3.0}}, {"material", "plane"}, {"name", "plane"}}}}};
  if (sphere) {
    scene["shapes"].push_back({{"type", "sphere"},
                               {"radius", p.light_radius},
                               {"emission", rgb_json(p.emission)},
                               {"transform", {{"translate", vec_json(p.light_position)}}},
                               {"name", "light"}});
  } else {
    scene["lights"] = {{{"type", "point"}, {"position", vec_json(p.light_position)}, {"intensity", rgb_json(p.emission)}}};
  }
  AnalyticScene s = finish(sphere ? "one_bounce_sphere" : "one_bounce_point", std::move(scene));
  const Camera& cam = s.world->camera();
  const Vec3 n(0, 0, 1);
  s.exact = pixel_averages(
      cam.width(), cam.height(),
      [&](const Vec2& raster) {
        const Vec3 x = hit_plane_z0(cam.generate_ray(raster, Vec2(0.5)).ray);
        Rgb l(0.0);
        for (int c = 0; c < 3; ++c) {
          const double e = sphere ? sphere_irradiance(p.emission[c], p.light_radius, p.light_position, x, n)
                                  : point_irradiance(p.emission[c], p.light_position, x, n);
          l[c] = p.albedo[c] / kPi * e;
        }
        return l;
      },
      p.quadrature_order);
  s.max_depth = -1;
  s.min_depth = 1;
  return s;
}

WelchImage exact_welch_image(int width, int height, const std::vector<Rgb>& exact) {
  if (exact.size() != size_t(width) * size_t(height)) throw std::invalid_argument("exact_welch_image: size mismatch");
  WelchImage w(width, height);
  for (size_t i = 0; i < exact.size(); ++i) w.set_from_moments(i, exact[i], Rgb(0.0), 1);
  return w;
}

}  // namespace tb
