// Import of Mitsuba XML scenes (lib/scene/mitsuba_import.h, docs/scene.md "Importing Mitsuba
// scenes"), on two hand-written XML versions of shipped scenes against their JSON files:
// scenes/peer/mitsuba-cornell-box.xml (Mitsuba 3 syntax) vs scenes/cornell-box.json and
// scenes/peer/mitsuba-caustic.xml (Mitsuba 0.6 syntax) vs scenes/caustic.json:
//  - the same world: per surface the name, the BSDF's sampled directions, values and weights,
//    the emitter's power and area; ray casts (camera rays and rays from inside the scene) hit
//    the same surface at the same distance, point and geometric normal; the camera's rays; the
//    integrator defaults; all to 1e-9;
//  - the same image: Welch comparison (validate/image_compare.h, the statistic `tb compare`
//    applies; alpha = 0.01 for the whole comparison) of path-traced 24 x 24 renders of each
//    (16 passes of 32 spp), fixed seeds; negative control: the XML with one albedo raised by
//    5% must be rejected at the same alpha;
//  - every element outside the subset is a MitsubaError naming the element, its line and what
//    is unsupported; mutated XML either imports or throws MitsubaError, nothing else.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "lib/core/rng.h"
#include "lib/film/film.h"
#include "lib/registry/integrator_registry.h"
#include "lib/scene/mitsuba_import.h"
#include "lib/scene/scene_loader.h"
#include "validate/image_compare.h"
#include "import_test_render.h"

