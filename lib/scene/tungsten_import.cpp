#include "lib/scene/tungsten_import.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "lib/core/math.h"

namespace tb {

namespace {

using nlohmann::json;

// A value of the Tungsten document with its JSON pointer (for the line) and its path as written
// in messages: primitives[3].bsdf.type.
struct Node {
  const JsonDocument* doc;
  std::string pointer, path;
  const json* v;

  static std::string escape(const std::string& key) {
    std::string out;
    for (char c : key) {
      if (c == '~')
        out += "~0";
      else if (c == '/')
        out += "~1";
      else
        out += c;
    }
    return out;
  }
  bool has(const std::string& key) const { return v->is_object() && v->contains(key); }
  Node at(const std::string& key) const {
    return {doc, pointer + "/" + escape(key), path.empty() ? key : path + "." + key, &v->at(key)};
  }
  Node at(size_t i) const { return {doc, pointer + "/" + std::to_string(i), fmt::format("{}[{}]", path, i), &v->at(i)}; }
  // "file:line: path = value: what"
  [[noreturn]] void fail(const std::string& what) const {
    std::string shown = v->dump();
    if (shown.size() > 60) shown = shown.substr(0, 57) + "...";
    throw JsonError(fmt::format("{}: {} = {}: {}", doc->where(pointer), path.empty() ? "(top level)" : path, shown,
                                what));
  }
  // A missing key of this object.
  [[noreturn]] void missing(const std::string& key, const std::string& what) const {
    throw JsonError(fmt::format("{}: {}: missing key '{}' ({})", doc->where(pointer),
                                path.empty() ? "(top level)" : path, key, what));
  }
  Node require(const std::string& key, const std::string& what) const {
    if (!has(key)) missing(key, what);
    return at(key);
  }
  const json::object_t& object(const std::string& what) const {
    if (!v->is_object()) fail(fmt::format("expected an object ({})", what));
    return v->get_ref<const json::object_t&>();
  }
  // Every key must be one of `supported`.
  void only(const std::vector<std::string>& supported, const std::string& what) const {
    for (const auto& [k, _] : object(what))
      if (std::find(supported.begin(), supported.end(), k) == supported.end())
        at(k).fail(fmt::format("'{}' of a {} is not supported by the Tungsten import (supported: {})", k, what,
                               fmt::join(supported, ", ")));
  }
  double number() const {
    if (!v->is_number()) fail("expected a number");
    const double x = v->get<double>();
    if (!std::isfinite(x)) fail("number is not finite");
    return x;
  }
  int64_t integer() const {
    if (!v->is_number_integer()) fail("expected an integer");
    return v->get<int64_t>();
  }
  bool boolean() const {
    if (!v->is_boolean()) fail("expected true or false");
    return v->get<bool>();
  }
  std::string string() const {
    if (!v->is_string()) fail("expected a string");
    return v->get<std::string>();
  }
  // A number (broadcast) or an array of three numbers; textures (strings, objects) are not supported.
  std::array<double, 3> vec3(const std::string& what) const {
    if (v->is_number()) {
      const double x = number();
      return {x, x, x};
    }
    if (!v->is_array() || v->size() != 3)
      fail(fmt::format("expected a number or an array of 3 numbers ({}; textures are not supported)", what));
    return {at(0).number(), at(1).number(), at(2).number()};
  }
};

using M34 = std::array<std::array<double, 4>, 3>;  // rows of [A | t]

// Tungsten's rotYXZ, row by row (rotation in degrees about x, y, z).
std::array<std::array<double, 3>, 3> rot_yxz(const std::array<double, 3>& deg) {
  double c[3], s[3];
  for (int i = 0; i < 3; ++i) {
    const double r = deg[size_t(i)] * kPi / 180.0;
    c[i] = std::cos(r);
    s[i] = std::sin(r);
  }
  return {{{c[1] * c[2] - s[1] * s[0] * s[2], -c[1] * s[2] - s[1] * s[0] * c[2], -s[1] * c[0]},
           {c[0] * s[2], c[0] * c[2], -s[0]},
           {s[1] * c[2] + c[1] * s[0] * s[2], -s[1] * s[2] + c[1] * s[0] * c[2], c[1] * c[0]}}};
}

// A primitive's transform: translate(position) * rotYXZ(rotation) * scale(scale).
M34 parse_transform(const Node& t) {
  t.only({"position", "rotation", "scale"}, "primitive transform");
  std::array<double, 3> pos{0, 0, 0}, rot{0, 0, 0}, scale{1, 1, 1};
  if (t.has("position")) pos = t.at("position").vec3("position");
  if (t.has("rotation")) rot = t.at("rotation").vec3("rotation in degrees");
  if (t.has("scale")) scale = t.at("scale").vec3("scale");
  const auto r = rot_yxz(rot);
  M34 m{};
  for (size_t i = 0; i < 3; ++i) {
    for (size_t j = 0; j < 3; ++j) m[i][j] = r[i][j] * scale[j];
    m[i][3] = pos[i];
  }
  return m;
}

std::array<double, 3> transform_point(const M34& m, const std::array<double, 3>& p) {
  std::array<double, 3> q{};
  for (size_t i = 0; i < 3; ++i) q[i] = m[i][0] * p[0] + m[i][1] * p[1] + m[i][2] * p[2] + m[i][3];
  return q;
}

double det3(const M34& m) {
  return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
         m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

json rgb_json(const std::array<double, 3>& c) { return json::array({c[0], c[1], c[2]}); }

struct Material {
  bool is_null = false;
  std::string name;  // in the converted document
};

// One Tungsten BSDF; adds a lambert to `materials` under `name`.
Material parse_bsdf(const Node& b, const std::string& name, json& materials) {
  b.object("bsdf");
  const Node type = b.require("type", "the BSDF type");
  const std::string t = type.string();
  if (t == "lambert") {
    b.only({"name", "type", "albedo"}, "lambert bsdf");
    const auto albedo = b.require("albedo", "the lambert albedo").vec3("albedo");
    for (size_t c = 0; c < 3; ++c)
      if (albedo[c] < 0 || albedo[c] > 1) b.at("albedo").fail("albedo components must lie in [0, 1]");
    materials.push_back({{"name", name}, {"type", "lambert"}, {"reflectance", rgb_json(albedo)}});
    return {false, name};
  }
  if (t == "null") {
    // Tungsten's null BSDF scatters nothing: a path ends there. Its albedo has no effect.
    b.only({"name", "type", "albedo"}, "null bsdf");
    if (b.has("albedo")) b.at("albedo").vec3("albedo");
    return {true, ""};
  }
  type.fail("unsupported Tungsten bsdf type (supported: lambert, null)");
}

}  // namespace

bool is_tungsten_scene(const json& root) {
  if (!root.is_object() || root.contains("shapes") || root.contains("materials")) return false;
  return root.contains("primitives") || root.contains("bsdfs") || root.contains("renderer");
}

json tungsten_to_scene_json(const JsonDocument& doc) {
  const Node root{&doc, "", "", &doc.root};
  root.only({"media", "bsdfs", "primitives", "camera", "integrator", "renderer"}, "Tungsten scene");
  json out = json::object();
  out["description"] = "Imported from the Tungsten scene " + doc.file + " (docs/scene.md, 'Importing Tungsten scenes')";
  json materials = json::array(), shapes = json::array();

  if (root.has("media")) {
    const Node media = root.at("media");
    if (!media.v->is_array()) media.fail("expected an array");
    if (!media.v->empty()) media.at(0).fail("participating media are not supported by the Tungsten import");
  }

  // BSDFs by name.
  std::map<std::string, Material> bsdfs;
  if (root.has("bsdfs")) {
    const Node list = root.at("bsdfs");
    if (!list.v->is_array()) list.fail("expected an array of bsdfs");
    for (size_t i = 0; i < list.v->size(); ++i) {
      const Node b = list.at(i);
      b.object("bsdf");
      const std::string name = b.require("name", "bsdfs listed at the top level are referenced by name").string();
      if (bsdfs.count(name)) b.at("name").fail("a bsdf of this name is already defined");
      bsdfs[name] = parse_bsdf(b, name, materials);
    }
  }

  const Node prims = root.require("primitives", "a scene needs at least one primitive");
  if (!prims.v->is_array() || prims.v->empty()) prims.fail("expected a non-empty array of primitives");
  std::set<std::string> used_names;
  for (size_t i = 0; i < prims.v->size(); ++i) {
    const Node p = prims.at(i);
    p.object("primitive");
    const Node type = p.require("type", "the primitive type");
    const std::string t = type.string();
    if (t != "quad" && t != "cube") type.fail("unsupported Tungsten primitive type (supported: quad, cube)");
    p.only({"name", "type", "transform", "bsdf", "emission"}, t + " primitive");
    const std::string label = fmt::format("primitives[{}]", i);
    std::string name = p.has("name") ? p.at("name").string() : label;
    if (!used_names.insert(name).second) name = label;  // shape names need not be unique; keep them telling

    Material mat;
    const Node bsdf = p.require("bsdf", "the primitive's bsdf");
    if (bsdf.v->is_string()) {
      const auto it = bsdfs.find(bsdf.string());
      if (it == bsdfs.end()) bsdf.fail("no bsdf of this name in 'bsdfs'");
      mat = it->second;
    } else if (bsdf.v->is_object()) {
      mat = parse_bsdf(bsdf, label + ".bsdf", materials);
    } else {
      bsdf.fail("expected the name of a bsdf or a bsdf object");
    }

    std::array<double, 3> emission{0, 0, 0};
    bool emissive = false;
    if (p.has("emission")) {
      const Node e = p.at("emission");
      emission = e.vec3("emitted radiance");
      for (double c : emission)
        if (c < 0) e.fail("emission must be non-negative");
      emissive = emission[0] > 0 || emission[1] > 0 || emission[2] > 0;
      if (t != "quad") e.fail("emission is supported on quads only by the Tungsten import");
    }
    if (mat.is_null && !emissive)
      bsdf.fail("a null bsdf on a primitive without emission (an invisible occluder) is not supported");

    M34 m{};
    for (size_t r = 0; r < 3; ++r) m[r][r] = 1.0;
    if (p.has("transform")) m = parse_transform(p.at("transform"));
    const Node where = p.has("transform") ? p.at("transform") : p;

    json s = json::object();
    s["name"] = name;
    if (!mat.is_null) s["material"] = mat.name;
    if (emissive) s["emission"] = rgb_json(emission);
    if (t == "quad") {
      // The unit square [-1/2, 1/2]^2 in the xz plane. Wound so that its geometric normal is
      // (M e_z) x (M e_x): the transformed +y axis for rotations with positive scales, the side
      // an emissive quad emits from.
      const std::array<std::array<double, 3>, 4> corners = {
          {{-0.5, 0, -0.5}, {-0.5, 0, 0.5}, {0.5, 0, 0.5}, {0.5, 0, -0.5}}};
      json pos = json::array();
      for (const auto& c : corners) {
        const auto q = transform_point(m, c);
        pos.push_back(rgb_json(q));
      }
      // Edges M e_x and M e_z must span a parallelogram of positive area.
      const double ex[3] = {m[0][0], m[1][0], m[2][0]}, ez[3] = {m[0][2], m[1][2], m[2][2]};
      const double cx = ez[1] * ex[2] - ez[2] * ex[1], cy = ez[2] * ex[0] - ez[0] * ex[2],
                   cz = ez[0] * ex[1] - ez[1] * ex[0];
      const double area = std::sqrt(cx * cx + cy * cy + cz * cz);
      const double scale = std::sqrt(ex[0] * ex[0] + ex[1] * ex[1] + ex[2] * ex[2]) *
                           std::sqrt(ez[0] * ez[0] + ez[1] * ez[1] + ez[2] * ez[2]);
      if (!(area > 1e-12 * std::max(1.0, scale))) where.fail("degenerate quad (zero x or z scale)");
      s["type"] = "mesh";
      s["positions"] = pos;
      s["triangles"] = json::array({json::array({0, 1, 2}), json::array({0, 2, 3})});
    } else {
      if (!(std::abs(det3(m)) > 1e-12)) where.fail("singular transform (zero scale) of a cube");
      json rows = json::array();
      for (const auto& r : m) rows.push_back(json::array({r[0], r[1], r[2], r[3]}));
      s["type"] = "cube";
      s["transform"] = {{"matrix", rows}};
    }
    shapes.push_back(s);
  }

  // Camera.
  const Node cam = root.require("camera", "the camera");
  cam.only({"type", "resolution", "fov", "transform", "tonemap", "reconstruction_filter"}, "camera");
  const Node ctype = cam.require("type", "the camera type");
  if (ctype.string() != "pinhole") ctype.fail("unsupported Tungsten camera type (supported: pinhole)");
  const Node filter = cam.require("reconstruction_filter", "the importer maps only an explicit \"box\" filter");
  if (filter.string() != "box")
    filter.fail("unsupported reconstruction filter (supported: box, the pixel-area box of this project's film)");
  if (cam.has("tonemap")) cam.at("tonemap").string();  // affects Tungsten's LDR output only
  const Node res = cam.require("resolution", "the image size");
  int64_t w = 0, h = 0;
  if (res.v->is_number()) {
    w = h = res.integer();
  } else if (res.v->is_array() && res.v->size() == 2) {
    w = res.at(0).integer();
    h = res.at(1).integer();
  } else {
    res.fail("expected an integer or [width, height]");
  }
  if (w < 1 || h < 1 || w > 16384 || h > 16384) res.fail("width and height must lie in [1, 16384]");
  const Node fov = cam.require("fov", "the horizontal field of view in degrees");
  const double hfov = fov.number();
  if (!(hfov > 0 && hfov < 180)) fov.fail("the field of view must lie in (0, 180) degrees");
  // Tungsten's fov is horizontal; this project's is vertical.
  const double vfov =
      2.0 * std::atan(std::tan(0.5 * hfov * kPi / 180.0) * double(h) / double(w)) * 180.0 / kPi;
  const Node ct = cam.require("transform", "the camera placement");
  ct.only({"position", "look_at", "up"}, "camera transform");
  const auto eye = ct.require("position", "the eye").vec3("position");
  const auto target = ct.require("look_at", "the target").vec3("look_at");
  const auto up = ct.has("up") ? ct.at("up").vec3("up") : std::array<double, 3>{0, 1, 0};
  const double d[3] = {target[0] - eye[0], target[1] - eye[1], target[2] - eye[2]};
  const double dl = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  const double ul = std::sqrt(up[0] * up[0] + up[1] * up[1] + up[2] * up[2]);
  if (!(dl > 0)) ct.at("look_at").fail("look_at equals position: no viewing direction");
  const double cr[3] = {d[1] * up[2] - d[2] * up[1], d[2] * up[0] - d[0] * up[2], d[0] * up[1] - d[1] * up[0]};
  if (!(std::sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]) > 1e-9 * dl * ul))
    (ct.has("up") ? ct.at("up") : ct).fail("up is zero or parallel to the viewing direction");
  json camera = {{"type", "pinhole"},
                 {"position", rgb_json(eye)},
                 {"look_at", rgb_json(target)},
                 {"up", rgb_json(up)},
                 {"fov", vfov},
                 {"resolution", json::array({w, h})}};
  out["camera"] = camera;

