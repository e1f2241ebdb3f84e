#include "lib/scene/world.h"

#include <stdexcept>

#include <fmt/format.h>

namespace tb {

WorldBuilder::WorldBuilder() : w_(std::make_unique<World>()) { w_->geometry_ = std::make_unique<Scene>(); }

WorldBuilder& WorldBuilder::camera(std::unique_ptr<Camera> camera) {
  w_->camera_ = std::move(camera);
  return *this;
}

WorldBuilder& WorldBuilder::material(const std::string& name, std::unique_ptr<Bsdf> bsdf) {
  for (const auto& [n, b] : materials_)
    if (n == name) throw std::invalid_argument(fmt::format("material '{}' defined twice", name));
  materials_.emplace_back(name, bsdf.get());
  w_->bsdfs_.push_back(std::move(bsdf));
  return *this;
}

uint32_t WorldBuilder::finish_shape(uint32_t id, const std::string& material, const Rgb& emission, bool two_sided,
                                    const std::string& name) {
  if (!is_finite(emission) || emission.r < 0 || emission.g < 0 || emission.b < 0)
    throw std::invalid_argument(fmt::format("shape '{}': emission must be finite and non-negative", name));
  if (!material.empty()) {
    bool found = false;
    for (const auto& [n, b] : materials_) found = found || n == material;
    if (!found) throw std::invalid_argument(fmt::format("shape '{}': unknown material '{}'", name, material));
  }
  if (material.empty() && is_black(emission))
    throw std::invalid_argument(fmt::format("shape '{}': neither a material nor emission", name));
  if (id != pending_.size()) throw std::logic_error("shape ids out of order");
  pending_.push_back(Pending{material, emission, two_sided, name});
  return id;
}

uint32_t WorldBuilder::add_shape(ShapeInstance shape, const std::string& material, const Rgb& emission,
                                 bool two_sided_emission, const std::string& name) {
  return finish_shape(w_->geometry_->add(std::move(shape)), material, emission, two_sided_emission, name);
}

uint32_t WorldBuilder::add_shape(TriangleMesh mesh, const std::string& material, const Rgb& emission,
                                 bool two_sided_emission, const std::string& name) {
  if (mesh.triangle_count() == 0) throw std::invalid_argument(fmt::format("shape '{}': mesh has no triangles", name));
  for (const Vec3& p : mesh.positions())
    if (!is_finite(p)) throw std::invalid_argument(fmt::format("shape '{}': mesh has a non-finite vertex", name));
  for (uint32_t t = 0; t < mesh.triangle_count(); ++t)
    if (!(mesh.triangle_area(t) > 0))
      throw std::invalid_argument(fmt::format("shape '{}': triangle {} is degenerate (zero area)", name, t));
  return finish_shape(w_->geometry_->add(std::move(mesh)), material, emission, two_sided_emission, name);
}

WorldBuilder& WorldBuilder::light(std::unique_ptr<Light> light) {
  w_->lights_.push_back(std::move(light));
  return *this;
}

WorldBuilder& WorldBuilder::integrator_defaults(nlohmann::json j) {
  w_->integrator_ = std::move(j);
  return *this;
}

WorldBuilder& WorldBuilder::description(nlohmann::json j) {
  w_->description_ = std::move(j);
  return *this;
}

std::unique_ptr<World> WorldBuilder::build() {
  if (!w_->camera_) throw std::invalid_argument("the world has no camera");
  if (pending_.empty()) throw std::invalid_argument("the world has no shapes");
  w_->geometry_->commit();
  // Bounds: from the shapes' sampled points and the camera position (for infinite lights).
  Bounds3 b;
  for (uint32_t id = 0; id < pending_.size(); ++id)
    for (int i = 0; i < 16; ++i)
      for (int j = 0; j < 16; ++j) b.extend(w_->geometry_->sample_area(id, Vec2((i + 0.5) / 16, (j + 0.5) / 16)).hit.p);
  b.extend(w_->camera_->projection().eye());
  w_->sphere_.center = 0.5 * (b.lo + b.hi);
  w_->sphere_.radius = std::max(1e-3, 0.5 * glm::length(b.hi - b.lo) * 1.01);

  w_->surfaces_.resize(pending_.size());
  for (uint32_t id = 0; id < pending_.size(); ++id) {
    const Pending& p = pending_[id];
    SurfaceInfo& s = w_->surfaces_[id];
    s.name = p.name;
    for (const auto& [n, bsdf] : materials_)
      if (n == p.material) s.bsdf = bsdf;
    if (!is_black(p.emission)) {
      auto light = std::make_unique<AreaLight>(*w_->geometry_, id, p.emission, p.two_sided);
      s.emitter = light.get();
      w_->lights_.push_back(std::move(light));
    }
  }
  for (auto& l : w_->lights_) {
    l->set_scene_sphere(w_->sphere_);
    w_->light_ptrs_.push_back(l.get());
    if ((l->flags() & light_flags::kInfinite) && !(l->flags() & light_flags::kDeltaDirection))
      w_->infinite_.push_back(l.get());
  }
  if (w_->light_ptrs_.empty()) throw std::invalid_argument("the world has no light (no emitting shape, no light)");
  return std::move(w_);
}

}  // namespace tb