namespace tb {
namespace {

const std::string kScenes = std::string(TB_SOURCE_DIR) + "/scenes";
const std::string kPeer = kScenes + "/peer";

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string replace_once(std::string s, const std::string& from, const std::string& to) {
  const size_t at = s.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) s.replace(at, from.size(), to);
  return s;
}

void expect_near(const Vec3& a, const Vec3& b, double tol, const std::string& what) {
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(a[k], b[k], tol) << what << " component " << k;
}

// Two BSDFs behave the same: sampled directions, values, weights and densities, and values at
// fixed direction pairs, for several outgoing directions in both hemispheres.
void expect_same_bsdf(const Bsdf& a, const Bsdf& b, const std::string& what) {
  EXPECT_EQ(a.name(), b.name()) << what;
  EXPECT_EQ(a.flags(), b.flags()) << what;
  for (const Vec3 wo : {Vec3(0, 0, 1), glm::normalize(Vec3(0.3, -0.2, 0.9)), glm::normalize(Vec3(-0.7, 0.1, 0.2)),
                        glm::normalize(Vec3(0.2, 0.5, -0.8))}) {
    for (const double uc : {0.1, 0.5, 0.97})
      for (const Vec2 u : {Vec2(0.2, 0.7), Vec2(0.9, 0.1)}) {
        const auto sa = a.sample(wo, uc, u, TransportMode::kRadiance);
        const auto sb = b.sample(wo, uc, u, TransportMode::kRadiance);
        ASSERT_EQ(sa.has_value(), sb.has_value()) << what;
        if (!sa) continue;
        expect_near(sa->wi, sb->wi, 1e-9, what + " sampled wi");
        expect_near(sa->f, sb->f, 1e-9, what + " sampled f");
        expect_near(sa->weight, sb->weight, 1e-9, what + " sampled weight");
        EXPECT_NEAR(sa->pdf, sb->pdf, 1e-9) << what;
      }
    const Vec3 wi = glm::normalize(Vec3(-0.4, 0.3, 0.8));
    expect_near(a.eval(wo, wi, TransportMode::kRadiance), b.eval(wo, wi, TransportMode::kRadiance), 1e-9,
                what + " eval");
  }
}

// The imported world `m` equals the JSON world `j` in everything a render reads.
void expect_same_world(const World& m, const World& j) {
  ASSERT_EQ(m.surface_count(), j.surface_count());
  for (uint32_t i = 0; i < j.surface_count(); ++i) {
    const SurfaceInfo &sm = m.surface(i), &sj = j.surface(i);
    const std::string name = sj.name;
    EXPECT_EQ(sm.name, name);
    ASSERT_EQ(sm.bsdf == nullptr, sj.bsdf == nullptr) << name;
    if (sj.bsdf) expect_same_bsdf(*sm.bsdf, *sj.bsdf, name);
    ASSERT_EQ(sm.emitter == nullptr, sj.emitter == nullptr) << name;
    // Area from the density of uniform area sampling. A mesh's area is summed in float, so
    // between a mesh and an analytic shape (the Cornell walls and light are meshes in the JSON
    // file and rectangles in the XML) they agree to 1e-7 only.
    const double am = 1.0 / m.geometry().sample_area(i, Vec2(0.3, 0.6)).pdf_area;
    const double aj = 1.0 / j.geometry().sample_area(i, Vec2(0.3, 0.6)).pdf_area;
    const bool same_kind = m.geometry().is_mesh(i) == j.geometry().is_mesh(i);
    EXPECT_NEAR(am, aj, (same_kind ? 1e-9 : 1e-7) * aj) << name << " area";
    if (sj.emitter) {
      // An emitter's power and area are summed in float for meshes (the Cornell light is one in
      // the JSON file and an analytic rectangle in the XML): 1e-6 relative there.
      const Rgb pj = sj.emitter->power();
      expect_near(sm.emitter->power(), pj, 1e-6 * std::max({pj.r, pj.g, pj.b}), name + " power");
      EXPECT_NEAR(sm.emitter->area(), sj.emitter->area(), 1e-6 * sj.emitter->area()) << name;
    }
  }
  ASSERT_EQ(m.lights().size(), j.lights().size());
  for (size_t k = 0; k < j.lights().size(); ++k) {
    const Rgb pj = j.lights()[k]->power();
    expect_near(m.lights()[k]->power(), pj, 1e-6 * std::max({pj.r, pj.g, pj.b}), "light power");
  }
  EXPECT_EQ(m.infinite_lights().size(), j.infinite_lights().size());

  // Geometry: camera rays over the image and rays from inside the scene in all directions.
  ASSERT_EQ(m.camera().width(), j.camera().width());
  ASSERT_EQ(m.camera().height(), j.camera().height());
  std::vector<Ray> rays;
  const int w = j.camera().width(), h = j.camera().height();
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) {
      const Vec2 raster((x + 0.37) * w / 16.0, (y + 0.61) * h / 16.0);
      const CameraRay a = m.camera().generate_ray(raster, Vec2(0.5));
      const CameraRay b = j.camera().generate_ray(raster, Vec2(0.5));
      expect_near(a.ray.o, b.ray.o, 1e-9, "camera ray origin");
      expect_near(a.ray.d, b.ray.d, 1e-9, "camera ray direction");
      EXPECT_NEAR(a.weight, b.weight, 1e-9);
      rays.push_back(b.ray);
    }
  Rng rng = Rng::for_sample(2024, 7, 0);
  const SceneSphere s = j.bounds();
  for (int k = 0; k < 512; ++k) {
    Ray r;
    r.o = s.center + 0.3 * s.radius * Vec3(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5);
    const double z = 1 - 2 * rng.uniform(), phi = 2 * kPi * rng.uniform(), rho = std::sqrt(std::max(0.0, 1 - z * z));
    r.d = Vec3(rho * std::cos(phi), rho * std::sin(phi), z);
    rays.push_back(r);
  }
  int hits = 0;
  for (const Ray& r : rays) {
    const auto hm = m.geometry().intersect(r), hj = j.geometry().intersect(r);
    ASSERT_EQ(hm.has_value(), hj.has_value());
    if (!hj) continue;
    ++hits;
    const std::string what = "ray hit on " + j.surface(hj->shape_id).name;
    EXPECT_EQ(hm->shape_id, hj->shape_id) << what;
    EXPECT_NEAR(hm->t, hj->t, 1e-9 * std::max(1.0, hj->t)) << what;
    expect_near(hm->p, hj->p, 1e-9, what + " point");
    expect_near(hm->ng, hj->ng, 1e-9, what + " geometric normal");
  }
  EXPECT_GT(hits, 100);  // of 768 rays; the scenes are open (the Cornell box towards the camera)

