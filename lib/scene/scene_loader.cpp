#include "lib/scene/scene_loader.h"

#include <filesystem>

#include <fmt/format.h>

#include "lib/camera/camera.h"
#include "lib/geometry/cylinder.h"
#include "lib/geometry/disk.h"
#include "lib/geometry/obj_loader.h"
#include "lib/geometry/paraboloid.h"
#include "lib/geometry/rectangle.h"
#include "lib/geometry/sphere.h"
#include "lib/geometry/torus.h"
#include "lib/light/infinite_lights.h"
#include "lib/light/point_light.h"
#include "lib/material/bsdf_registry.h"
#include "lib/core/atomic_file.h"
#include "lib/scene/mitsuba_import.h"
#include "lib/scene/tungsten_import.h"

namespace tb {

namespace {

AffineTransform parse_transform_at(const StrictObject& parent, const std::string& key) {
  if (!parent.has(key)) return {};
  return parse_transform(parent.object(key));
}

// A closed unit cube [-1/2, 1/2]^3 as 12 triangles with outward winding.
TriangleMesh make_cube(const AffineTransform& xf) {
  std::vector<Vec3> p;
  std::vector<glm::uvec3> t;
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const double s = side ? 0.5 : -0.5;
      const int a = (axis + 1) % 3, b = (axis + 2) % 3;
      const uint32_t base = static_cast<uint32_t>(p.size());
      for (auto [ua, ub] : {std::pair{-0.5, -0.5}, {0.5, -0.5}, {0.5, 0.5}, {-0.5, 0.5}}) {
        Vec3 q(0.0);
        q[axis] = s;
        q[a] = ua;
        q[b] = ub;
        p.push_back(xf.point(q));
      }
      // (a, b, axis) is right-handed: counter-clockwise seen from +axis.
      if (side)
        t.insert(t.end(), {glm::uvec3(base, base + 1, base + 2), glm::uvec3(base, base + 2, base + 3)});
      else
        t.insert(t.end(), {glm::uvec3(base, base + 2, base + 1), glm::uvec3(base, base + 3, base + 2)});
    }
  return TriangleMesh(std::move(p), std::move(t));
}

void parse_camera(const StrictObject& c, WorldBuilder& b) {
  CameraSetup s;
  const std::string type = c.choice("type", scene_camera_types(), "pinhole");
  s.eye = c.vec3("position");
  s.target = c.vec3("look_at");
  s.up = c.vec3("up", Vec3(0, 1, 0));
  s.vfov_degrees = c.positive("fov");
  const auto res = c.numbers("resolution");
  if (res.size() != 2 || res[0] < 1 || res[1] < 1 || res[0] != std::floor(res[0]) || res[1] != std::floor(res[1]))
    c.fail("resolution", "expected two positive integers [width, height]");
  // Also keeps the int cast defined and the film allocation sane (a 16384^2 RGB film is 6 GiB).
  constexpr double kMaxResolution = 16384;
  if (res[0] > kMaxResolution || res[1] > kMaxResolution)
    c.fail("resolution", fmt::format("each side must be at most {} pixels", kMaxResolution));
  s.width = static_cast<int>(res[0]);
  s.height = static_cast<int>(res[1]);
  if (type == "thin_lens") {
    s.lens_radius = c.positive("aperture_radius");
    s.focus_distance = c.positive("focus_distance");
  }
  c.finish();
  try {
    b.camera(make_camera(type, s));
  } catch (const std::invalid_argument& e) {
    c.fail("", e.what());
  }
}

void parse_material(const StrictObject& m, WorldBuilder& b) {
  const std::string name = m.string("name");
  const std::string type = m.string("type");
  // The other keys are BSDF parameters; make_bsdf checks their names and types.
  nlohmann::json params = nlohmann::json::object();
  std::vector<std::string> keys;
  for (const std::string& k : m.keys())
    if (k != "name" && k != "type") {
      params[k] = m.raw(k);
      keys.push_back(k);
    }
  m.finish();
  try {
    b.material(name, make_bsdf(type, params));
  } catch (const std::invalid_argument& e) {
    m.fail(keys.empty() ? "type" : "", fmt::format("material '{}': {}", name, e.what()));
  }
}

void parse_shape(const StrictObject& s, WorldBuilder& b, const std::string& base_dir, size_t index) {
  const std::string type =
      s.choice("type", scene_shape_types());
  const std::string name = s.string("name", fmt::format("{}#{}", type, index));
  const std::string material = s.string("material", "");
  const Rgb emission = s.rgb("emission", Rgb(0.0));
  if (emission.r < 0 || emission.g < 0 || emission.b < 0) s.fail("emission", "must be non-negative");
  const bool two_sided = s.boolean("two_sided", false);
  const bool flip = s.boolean("flip_normal", false);
  const AffineTransform xf = parse_transform_at(s, "transform");
  std::shared_ptr<const AnalyticShape> shape;
  if (type == "sphere") {
    shape = std::make_shared<Sphere>(s.positive("radius"));
  } else if (type == "disk") {
    const double r = s.positive("radius"), ri = s.number("inner_radius", 0.0);
    if (ri < 0 || ri >= r) s.fail("inner_radius", "must be in [0, radius)");
    shape = std::make_shared<Disk>(r, ri);
  } else if (type == "rectangle") {
    const Vec2 h = s.vec2("half_size");
    if (!(h.x > 0 && h.y > 0)) s.fail("half_size", "both half sizes must be positive");
    shape = std::make_shared<Rectangle>(h.x, h.y);
  } else if (type == "cylinder") {
    const double r = s.positive("radius"), z0 = s.number("z_min"), z1 = s.number("z_max");
    if (!(z1 > z0)) s.fail("z_max", "must be greater than z_min");
    shape = std::make_shared<Cylinder>(r, z0, z1);
  } else if (type == "paraboloid") {
    shape = std::make_shared<Paraboloid>(s.positive("radius"), s.positive("height"));
  } else if (type == "torus") {
    const double R = s.positive("major_radius"), r = s.positive("minor_radius");
    if (!(r < R)) s.fail("minor_radius", "must be smaller than major_radius (no self-intersecting tori)");
    shape = std::make_shared<Torus>(R, r);
  }
  if (std::abs(xf.determinant()) < 1e-12) s.fail("transform", "is singular (zero scale?)");
  std::optional<TriangleMesh> mesh;
  if (type == "cube") {
    try {
      mesh = make_cube(xf);
    } catch (const std::invalid_argument& e) {
      s.fail("transform", fmt::format("{} (degenerate cube)", e.what()));
    }
  } else if (type == "obj") {
    std::string file = s.string("file");
    const std::filesystem::path p = std::filesystem::path(file).is_absolute() ? std::filesystem::path(file)
                                                                              : std::filesystem::path(base_dir) / file;
    if (!std::filesystem::exists(p)) s.fail("file", fmt::format("mesh file not found: {}", p.string()));
    try {
      mesh = load_obj(p.string(), xf, flip);
    } catch (const std::exception& e) {
      s.fail("file", e.what());
    }
  } else if (type == "mesh") {
    std::vector<Vec3> pos, nrm;
    std::vector<glm::uvec3> tri;
    const auto& jp = s.raw("positions");
    const auto& jt = s.raw("triangles");
    if (!jp.is_array() || jp.empty()) s.fail("positions", "expected a non-empty array of [x, y, z]");
    if (!jt.is_array() || jt.empty()) s.fail("triangles", "expected a non-empty array of [i, j, k]");
    for (size_t i = 0; i < jp.size(); ++i) {
      if (!jp[i].is_array() || jp[i].size() != 3 || !jp[i][0].is_number() || !jp[i][1].is_number() ||
          !jp[i][2].is_number())
        s.fail("positions", fmt::format("element {} is not [x, y, z]", i));
      const Vec3 v(jp[i][0].get<double>(), jp[i][1].get<double>(), jp[i][2].get<double>());
      if (!is_finite(v)) s.fail("positions", fmt::format("element {} is not finite", i));
      pos.push_back(xf.point(v));
    }
    for (size_t i = 0; i < jt.size(); ++i) {
      if (!jt[i].is_array() || jt[i].size() != 3) s.fail("triangles", fmt::format("element {} is not [i, j, k]", i));
      glm::uvec3 t;
      for (int k = 0; k < 3; ++k) {
        if (!jt[i][k].is_number_unsigned() || jt[i][k].get<uint64_t>() >= pos.size())
          s.fail("triangles", fmt::format("element {} has an index outside [0, {})", i, pos.size()));
        t[k] = static_cast<uint32_t>(jt[i][k].get<uint64_t>());
      }
      tri.push_back(t);
    }
    if (s.has("normals")) {
      const auto& jn = s.raw("normals");
      if (!jn.is_array() || jn.size() != jp.size()) s.fail("normals", "expected one [x, y, z] per position");
      for (size_t i = 0; i < jn.size(); ++i) {
        if (!jn[i].is_array() || jn[i].size() != 3 || !jn[i][0].is_number() || !jn[i][1].is_number() ||
            !jn[i][2].is_number())
          s.fail("normals", fmt::format("element {} is not [x, y, z]", i));
        const Vec3 v(jn[i][0].get<double>(), jn[i][1].get<double>(), jn[i][2].get<double>());
        const Vec3 w = glm::transpose(xf.inverse_linear()) * v;
        if (!is_finite(w) || glm::length(w) == 0) s.fail("normals", fmt::format("element {} is zero or not finite", i));
        nrm.push_back(glm::normalize(w));
      }
    }
    try {
      mesh = TriangleMesh(std::move(pos), std::move(tri), std::move(nrm), {}, flip);
    } catch (const std::invalid_argument& e) {
      s.fail("triangles", fmt::format("{} (degenerate mesh)", e.what()));
    }
  }
  s.finish();
  try {
    if (mesh)
      b.add_shape(std::move(*mesh), material, emission, two_sided, name);
    else
      b.add_shape(ShapeInstance(shape, xf, flip), material, emission, two_sided, name);
  } catch (const std::invalid_argument& e) {
    s.fail("", e.what());
  }
}

void parse_light(const StrictObject& l, WorldBuilder& b) {
  const std::string type = l.choice("type", scene_light_types());
  std::unique_ptr<Light> light;
  if (type == "point") {
    light = std::make_unique<PointLight>(l.vec3("position"), l.rgb("intensity", Rgb(1.0)));
  } else if (type == "spot") {
    const Vec3 dir = l.vec3("direction");
    if (glm::length(dir) == 0) l.fail("direction", "must not be zero");
    const double total = l.positive("total_width"), start = l.number("falloff_start", total);
    if (total >= 180 || start < 0) l.fail("total_width", "cone angles must be in (0, 180) degrees");
    light = std::make_unique<SpotLight>(l.vec3("position"), dir, l.rgb("intensity", Rgb(1.0)), total, start);
  } else if (type == "directional") {
    const Vec3 dir = l.vec3("direction");
    if (glm::length(dir) == 0) l.fail("direction", "must not be zero");
    light = std::make_unique<DirectionalLight>(dir, l.rgb("irradiance", Rgb(1.0)));
  } else {
    light = std::make_unique<ConstantEnvironmentLight>(l.rgb("radiance", Rgb(1.0)));
  }
  l.finish();
  b.light(std::move(light));
}

std::unique_ptr<World> load(std::shared_ptr<const JsonDocument> doc, const std::string& base_dir) {
  // A Tungsten scene (top-level primitives / bsdfs / renderer) is translated into this format
  // first (lib/scene/tungsten_import.h); the translation reports what it cannot map.
  if (is_tungsten_scene(doc->root)) {
    const nlohmann::json converted = tungsten_to_scene_json(*doc);
    // Errors past the import (none expected: it checks what it writes) name the converted text.
    return load(JsonDocument::parse(converted.dump(1), doc->file + " (converted from Tungsten)"), base_dir);
  }
  const StrictObject root = StrictObject::root(doc);
  WorldBuilder b;
  parse_camera(root.object("camera"), b);
  for (const StrictObject& m : root.objects("materials")) parse_material(m, b);
  const auto shapes = root.objects("shapes");
  if (shapes.empty()) root.fail("shapes", "a scene needs at least one shape");
  for (size_t i = 0; i < shapes.size(); ++i) parse_shape(shapes[i], b, base_dir, i);
  for (const StrictObject& l : root.objects("lights")) parse_light(l, b);
  if (auto integ = root.optional_object("integrator")) {
    nlohmann::json j = nlohmann::json::object();
    if (integ->has("max_depth")) {
      const int64_t d = integ->integer("max_depth");
      if (d < 1) integ->fail("max_depth", "must be at least 1");
      j["max_depth"] = d;
    }
    if (integ->has("spp")) {
      const int64_t n = integ->integer("spp");
      if (n < 1) integ->fail("spp", "must be at least 1");
      j["spp"] = n;
    }
    integ->finish();
    b.integrator_defaults(j);
  }
  root.string("description", "");
  root.finish();
  b.description(doc->root);
  try {
    return b.build();
  } catch (const std::invalid_argument& e) {
    throw JsonError(fmt::format("{}: {}", doc->file, e.what()));
  }
}

// A Mitsuba XML scene: translated (lib/scene/mitsuba_import.h), then built as any scene. The
// import checks what it writes; an error past it (none expected) is still a MitsubaError.
std::unique_ptr<World> load_mitsuba(const std::string& text, const std::string& file, const std::string& base_dir) {
  const nlohmann::json converted = mitsuba_to_scene_json(text, file, base_dir);
  try {
    return load(JsonDocument::parse(converted.dump(1), file + " (converted from Mitsuba XML)"), base_dir);
  } catch (const MitsubaError&) {
    throw;
  } catch (const JsonError& e) {
    throw MitsubaError(e.what());
  }
}

}  // namespace