  // Integrator.
  json integ = json::object();
  const Node in = root.require("integrator", "the integrator (max_bounces)");
  in.only({"type", "min_bounces", "max_bounces", "enable_consistency_checks", "enable_two_sided_shading",
           "enable_light_sampling", "enable_volume_light_sampling"},
          "integrator");
  const Node itype = in.require("type", "the integrator type");
  if (itype.string() != "path_tracer") itype.fail("unsupported Tungsten integrator (supported: path_tracer)");
  if (in.has("min_bounces") && in.at("min_bounces").integer() != 0)
    in.at("min_bounces").fail("only min_bounces = 0 is supported (every path length contributes)");
  const Node maxb = in.require("max_bounces", "the importer does not assume Tungsten's default");
  const int64_t mb = maxb.integer();
  // Tungsten counts path segments, this project scattering events: max_depth = max_bounces - 1.
  if (mb < 2) maxb.fail("max_bounces must be at least 2 (max_depth = max_bounces - 1 >= 1)");
  integ["max_depth"] = mb - 1;
  const Node two = in.require("enable_two_sided_shading", "this project shades two-sided; the file must say so");
  if (!two.boolean()) two.fail("one-sided shading is not supported (this project shades non-transmissive surfaces two-sided)");
  // Light sampling and consistency checks change the variance, not the expected image.
  for (const char* k : {"enable_consistency_checks", "enable_light_sampling", "enable_volume_light_sampling"})
    if (in.has(k)) in.at(k).boolean();

  if (root.has("renderer")) {
    const Node r = root.at("renderer");
    r.only({"spp", "adaptive_sampling", "resume_render_file", "overwrite_output_files", "enable_resume_render",
            "stratified_sampler", "scene_bvh", "spp_step", "checkpoint_interval", "timeout", "output_buffers",
            "output_file", "hdr_output_file"},
           "renderer");
    if (r.has("spp")) {
      const int64_t spp = r.at("spp").integer();
      if (spp < 1) r.at("spp").fail("spp must be at least 1");
      integ["spp"] = spp;
    }
    if (r.has("adaptive_sampling") && r.at("adaptive_sampling").boolean())
      r.at("adaptive_sampling").fail("adaptive sampling is not supported");
  }
  out["integrator"] = integ;
  out["materials"] = materials;
  out["shapes"] = shapes;
  return out;
}

}  // namespace tb