  EXPECT_EQ(m.integrator_defaults(), j.integrator_defaults());
}

TEST(MitsubaImport, IsRecognisedByContent) {
  EXPECT_TRUE(is_mitsuba_scene(read_text(kPeer + "/mitsuba-cornell-box.xml")));
  EXPECT_TRUE(is_mitsuba_scene("\xEF\xBB\xBF  \n<scene version=\"3.0.0\"/>"));
  EXPECT_FALSE(is_mitsuba_scene(read_text(kScenes + "/cornell-box.json")));
  EXPECT_FALSE(is_mitsuba_scene(""));
}

TEST(MitsubaImport, CornellBoxIsTheSameWorldAsTheJsonFile) {
  const auto m = load_world(kPeer + "/mitsuba-cornell-box.xml");
  const auto j = load_world(kScenes + "/cornell-box.json");
  expect_same_world(*m, *j);
  EXPECT_EQ(m->integrator_defaults().at("max_depth"), 9);  // Mitsuba's max_depth 10 counts segments
  EXPECT_EQ(m->integrator_defaults().at("spp"), 64);
}

TEST(MitsubaImport, CausticIsTheSameWorldAsTheJsonFile) {
  const auto m = load_world(kPeer + "/mitsuba-caustic.xml");
  const auto j = load_world(kScenes + "/caustic.json");
  expect_same_world(*m, *j);
}

void expect_error(const std::string& text, const std::string& marker, const std::vector<std::string>& what);

// The rest of the subset (disk, cube, obj, a rectangle by matrix, conductors, a dielectric of
// numeric indices, point and constant emitters, the direct integrator, a stratified sampler, a
// diagonal field of view on a 40 x 30 film, the value= forms of Mitsuba 3) against the JSON
// scene written for it.
const char* const kSubsetXml = R"(<scene version="3.0.0">
  <integrator type="direct"/>
  <sensor type="perspective">
    <float name="fov" value="40"/>
    <string name="fov_axis" value="diagonal"/>
    <transform name="to_world"><lookat origin="0, 1, 5" target="0, 0.5, 0" up="0, 1, 0"/></transform>
    <sampler type="stratified"><integer name="sample_count" value="16"/></sampler>
    <film type="hdrfilm"><integer name="width" value="40"/><integer name="height" value="30"/><rfilter type="box"/></film>
  </sensor>
  <bsdf type="twosided" id="mirror"><bsdf type="conductor"/></bsdf>
  <bsdf type="twosided" id="gold">
    <bsdf type="conductor"><rgb name="eta" value="0.2, 0.92, 1.1"/><rgb name="k" value="3.9 2.45 2.14"/></bsdf>
  </bsdf>
  <shape type="disk" id="disk">
    <transform name="to_world"><scale value="0.7"/><rotate x="1" angle="-90"/><translate y="0.01"/></transform>
    <ref id="mirror"/>
  </shape>
  <shape type="cube" id="cube">
    <transform name="to_world"><scale x="0.3" y="0.2" z="0.4"/><rotate value="0 1 0" angle="30"/><translate value="0.8 0.2 0"/></transform>
    <ref name="bsdf" id="gold"/>
  </shape>
  <shape type="obj" id="obj">
    <string name="filename" value="../smooth-sphere.obj"/>
    <transform name="to_world"><scale value="0.5"/><rotate y="1" angle="20"/><translate x="-0.5" y="0.5"/></transform>
    <bsdf type="dielectric"><float name="int_ior" value="1.33"/><float name="ext_ior" value="1"/></bsdf>
  </shape>
  <shape type="rectangle" id="panel">
    <transform name="to_world"><matrix value="2 0 0 0  0 1 0 1  0 0 1 -1  0 0 0 1"/></transform>
    <bsdf type="twosided"><bsdf type="diffuse"/></bsdf>
  </shape>
  <emitter type="point"><point name="position" value="0 2 1"/><rgb name="intensity" value="5, 4, 3"/></emitter>
  <emitter type="constant"><rgb name="radiance" value="0.1, 0.2, 0.3"/></emitter>
