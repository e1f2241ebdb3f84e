// Feature coverage of the checked scenes: every feature the scene format accepts (camera, material,
// microfacet distribution, shape and light types, shading normals inline and from OBJ `vn`, one-
// and two-sided emitters, flipped normals, every transform form, several lights of different kind
// and power in one scene) must appear in a scene that the agreement checks render
// (validate/checks/checked_scenes.h). The vocabularies come from the parser and the BSDF registry,
// so a type added there without a checked scene fails this check.
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "lib/material/bsdf_registry.h"
#include "lib/scene/scene_loader.h"
#include "validate/checks/checked_scenes.h"
#include "validate/registry.h"
#include "validate/render/render_compare.h"

namespace tb {
namespace {

// The features one scene file uses, as "kind:value" strings.
std::set<std::string> scene_features(const std::string& file) {
  std::set<std::string> f;
  const std::string path = scenes_dir() + "/" + file;
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open " + path);
  const nlohmann::json j = nlohmann::json::parse(in);
  if (j.contains("camera")) f.insert("camera:" + j["camera"].value("type", std::string("pinhole")));
  for (const auto& m : j.value("materials", nlohmann::json::array())) {
    const std::string type = m.value("type", std::string());
    f.insert("material:" + type);
    if (type.rfind("rough_", 0) == 0) f.insert("distribution:" + type + "/" + m.value("distribution", std::string("ggx")));
    if (m.value("visible_normals", false)) f.insert("option:visible_normals");
  }
  int emitters = 0;
  std::set<std::string> emitter_kinds;
  std::set<double> powers;
  for (const auto& s : j.value("shapes", nlohmann::json::array())) {
    const std::string type = s.value("type", std::string());
    f.insert("shape:" + type);
    if (s.contains("normals")) f.insert("option:mesh_normals");
    if (type == "obj") {
      std::ifstream obj(scenes_dir() + "/" + s.value("file", std::string()));
      std::string line;
      while (std::getline(obj, line))
        if (line.rfind("vn ", 0) == 0) {
          f.insert("option:obj_vn");
          break;
        }
    }
    if (s.contains("emission")) {
      ++emitters;
      const bool two = s.value("two_sided", false);
      f.insert(two ? "emitter:two_sided" : "emitter:one_sided");
      emitter_kinds.insert("area_" + type);
      double sum = 0;
      for (const auto& c : s["emission"]) sum += c.get<double>();
      powers.insert(sum);
    }
    if (s.value("flip_normal", false)) f.insert("option:flip_normal");
    if (s.contains("transform") && s["transform"].is_object())
      for (auto it = s["transform"].begin(); it != s["transform"].end(); ++it) f.insert("transform:" + it.key());
  }
  for (const auto& l : j.value("lights", nlohmann::json::array())) {
    const std::string type = l.value("type", std::string());
    f.insert("light:" + type);
    ++emitters;
    emitter_kinds.insert(type);
    double sum = 0;
    for (const char* key : {"intensity", "irradiance", "radiance"})
      if (l.contains(key))
        for (const auto& c : l[key]) sum += c.get<double>();
    powers.insert(sum);
  }
  // Light selection matters only when lights differ: three kinds or more, of different power.
  if (emitter_kinds.size() >= 3 && powers.size() >= 3) f.insert("lights:several_kinds_and_powers");
  return f;
}

// Every feature of the format, from the parser's and the registry's vocabularies.
std::vector<std::string> format_features() {
  std::vector<std::string> v;
  for (const auto& t : scene_camera_types()) v.push_back("camera:" + t);
  for (const auto& t : bsdf_names()) {
    v.push_back("material:" + t);
    if (t.rfind("rough_", 0) == 0)
      for (const char* d : {"beckmann", "ggx"}) v.push_back("distribution:" + t + "/" + d);
  }
  for (const auto& t : scene_shape_types()) v.push_back("shape:" + t);
  for (const auto& t : scene_light_types()) v.push_back("light:" + t);
  for (const char* o : {"option:visible_normals", "option:mesh_normals", "option:obj_vn", "option:flip_normal",
                        "emitter:one_sided", "emitter:two_sided", "transform:matrix", "transform:translate",
                        "transform:rotate", "transform:scale", "lights:several_kinds_and_powers"})
    v.push_back(o);
  return v;
}

CheckResult coverage(const std::vector<CheckedScene>& scenes) {
  std::map<std::string, std::vector<std::string>> where;
  for (const auto& sc : scenes)
    for (const auto& f : scene_features(sc.file)) where[f].push_back(sc.key);
  CheckResult res;
  res.statistic_name = "features without a checked scene";
  std::vector<std::string> missing;
  nlohmann::json table = nlohmann::json::object();
  const auto all = format_features();
  for (const auto& f : all) {
    const auto it = where.find(f);
    if (it == where.end()) missing.push_back(f);
    table[f] = it == where.end() ? nlohmann::json::array() : nlohmann::json(it->second);
  }
  res.statistic = static_cast<double>(missing.size());
  res.samples = static_cast<int64_t>(all.size());
  res.passed = missing.empty();
  res.details["features"] = table;
  std::string list;
  for (const auto& m : missing) list += (list.empty() ? "" : ", ") + m;
  res.message = missing.empty() ? fmt::format("all {} features of the scene format appear in the {} checked scenes",
                                              all.size(), scenes.size())
                                : fmt::format("{} of {} features appear in no checked scene: {}", missing.size(),
                                              all.size(), list);
  return res;
}

TB_REGISTER_CHECK({.name = "scene.feature_coverage",
                   .description = "Every feature the scene format accepts appears in a scene the agreement checks render",
                   .kind = CheckKind::kDeterministic,
                   .run = [](const CheckContext&) { return coverage(agreement_scenes()); }});

// Negative control: without features.json the thin lens, the point, spot, directional and
// environment lights and the two-sided emitter are uncovered, and the check must say so.
TB_REGISTER_CHECK({.name = "scene.feature_coverage.negative_control",
                   .description = "The coverage check fails when the scene covering the lights and the thin lens is "
                                  "left out",
                   .kind = CheckKind::kDeterministic,
                   .run = [](const CheckContext&) {
                     std::vector<CheckedScene> fewer;
                     for (const auto& sc : agreement_scenes())
                       if (sc.key != "features") fewer.push_back(sc);
                     CheckResult r = coverage(fewer);
                     r.passed = !r.passed && r.message.find("light:point") != std::string::npos &&
                                r.message.find("camera:thin_lens") != std::string::npos;
                     r.message = (r.passed ? "caught: " : "NOT caught: ") + r.message;
                     return r;
                   }});

}  // namespace
}  // namespace tb
