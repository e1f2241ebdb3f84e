// Import of Tungsten scenes (lib/scene/tungsten_import.h, docs/scene.md "Importing Tungsten
// scenes"), on Tungsten's example Cornell box (scenes/peer/tungsten-cornell-box.json) against its
// hand conversion (scenes/cornell-box.json):
//  - the same world: shape count, per-shape bounding boxes and facing, emitter power, camera
//    rays at several raster positions, all to 1e-9; max_depth = max_bounces - 1;
//  - the same image: Welch comparison (validate/image_compare.h, alpha = 0.01 for the whole
//    comparison) of path-traced 24 x 24 renders of each (16 passes of 32 spp), fixed seeds;
//    negative control: the import with the left wall's red albedo raised by 5% must be
//    rejected at the same alpha;
//  - every element outside the supported subset is an error naming its path, its line and what
//    is unsupported.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "lib/film/film.h"
#include "lib/registry/integrator_registry.h"
#include "lib/scene/scene_loader.h"
#include "lib/scene/tungsten_import.h"
#include "validate/image_compare.h"
#include "import_test_render.h"

namespace tb {
namespace {

const std::string kScenes = std::string(TB_SOURCE_DIR) + "/scenes";
const std::string kTungsten = kScenes + "/peer/tungsten-cornell-box.json";
const std::string kOurs = kScenes + "/cornell-box.json";

nlohmann::json read_json(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return nlohmann::json::parse(ss.str());
}

std::unique_ptr<World> load_json(const nlohmann::json& j, const std::string& name = "t.json") {
  return load_world_from_string(j.dump(1), name, kScenes);
}

struct Box {
  Vec3 lo{kInfinity}, hi{-kInfinity};
};

Box mesh_box(const World& w, uint32_t id) {
  Box b;
  for (const Vec3& p : w.geometry().mesh(id).positions()) {
    b.lo = glm::min(b.lo, p);
    b.hi = glm::max(b.hi, p);
  }
  return b;
}

// Sum over triangles of (v1 - v0) x (v2 - v0) / 2: the area-weighted normal (zero for a closed mesh).
Vec3 area_normal(const World& w, uint32_t id) {
  const TriangleMesh& m = w.geometry().mesh(id);
  Vec3 n(0.0);
  for (const auto& t : m.triangles()) {
    const Vec3 a = m.positions()[t[0]], b = m.positions()[t[1]], c = m.positions()[t[2]];
    n += 0.5 * glm::cross(b - a, c - a);
  }
  return n;
}

void expect_near(const Vec3& a, const Vec3& b, double tol, const std::string& what) {
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(a[k], b[k], tol) << what << " component " << k;
}

TEST(TungstenImport, IsRecognisedByContent) {
  EXPECT_TRUE(is_tungsten_scene(read_json(kTungsten)));
  EXPECT_FALSE(is_tungsten_scene(read_json(kOurs)));
  EXPECT_FALSE(is_tungsten_scene(nlohmann::json::parse(R"({"primitives": [], "shapes": []})")));
}

TEST(TungstenImport, CornellBoxIsTheSameWorldAsItsHandConversion) {
  const auto t = load_world(kTungsten);
  const auto o = load_world(kOurs);
  ASSERT_EQ(t->surface_count(), 8u);
  ASSERT_EQ(t->surface_count(), o->surface_count());
  ASSERT_EQ(t->geometry().shape_count(), o->geometry().shape_count());
  for (uint32_t i = 0; i < t->surface_count(); ++i) {
    const std::string name = o->surface(i).name;
    EXPECT_EQ(t->surface(i).name, name);
    ASSERT_TRUE(t->geometry().is_mesh(i) && o->geometry().is_mesh(i)) << name;
    const Box bt = mesh_box(*t, i), bo = mesh_box(*o, i);
    expect_near(bt.lo, bo.lo, 1e-9, name + " box min");
    expect_near(bt.hi, bo.hi, 1e-9, name + " box max");
    // Quads: the same plane and area; the same facing for the light (its emitting side). Shading
    // is two-sided, so the facing of the other quads does not matter (the import keeps Tungsten's,
    // in which the floor and ceiling face the room and the walls away from it; the hand
    // conversion turned all of them inwards). Cubes are closed (zero).
    const Vec3 nt = area_normal(*t, i), no = area_normal(*o, i);
    if (o->surface(i).emitter)
      expect_near(nt, no, 1e-9, name + " area normal");
    else
      EXPECT_LT(std::min(glm::length(nt - no), glm::length(nt + no)), 1e-9) << name << " area normal up to sign";
    EXPECT_EQ(t->surface(i).bsdf == nullptr, o->surface(i).bsdf == nullptr) << name;
    ASSERT_EQ(t->surface(i).emitter == nullptr, o->surface(i).emitter == nullptr) << name;
    if (o->surface(i).emitter) {
      expect_near(t->surface(i).emitter->power(), o->surface(i).emitter->power(), 1e-9, name + " power");
      EXPECT_NEAR(t->surface(i).emitter->area(), o->surface(i).emitter->area(), 1e-12);
      EXPECT_NEAR(t->surface(i).emitter->area(), 0.47 * 0.38, 1e-7);  // the area is summed in float
    }
  }
  // The light faces down: its emitting side is towards the room.
  const Vec3 nl = area_normal(*t, 7);
  EXPECT_LT(nl.y, -0.17);
  EXPECT_EQ(t->lights().size(), o->lights().size());

  ASSERT_EQ(t->camera().width(), 256);
  ASSERT_EQ(t->camera().height(), 256);
  for (const Vec2 raster : {Vec2(0.5, 0.5), Vec2(128.0, 128.0), Vec2(255.5, 3.25), Vec2(17.75, 200.5), Vec2(0, 256)}) {
    const CameraRay a = t->camera().generate_ray(raster, Vec2(0.5));
    const CameraRay b = o->camera().generate_ray(raster, Vec2(0.5));
    expect_near(a.ray.o, b.ray.o, 1e-9, "ray origin");
    expect_near(a.ray.d, b.ray.d, 1e-9, "ray direction");
    EXPECT_NEAR(a.weight, b.weight, 1e-9);
  }
  // max_bounces 10 (segments) -> max_depth 9 (scattering events); spp from the renderer block.
  EXPECT_EQ(t->integrator_defaults().at("max_depth"), 9);
  EXPECT_EQ(t->integrator_defaults().at("max_depth"), o->integrator_defaults().at("max_depth"));
  EXPECT_EQ(t->integrator_defaults().at("spp"), 4096);
}

WelchImage render_pt(const World& w, uint64_t seed) { return test::render_pt_for_import_test(w, seed); }

TEST(TungstenImport, CornellBoxRendersTheSameImageAndAFivePercentAlbedoChangeIsRejected) {
  constexpr int kRes = 24;
  constexpr double kAlpha = 0.01;
  nlohmann::json tj = read_json(kTungsten), oj = read_json(kOurs);
  tj["camera"]["resolution"] = {kRes, kRes};
  oj["camera"]["resolution"] = {kRes, kRes};
  const WelchImage imported = render_pt(*load_json(tj), 11);
  const WelchImage ours = render_pt(*load_json(oj), 12);
  const ImageCompareResult same = compare_welch_images(imported, ours, kAlpha);
  EXPECT_FALSE(same.rejects()) << same.message();
  EXPECT_GT(same.tested, 3 * kRes * kRes / 2);

  // Negative control: the left wall's albedo red 0.63 -> 0.6615 (+5%).
  ASSERT_EQ(tj["bsdfs"][0]["name"], "leftWall");
  tj["bsdfs"][0]["albedo"][0] = 0.63 * 1.05;
  const WelchImage changed = render_pt(*load_json(tj), 11);
  const ImageCompareResult diff = compare_welch_images(changed, ours, kAlpha);
  EXPECT_TRUE(diff.rejects()) << diff.message();
  std::cout << "same: p = " << same.p_value() << "; +5% albedo: p = " << diff.p_value()
            << "\n" << diff.message() << "\n";
}

// The error for a modified scene, "file:LINE: PATH = VALUE: WHAT", LINE being the line of the
// element at `pointer` in the text the scene was loaded from.
std::string import_error(const nlohmann::json& j) {
  try {
    load_json(j, "bad.json");
  } catch (const JsonError& e) {
    return e.what();
  }
  return "(no error)";
}

void expect_error(const nlohmann::json& j, const std::string& path_and_value, const std::string& what,
                  const std::string& pointer) {
  const std::string msg = import_error(j);
  EXPECT_NE(msg.find(path_and_value), std::string::npos) << msg;
  EXPECT_NE(msg.find(what), std::string::npos) << msg;
  const auto doc = JsonDocument::parse(j.dump(1), "bad.json");
  ASSERT_TRUE(doc->lines.count(pointer)) << pointer;
  const int line = doc->lines.at(pointer);
  EXPECT_GT(line, 1);
  EXPECT_EQ(msg.rfind("bad.json:" + std::to_string(line) + ": ", 0), 0u) << msg << " (expected line " << line << ")";
}

TEST(TungstenImport, UnsupportedElementsAreErrorsNamingPathLineAndWhat) {
  const nlohmann::json base = read_json(kTungsten);
  {
    auto j = base;
    j["primitives"][3]["bsdf"] = {{"type", "plastic"}, {"albedo", 0.5}};
    expect_error(j, "primitives[3].bsdf.type = \"plastic\"", "unsupported Tungsten bsdf type", "/primitives/3/bsdf/type");
  }
  {
    auto j = base;
    j["bsdfs"][2]["type"] = "rough_conductor";
    expect_error(j, "bsdfs[2].type = \"rough_conductor\"", "unsupported Tungsten bsdf type", "/bsdfs/2/type");
  }
  {
    auto j = base;
    j["primitives"][0]["type"] = "sphere";
    expect_error(j, "primitives[0].type = \"sphere\"", "unsupported Tungsten primitive type", "/primitives/0/type");
  }
  {
    auto j = base;
    j["bsdfs"][0]["albedo"] = "wood.png";
    expect_error(j, "bsdfs[0].albedo = \"wood.png\"", "textures are not supported", "/bsdfs/0/albedo");
  }
  {
    auto j = base;
    j["bsdfs"][0]["bump"] = "bump.png";
    expect_error(j, "bsdfs[0].bump = \"bump.png\"", "'bump' of a lambert bsdf is not supported", "/bsdfs/0/bump");
  }
  {
    auto j = base;
    j["primitives"][5]["transform"]["x_axis"] = {1, 0, 0};
    expect_error(j, "primitives[5].transform.x_axis", "is not supported by the Tungsten import", "/primitives/5/transform/x_axis");
  }
  {
    auto j = base;
    j["primitives"][6]["transform"]["scale"] = {0.6, 0.0, 1.2};
    expect_error(j, "primitives[6].transform", "singular transform", "/primitives/6/transform");
  }
  {
    auto j = base;
    j["primitives"][0]["transform"]["scale"] = {0.0, 4, 2};
    expect_error(j, "primitives[0].transform", "degenerate quad", "/primitives/0/transform");
  }
  {
    auto j = base;  // NaN is written as null in JSON: rejected, not read as 0
    j["primitives"][2]["transform"]["position"][1] = std::nan("");
    expect_error(j, "primitives[2].transform.position[1] = null", "expected a number", "/primitives/2/transform/position/1");
  }
  {
    auto j = base;
    j["media"] = {{{"type", "homogeneous"}, {"name", "fog"}}};
    expect_error(j, "media[0]", "participating media are not supported", "/media/0");
  }
  {
    auto j = base;
    j["primitives"][5]["emission"] = {1, 1, 1};
    expect_error(j, "primitives[5].emission", "emission is supported on quads only", "/primitives/5/emission");
  }
  {
    auto j = base;
    j["primitives"][7].erase("emission");
    expect_error(j, "primitives[7].bsdf = \"light\"", "null bsdf on a primitive without emission",
                 "/primitives/7/bsdf");
  }
  {
    auto j = base;
    j["primitives"][1]["bsdf"] = "marble";
    expect_error(j, "primitives[1].bsdf = \"marble\"", "no bsdf of this name", "/primitives/1/bsdf");
  }
  {
    auto j = base;
    j["primitives"][1]["power"] = 10;
    expect_error(j, "primitives[1].power = 10", "is not supported", "/primitives/1/power");
  }
  {
    auto j = base;
    j["camera"]["type"] = "thinlens";
    expect_error(j, "camera.type = \"thinlens\"", "unsupported Tungsten camera type", "/camera/type");
  }
  {
    auto j = base;
    j["camera"]["reconstruction_filter"] = "tent";
    expect_error(j, "camera.reconstruction_filter = \"tent\"", "unsupported reconstruction filter", "/camera/reconstruction_filter");
  }
  {
    auto j = base;
    j["integrator"]["type"] = "bidirectional_path_tracer";
    expect_error(j, "integrator.type = \"bidirectional_path_tracer\"", "unsupported Tungsten integrator",
                 "/integrator/type");
  }
  {
    auto j = base;
    j["integrator"]["enable_two_sided_shading"] = false;
    expect_error(j, "integrator.enable_two_sided_shading = false", "one-sided shading is not supported",
                 "/integrator/enable_two_sided_shading");
  }
  {
    auto j = base;
    j["integrator"]["min_bounces"] = 2;
    expect_error(j, "integrator.min_bounces = 2", "only min_bounces = 0", "/integrator/min_bounces");
  }
  {
    auto j = base;
    j["integrator"]["max_bounces"] = 1;
    expect_error(j, "integrator.max_bounces = 1", "at least 2", "/integrator/max_bounces");
  }
  {
    auto j = base;
    j["renderer"]["adaptive_sampling"] = true;
    expect_error(j, "renderer.adaptive_sampling = true", "adaptive sampling is not supported",
                 "/renderer/adaptive_sampling");
  }
  {
    auto j = base;
    j["integrator"].erase("max_bounces");
    const std::string msg = import_error(j);
    EXPECT_NE(msg.find("integrator: missing key 'max_bounces'"), std::string::npos) << msg;
  }
  {
    auto j = base;
    j["camera"]["transform"]["look_at"] = {0, 1, 6.8};
    expect_error(j, "camera.transform.look_at = [0,1,6.8]", "look_at equals position", "/camera/transform/look_at");
  }
  {
    auto j = base;
    j["camera"]["transform"]["up"] = {0, 0, -2};
    expect_error(j, "camera.transform.up = [0,0,-2]", "parallel to the viewing direction", "/camera/transform/up");
  }
  {
    auto j = base;
    j["camera"]["resolution"] = {0, 256};
    expect_error(j, "camera.resolution = [0,256]", "must lie in [1, 16384]", "/camera/resolution");
  }
  {
    auto j = base;
    j["skybox"] = {{"type", "constant"}};
    expect_error(j, "skybox", "is not supported by the Tungsten import", "/skybox");
  }
}

TEST(TungstenImport, BounceCountAndHorizontalFieldOfViewAreConverted) {
  auto j = read_json(kTungsten);
  j["integrator"]["max_bounces"] = 5;
  j["camera"]["resolution"] = {200, 100};
  j["camera"]["fov"] = 40.0;
  j["primitives"][0]["bsdf"] = {{"type", "lambert"}, {"albedo", 0.25}};  // inline bsdf, scalar albedo
  const auto doc = JsonDocument::parse(j.dump(1), "t.json");
  const nlohmann::json c = tungsten_to_scene_json(*doc);
  EXPECT_EQ(c["integrator"]["max_depth"], 4);
  const double vfov = 2.0 * std::atan(std::tan(20.0 * kPi / 180.0) * 0.5) * 180.0 / kPi;
  EXPECT_NEAR(c["camera"]["fov"].get<double>(), vfov, 1e-12);
  EXPECT_EQ(c["shapes"][0]["material"], "primitives[0].bsdf");
  const auto w = load_json(j);
  EXPECT_EQ(w->camera().width(), 200);
  EXPECT_EQ(w->camera().height(), 100);
  // The horizontal half-angle: the ray through the right edge's middle is 20 degrees off axis.
  const CameraRay r = w->camera().generate_ray(Vec2(200.0, 50.0), Vec2(0.5));
  const CameraRay m = w->camera().generate_ray(Vec2(100.0, 50.0), Vec2(0.5));
  EXPECT_NEAR(std::acos(glm::dot(glm::normalize(r.ray.d), glm::normalize(m.ray.d))) * 180.0 / kPi, 20.0, 1e-9);
}

}  // namespace
}  // namespace tb