</scene>
)";

TEST(MitsubaImport, TheRestOfTheSubsetIsTheSameWorldAsItsJsonEquivalent) {
  // Mitsuba's diagonal field of view: tan(v / 2) = tan(40 deg / 2) * h / sqrt(w^2 + h^2).
  const double vfov = 2 * std::atan(std::tan(20 * kPi / 180) * 30.0 / 50.0) * 180 / kPi;
  const nlohmann::json j = {
      {"camera", {{"type", "pinhole"}, {"position", {0, 1, 5}}, {"look_at", {0, 0.5, 0}}, {"up", {0, 1, 0}},
                  {"fov", vfov}, {"resolution", {40, 30}}}},
      {"materials",
       {{{"name", "mirror"}, {"type", "smooth_conductor"}, {"eta", {0, 0, 0}}, {"k", {1, 1, 1}}},
        {{"name", "gold"}, {"type", "smooth_conductor"}, {"eta", {0.2, 0.92, 1.1}}, {"k", {3.9, 2.45, 2.14}}},
        {{"name", "water"}, {"type", "smooth_dielectric"}, {"eta", 1.33}},
        {{"name", "white"}, {"type", "lambert"}, {"reflectance", 0.5}}}},
      {"shapes",
       {{{"name", "disk"}, {"type", "disk"}, {"radius", 0.7}, {"material", "mirror"},
         {"transform", {{"rotate", {{1, 0, 0, -90}}}, {"translate", {0, 0.01, 0}}}}},
        {{"name", "cube"}, {"type", "cube"}, {"material", "gold"},
         {"transform", {{"scale", {0.6, 0.4, 0.8}}, {"rotate", {{0, 1, 0, 30}}}, {"translate", {0.8, 0.2, 0}}}}},
        {{"name", "obj"}, {"type", "obj"}, {"file", "smooth-sphere.obj"}, {"material", "water"},
         {"transform", {{"scale", 0.5}, {"rotate", {{0, 1, 0, 20}}}, {"translate", {-0.5, 0.5, 0}}}}},
        {{"name", "panel"}, {"type", "rectangle"}, {"half_size", {1, 1}}, {"material", "white"},
         {"transform", {{"matrix", {{2, 0, 0, 0}, {0, 1, 0, 1}, {0, 0, 1, -1}}}}}}}},
      {"lights",
       {{{"type", "point"}, {"position", {0, 2, 1}}, {"intensity", {5, 4, 3}}},
        {{"type", "environment"}, {"radiance", {0.1, 0.2, 0.3}}}}},
      {"integrator", {{"max_depth", 1}, {"spp", 16}}}};
  const auto m = load_world_from_string(kSubsetXml, "subset.xml", kPeer);
  const auto o = load_world_from_string(j.dump(1), "subset.json", kScenes);
  expect_same_world(*m, *o);
  ASSERT_TRUE(m->geometry().is_mesh(2));
  EXPECT_TRUE(m->geometry().mesh(2).has_normals());  // the OBJ's vn
  const auto& pm = m->geometry().mesh(2).positions();
  const auto& po = o->geometry().mesh(2).positions();
  ASSERT_EQ(pm.size(), po.size());
  for (size_t k = 0; k < pm.size(); ++k) expect_near(pm[k], po[k], 1e-12, "obj vertex");

  // face_normals with an OBJ that has vn, and a missing OBJ file, are errors on their lines.
  const std::string xml = kSubsetXml;
  expect_error(replace_once(xml, "<string name=\"filename\" value=\"../smooth-sphere.obj\"/>",
                            "<string name=\"filename\" value=\"../smooth-sphere.obj\"/><boolean name=\"face_normals\" value=\"true\"/>"),
               "face_normals", {"face_normals with an OBJ that has vertex normals"});
  expect_error(replace_once(xml, "../smooth-sphere.obj", "../no-such.obj"), "no-such.obj", {"mesh file not found"});
  // A sheared rectangle (Mitsuba 3 rejects it too).
  expect_error(replace_once(xml, "<matrix value=\"2 0 0 0  0 1 0 1", "<matrix value=\"2 0.5 0 0  0 1 0 1"), "<transform name=\"to_world\"><matrix value=\"2 0.5",
               {"must not shear"});
}

