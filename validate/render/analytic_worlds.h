// Closed-form test worlds for the image-level checks of the integrators (docs/validation.md A:
// "analytic scenes with known radiance come first"), each with its exact image: the value
// every pixel of an unbiased render converges to. docs/integrator-checks.md derives the
// closed forms; in short (per colour channel, Lambert albedo rho, pinhole camera, box filter):
//
//  - white furnace: the camera inside a sphere that is both a two-sided Lambert reflector and a
//    two-sided emitter of radiance Le. Every point sees only the sphere, so the radiance after
//    k scattering events is rho^k Le and, with at most D scattering events (RenderSettings::
//    max_depth = D), L = Le sum_{k=0}^{D} rho^k  ->  Le / (1 - rho) as D -> infinity
//    (Veach 1997, Sec. 3.7, the Neumann series of the transport equation).
//  - diffuse plane under a constant sky L_env: every point of the plane sees the sky over its
//    whole upper hemisphere, E = pi L_env, so L = rho / pi * E = rho L_env (no other bounce:
//    a plane cannot see itself).
//  - one bounce: a Lambert plane lit by a spherical emitter of radiance Le, radius r, centre c
//    fully above every point's horizon (E = pi Le (r / d)^2 cos theta, d = |c - p|, theta the
//    angle between the normal and c - p), or by a point light of intensity I
//    (E = I cos theta / d^2). The pixel value is the average of rho / pi * E over the pixel's
//    raster square (the box filter of the film), by tensor Gauss-Legendre quadrature through
//    the camera's raster -> ray map. The camera sees only the plane.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "lib/camera/camera.h"
#include "lib/core/spectrum.h"
#include "lib/film/welch_image.h"
#include "lib/scene/world.h"

namespace tb {

struct AnalyticScene {
  std::string name;
  nlohmann::json scene;          // the JSON scene the world was built from (echoed in results)
  std::unique_ptr<World> world;
  std::vector<Rgb> exact;        // per pixel, row-major: the exact pixel values
  int max_depth = 0;             // the max_depth the exact image holds for (-1: any >= min_depth)
  int min_depth = 0;             // smallest max_depth for which the exact image holds
};

struct FurnaceParams {
  Rgb albedo{0.8, 0.5, 0.3};
  Rgb emission{1.0, 2.0, 0.5};
  int max_depth = 5;
  int resolution = 8;
};
// Le * sum_{k=0}^{D} rho^k per channel; D < 0 means unbounded, Le / (1 - rho).
Rgb furnace_radiance(const Rgb& albedo, const Rgb& emission, int max_depth);
AnalyticScene make_furnace(const FurnaceParams& p);

struct SkyPlaneParams {
  Rgb albedo{0.5, 0.6, 0.8};
  Rgb sky{1.0, 0.7, 0.4};
  int resolution = 8;
};
AnalyticScene make_sky_plane(const SkyPlaneParams& p);

enum class OneBounceLight { kSphere, kPoint };
struct OneBounceParams {
  OneBounceLight light = OneBounceLight::kSphere;
  Rgb albedo{0.7, 0.5, 0.3};
  Rgb emission{4.0, 3.0, 2.0};   // sphere radiance Le, or point intensity I [W/sr]
  Vec3 light_position{1.3, 0.2, 0.5};
  double light_radius = 0.3;     // sphere only
  int resolution = 12;
  int quadrature_order = 10;     // Gauss-Legendre points per raster axis and pixel
};
AnalyticScene make_one_bounce(const OneBounceParams& p);

// Irradiance closed forms at point p with unit normal n. sphere_irradiance requires the sphere
// to be fully above the horizon (cos theta >= r / d) and throws std::invalid_argument otherwise.
double sphere_irradiance(double radiance, double radius, const Vec3& centre, const Vec3& p, const Vec3& n);
double point_irradiance(double intensity, const Vec3& light, const Vec3& p, const Vec3& n);

// Per pixel, the average of f(raster) over the pixel's unit raster square by tensor
// Gauss-Legendre quadrature of `order` points per axis (order in {5, 10, 15, 20}).
std::vector<Rgb> pixel_averages(int width, int height, const std::function<Rgb(const Vec2&)>& f, int order);

// An exact reference as a WelchImage: count 1 and the exact mean in every pixel, which
// compare_welch_images treats as a known value (one-sample t-tests).
WelchImage exact_welch_image(int width, int height, const std::vector<Rgb>& exact);

}  // namespace tb