AffineTransform parse_transform(const StrictObject& o) {
  if (o.has("matrix")) {
    const auto& m = o.raw("matrix");
    if (!m.is_array() || m.size() != 3) o.fail("matrix", "expected 3 rows of 4 numbers");
    Mat3 a(1.0);
    Vec3 t(0.0);
    for (int r = 0; r < 3; ++r) {
      if (!m[r].is_array() || m[r].size() != 4) o.fail("matrix", fmt::format("row {} is not 4 numbers", r));
      for (int c = 0; c < 4; ++c) {
        if (!m[r][c].is_number()) o.fail("matrix", fmt::format("row {} column {} is not a number", r, c));
        const double v = m[r][c].get<double>();
        if (!std::isfinite(v)) o.fail("matrix", "is not finite");
        if (c < 3)
          a[c][r] = v;  // glm is column-major
        else
          t[r] = v;
      }
    }
    o.finish();
    return AffineTransform(a, t);
  }
  AffineTransform xf;
  if (o.has("scale")) {
    const Vec3 s = o.rgb("scale", Vec3(1.0));
    xf = AffineTransform::scale(s);
  }
  if (o.has("rotate")) {
    const auto& r = o.raw("rotate");
    if (!r.is_array()) o.fail("rotate", "expected an array of [axis_x, axis_y, axis_z, degrees]");
    for (size_t i = 0; i < r.size(); ++i) {
      if (!r[i].is_array() || r[i].size() != 4 || !r[i][0].is_number() || !r[i][1].is_number() ||
          !r[i][2].is_number() || !r[i][3].is_number())
        o.fail("rotate", fmt::format("element {} is not [ax, ay, az, deg]", i));
      const Vec3 axis(r[i][0].get<double>(), r[i][1].get<double>(), r[i][2].get<double>());
      const double deg = r[i][3].get<double>();
      if (!is_finite(axis) || !std::isfinite(deg) || glm::length(axis) == 0)
        o.fail("rotate", fmt::format("element {} has a zero or non-finite axis or angle", i));
      xf = AffineTransform::rotate(deg * kPi / 180.0, axis) * xf;
    }
  }
  if (o.has("translate")) xf = AffineTransform::translate(o.vec3("translate")) * xf;
  o.finish();
  return xf;
}

std::unique_ptr<World> load_world(const std::string& path) {
  std::string text;
  try {
    text = read_file(path);
  } catch (const std::exception& e) {
    throw JsonError(e.what());
  }
  return load_world_from_string(text, path, std::filesystem::path(path).parent_path().string());
}

std::unique_ptr<World> load_world_from_string(const std::string& text, const std::string& name,
                                              const std::string& base_dir) {
  if (is_mitsuba_scene(text)) return load_mitsuba(text, name, base_dir);
  return load(JsonDocument::parse(text, name), base_dir);
}

nlohmann::json scene_json_from_file(const std::string& path) {
  std::string text;
  try {
    text = read_file(path);
  } catch (const std::exception& e) {
    throw JsonError(e.what());
  }
  if (is_mitsuba_scene(text)) {
    const std::filesystem::path parent = std::filesystem::path(path).parent_path();
    return mitsuba_to_scene_json(text, path, parent.empty() ? "." : parent.string());
  }
  return JsonDocument::parse(text, path)->root;
}

}  // namespace tb