WelchImage render_pt(const World& w, uint64_t seed) { return test::render_pt_for_import_test(w, seed); }

constexpr int kRes = 24;

std::unique_ptr<World> small(nlohmann::json j, const std::string& name) {
  j["camera"]["resolution"] = {kRes, kRes};
  return load_world_from_string(j.dump(1), name, kScenes);
}

std::unique_ptr<World> small_xml(const std::string& text) {
  return small(mitsuba_to_scene_json(text, "scene.xml", kPeer), "scene.xml (converted)");
}

void expect_same_image_and_control(const std::string& xml_file, const std::string& json_file, const std::string& from,
                                   const std::string& to) {
  constexpr double kAlpha = 0.01;
  const std::string xml = read_text(kPeer + "/" + xml_file);
  const WelchImage imported = render_pt(*small_xml(xml), 11);
  const WelchImage ours = render_pt(*small(scene_json_from_file(kScenes + "/" + json_file), json_file), 12);
  const ImageCompareResult same = compare_welch_images(imported, ours, kAlpha);
  EXPECT_FALSE(same.rejects()) << same.message();
  EXPECT_GT(same.tested, kRes * kRes);
  // Negative control: one albedo +5%.
  const WelchImage changed = render_pt(*small_xml(replace_once(xml, from, to)), 11);
  const ImageCompareResult diff = compare_welch_images(changed, ours, kAlpha);
  EXPECT_TRUE(diff.rejects()) << diff.message();
  std::cout << xml_file << " vs " << json_file << ": p = " << same.p_value() << " (tested " << same.tested
            << "); +5% albedo: p = " << diff.p_value() << "\n";
}

TEST(MitsubaImport, CornellBoxRendersTheSameImageAndAFivePercentAlbedoChangeIsRejected) {
  // The left wall's red 0.63 -> 0.6615.
  expect_same_image_and_control("mitsuba-cornell-box.xml", "cornell-box.json", "0.63, 0.065, 0.05",
                                "0.6615, 0.065, 0.05");
}

TEST(MitsubaImport, CausticRendersTheSameImageAndAFivePercentAlbedoChangeIsRejected) {
  // The floor's 0.8 -> 0.84.
  expect_same_image_and_control("mitsuba-caustic.xml", "caustic.json", "0.8, 0.8, 0.8", "0.84, 0.84, 0.84");
}

// The error for a modified scene; its message must start "scene.xml:LINE: " with LINE the line
// of the first occurrence of `marker` in the text, and contain every string of `what`.
void expect_error(const std::string& text, const std::string& marker, const std::vector<std::string>& what) {
  std::string msg = "(no error)";
  try {
    mitsuba_to_scene_json(text, "scene.xml", kPeer);
  } catch (const MitsubaError& e) {
    msg = e.what();
  }
  const size_t at = text.find(marker);
  ASSERT_NE(at, std::string::npos) << marker;
  const int line = 1 + int(std::count(text.begin(), text.begin() + ptrdiff_t(at), '\n'));
  EXPECT_EQ(msg.rfind("scene.xml:" + std::to_string(line) + ": ", 0), 0u) << msg << " (expected line " << line << ")";
  for (const auto& w : what) EXPECT_NE(msg.find(w), std::string::npos) << msg << " (expected '" << w << "')";
}

