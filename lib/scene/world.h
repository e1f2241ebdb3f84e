// A renderable world: the ray-tracing geometry, the material and emitter of every shape, the
// other lights, the camera and integrator defaults. Built in code with WorldBuilder or read
// from a JSON scene file (scene_loader.h); the builder validates what the file format
// validates, so both paths reject the same bad input.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "lib/camera/camera.h"
#include "lib/geometry/scene.h"
#include "lib/light/area_light.h"
#include "lib/light/light.h"
#include "lib/material/bsdf.h"

namespace tb {

// What sits on a shape: its BSDF (null: an emitter only, paths end there) and its emitter.
struct SurfaceInfo {
  const Bsdf* bsdf = nullptr;
  const AreaLight* emitter = nullptr;
  std::string name;
};

class World {
 public:
  const Scene& geometry() const { return *geometry_; }
  const Camera& camera() const { return *camera_; }
  const SurfaceInfo& surface(uint32_t shape_id) const { return surfaces_.at(shape_id); }
  size_t surface_count() const { return surfaces_.size(); }
  // Every light, area lights included (the same objects SurfaceInfo::emitter points to).
  const std::vector<const Light*>& lights() const { return light_ptrs_; }
  // Lights that rays escaping the scene see (the environment).
  const std::vector<const Light*>& infinite_lights() const { return infinite_; }
  const SceneSphere& bounds() const { return sphere_; }
  // Integrator defaults from the scene file ({"max_depth": ..., "spp": ...}), may be empty.
  const nlohmann::json& integrator_defaults() const { return integrator_; }
  // The scene description as read (echoed into every result).
  const nlohmann::json& description() const { return description_; }

 private:
  friend class WorldBuilder;
  std::unique_ptr<Scene> geometry_;
  std::unique_ptr<Camera> camera_;
  std::vector<std::unique_ptr<Bsdf>> bsdfs_;
  std::vector<std::unique_ptr<Light>> lights_;
  std::vector<const Light*> light_ptrs_, infinite_;
  std::vector<SurfaceInfo> surfaces_;
  SceneSphere sphere_;
  nlohmann::json integrator_ = nlohmann::json::object();
  nlohmann::json description_ = nlohmann::json::object();
};

// Builds a World in code. Throws std::invalid_argument on bad input (non-finite numbers,
// degenerate shapes, unknown material names, a world without camera).
class WorldBuilder {
 public:
  WorldBuilder();
  WorldBuilder& camera(std::unique_ptr<Camera> camera);
  // Registers a BSDF under a name for add_shape.
  WorldBuilder& material(const std::string& name, std::unique_ptr<Bsdf> bsdf);
  // Adds a shape with a named material ("" for none: a pure emitter) and optional emission.
  uint32_t add_shape(ShapeInstance shape, const std::string& material, const Rgb& emission = Rgb(0.0),
                     bool two_sided_emission = false, const std::string& name = "");
  uint32_t add_shape(TriangleMesh mesh, const std::string& material, const Rgb& emission = Rgb(0.0),
                     bool two_sided_emission = false, const std::string& name = "");
  WorldBuilder& light(std::unique_ptr<Light> light);
  WorldBuilder& integrator_defaults(nlohmann::json j);
  WorldBuilder& description(nlohmann::json j);
  std::unique_ptr<World> build();

 private:
  struct Pending {
    std::string material;
    Rgb emission;
    bool two_sided;
    std::string name;
  };
  uint32_t finish_shape(uint32_t id, const std::string& material, const Rgb& emission, bool two_sided,
                        const std::string& name);
  std::unique_ptr<World> w_;
  std::vector<std::pair<std::string, const Bsdf*>> materials_;
  std::vector<Pending> pending_;
};

}  // namespace tb