TEST(MitsubaImport, UnsupportedElementsAreErrorsNamingElementLineAndWhat) {
  const std::string base = read_text(kPeer + "/mitsuba-cornell-box.xml");
  {
    const std::string t = replace_once(base, "<shape type=\"cube\" id=\"shortBox\">",
                                       "<volume type=\"grid\"/>\n    <shape type=\"cube\" id=\"shortBox\">");
    expect_error(t, "<volume", {"<volume type=\"grid\">", "not supported"});
  }
  {
    const std::string t = replace_once(base, "<shape type=\"cube\" id=\"shortBox\">",
                                       "<banana/>\n    <shape type=\"cube\" id=\"shortBox\">");
    expect_error(t, "<banana", {"unknown element <banana>"});
  }
  {
    const std::string t = replace_once(base, "<bsdf type=\"twosided\" id=\"mat-floor\">\n        <bsdf type=\"diffuse\">",
                                       "<bsdf type=\"twosided\" id=\"mat-floor\">\n        <bsdf type=\"plastic\">");
    expect_error(t, "<bsdf type=\"plastic\"", {"<bsdf type=\"plastic\">", "unsupported BSDF type 'plastic'"});
  }
  {
    const std::string t = replace_once(base, "<bsdf type=\"twosided\" id=\"mat-floor\">\n        <bsdf type=\"diffuse\">",
                                       "<bsdf type=\"twosided\" id=\"mat-floor\">\n        <bsdf type=\"roughconductor\">");
    expect_error(t, "<bsdf type=\"roughconductor\"", {"unsupported BSDF type 'roughconductor'", "shadowing"});
  }
  {
    const std::string t = replace_once(base, "<rgb name=\"reflectance\" value=\"0.14, 0.45, 0.091\"/>",
                                       "<rgb name=\"reflectance\" value=\"0.14, 0.45, 0.091\" intent=\"srgb\"/>");
    expect_error(t, "intent=", {"<rgb name=\"reflectance\">", "attribute 'intent' is not supported"});
  }
  {
    const std::string t = replace_once(base, "<float name=\"fov\" value=\"19.5\"/>", "<float name=\"fov\" value=\"nan\"/>");
    expect_error(t, "value=\"nan\"", {"<float name=\"fov\">", "not finite"});
  }
  {
    const std::string t = replace_once(base, "<float name=\"fov\" value=\"19.5\"/>", "<float name=\"fov\" value=\"19.5x\"/>");
    expect_error(t, "19.5x", {"'19.5x' is not a number"});
  }
  {
    const std::string t = replace_once(base, "<float name=\"fov\" value=\"19.5\"/>",
                                       "<float name=\"fov\" value=\"19.5\"/>\n        <float name=\"near_clip\" value=\"0.1\"/>");
    expect_error(t, "near_clip", {"parameter 'near_clip' of a perspective sensor is not supported", "supported: fov"});
  }
  {
    const std::string t = replace_once(base, "<rfilter type=\"box\"/>", "<rfilter type=\"gaussian\"/>");
    expect_error(t, "<rfilter", {"unsupported reconstruction filter 'gaussian'"});
  }
  {
    const std::string t = replace_once(base, "<bsdf type=\"twosided\" id=\"mat-leftWall\">\n        <bsdf type=\"diffuse\">\n            <rgb name=\"reflectance\" value=\"0.63, 0.065, 0.05\"/>\n        </bsdf>\n    </bsdf>",
                                       "<bsdf type=\"diffuse\" id=\"mat-leftWall\">\n            <rgb name=\"reflectance\" value=\"0.63, 0.065, 0.05\"/>\n    </bsdf>");
    expect_error(t, "<bsdf type=\"diffuse\" id=\"mat-leftWall\"", {"black from behind", "twosided"});
  }
  {
    const std::string t = replace_once(base, "<integer name=\"max_depth\" value=\"10\"/>", "<integer name=\"max_depth\" value=\"-1\"/>");
    expect_error(t, "value=\"-1\"", {"unbounded"});
  }
  {
    const std::string t = replace_once(base, "<ref id=\"mat-ceiling\"/>", "<ref id=\"mat-marble\"/>");
    expect_error(t, "mat-marble", {"no top-level <bsdf> with id 'mat-marble'"});
  }
  {
    const std::string t = replace_once(base, "<rotate x=\"1\" angle=\"-90\"/>", "<shear x=\"1\"/>");
    expect_error(t, "<shear", {"unknown transform operation <shear>"});
  }
  {
    const std::string t = replace_once(base, "<shape type=\"rectangle\" id=\"floor\">", "<shape type=\"rectangle\" id=\"floor\" bump=\"yes\">");
    expect_error(t, "bump=", {"attribute 'bump' is not supported on <shape>"});
  }
  {
    const std::string t = replace_once(base, "<emitter type=\"area\">", "<emitter type=\"area\"");
    // pugixml stops at the '<' of the next line, inside the unterminated tag.
    expect_error(t, "<rgb name=\"radiance\"", {"XML syntax error"});
  }
  {
    const std::string t = replace_once(base, "<shape type=\"cube\" id=\"tallBox\">", "<shape type=\"cylinder\" id=\"tallBox\">");
    expect_error(t, "<shape type=\"cylinder\"", {"unsupported shape type 'cylinder'"});
  }
}

TEST(MitsubaImport, ErrorsAreReportedThroughLoadWorld) {
  const std::string bad = "<scene version=\"3.0.0\">\n  <shape type=\"rectangle\">\n    <bsdf type=\"plastic\"/>\n  </shape>\n</scene>\n";
  try {
    load_world_from_string(bad, "bad.xml", kPeer);
    FAIL() << "no error";
  } catch (const MitsubaError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("bad.xml:3: <bsdf type=\"plastic\">: unsupported BSDF type", 0), 0u) << e.what();
  }
}

// Mutated XML (bytes flipped, deleted, duplicated, inserted; tags and numbers swapped): every
// variant either imports or is a MitsubaError with a message; no other exception, no crash.
TEST(MitsubaImport, MutatedScenesImportOrThrowTheImportersError) {
  const std::vector<std::string> seeds = {read_text(kPeer + "/mitsuba-cornell-box.xml"),
                                          read_text(kPeer + "/mitsuba-caustic.xml")};
  const std::vector<std::string> tokens = {"<", ">", "/>", "\"", "=", " ", "nan", "inf", "-1", "0", "1e308", "1e-320",
                                           "<ref id=\"mat-floor\"/>", "<transform name=\"to_world\">", "</bsdf>",
                                           "<bsdf type=\"twosided\">", "name=\"radius\"", "value=\"0 0 0\"", "&amp;",
                                           "<!--", "-->", "<![CDATA[x]]>", "version=\"0.6.0\""};
  Rng rng = Rng::for_sample(99, 1, 0);
  constexpr int kMutants = 1500;
  int imported = 0, rejected = 0;
  for (int k = 0; k < kMutants; ++k) {
    std::string t = seeds[size_t(k) % seeds.size()];
    const int edits = 1 + int(rng.uniform() * 4);
    for (int e = 0; e < edits; ++e) {
      // Position 0 ('<') is kept, so every mutant is recognised as XML.
      const size_t pos = 1 + size_t(rng.uniform() * double(t.size() - 1));
      const double kind = rng.uniform();
      if (kind < 0.25) {
        t[pos] = char(32 + int(rng.uniform() * 95));
      } else if (kind < 0.45) {
        t.erase(pos, std::min(t.size() - pos, size_t(1 + rng.uniform() * 40)));
      } else if (kind < 0.65) {
        const size_t len = std::min(t.size() - pos, size_t(1 + rng.uniform() * 200));
        const size_t to = 1 + size_t(rng.uniform() * double(t.size() - 1));
        t.insert(to, t.substr(pos, len));
      } else {
        t.insert(pos, tokens[size_t(rng.uniform() * double(tokens.size())) % tokens.size()]);
      }
      if (t.size() < 2) t = "<x";
    }
    try {
      const auto w = load_world_from_string(t, "mutant.xml", kPeer);
      EXPECT_NE(w, nullptr);
      ++imported;
    } catch (const MitsubaError& e) {
      EXPECT_GT(std::string(e.what()).size(), 12u);
      ++rejected;
    } catch (const std::exception& e) {
      ADD_FAILURE() << "mutant " << k << " threw another exception: " << e.what() << "\n" << t;
    }
  }
  std::cout << kMutants << " mutants: " << imported << " imported, " << rejected << " rejected\n";
  EXPECT_GT(imported, 0);
  EXPECT_GT(rejected, kMutants / 2);
}

}  // namespace
}  // namespace tb
