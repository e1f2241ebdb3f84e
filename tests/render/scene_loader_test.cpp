#include "lib/scene/scene_loader.h"

#include <filesystem>

#include <gtest/gtest.h>

#include "lib/film/film.h"
#include "lib/geometry/ray.h"
#include "lib/integrator/albedo_integrator.h"

namespace tb {
namespace {

std::string error_of(const std::string& text) {
  try {
    load_world_from_string(text, "test.json");
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

const char* kMinimal = R"({
  "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "fov": 30, "resolution": [16, 12]},
  "materials": [{"name": "white", "type": "lambert", "reflectance": 0.5}],
  "shapes": [
    {"type": "sphere", "radius": 1, "material": "white"},
    {"type": "rectangle", "half_size": [0.5, 0.5], "emission": 4,
     "transform": {"translate": [0, 0, 3], "rotate": [[1, 0, 0, 180]]}}
  ]
})";

TEST(SceneLoader, LoadsAMinimalScene) {
  auto w = load_world_from_string(kMinimal);
  EXPECT_EQ(w->surface_count(), 2u);
  EXPECT_EQ(w->lights().size(), 1u);
  EXPECT_TRUE(w->surface(0).bsdf);
  EXPECT_TRUE(w->surface(1).emitter);
  EXPECT_EQ(w->camera().width(), 16);
}

TEST(SceneLoader, TyposWrongTypesAndBadGeometryAreNamedWithTheirLine) {
  std::string s = kMinimal;
  std::string typo = s;
  typo.replace(typo.find("\"radius\": 1"), 11, "\"raduis\": 1");
  const std::string e1 = error_of(typo);
  EXPECT_NE(e1.find("test.json:5"), std::string::npos) << e1;
  EXPECT_NE(e1.find("/shapes/0"), std::string::npos) << e1;

  std::string nan = s;
  nan.replace(nan.find("\"radius\": 1"), 11, "\"radius\": -1");
  EXPECT_NE(error_of(nan).find("must be positive"), std::string::npos) << error_of(nan);

  std::string unknown_mat = s;
  const std::string from = "\"material\": \"white\"}";
  unknown_mat.replace(unknown_mat.find(from), from.size(), "\"material\": \"whte\"}");
  EXPECT_NE(error_of(unknown_mat).find("unknown material 'whte'"), std::string::npos) << error_of(unknown_mat);

  EXPECT_NE(error_of(R"({"camera": {"position": [0,0,5], "look_at": [0,0,0], "fov": 30, "resolution": [4,4]},
    "shapes": [{"type": "mesh", "positions": [[0,0,0],[1,0,0],[2,0,0]], "triangles": [[0,1,2]], "emission": 1}]})")
                .find("degenerate"),
            std::string::npos)
      << error_of(R"({"camera": {"position": [0,0,5], "look_at": [0,0,0], "fov": 30, "resolution": [4,4]},
    "shapes": [{"type": "mesh", "positions": [[0,0,0],[1,0,0],[2,0,0]], "triangles": [[0,1,2]], "emission": 1}]})");
  EXPECT_NE(error_of(R"({"camera": {"position": [0,0,5], "look_at": [0,0,0], "fov": 30, "resolution": [4,4]},
    "shapes": [{"type": "obj", "file": "missing.obj", "emission": 1}]})")
                .find("mesh file not found"),
            std::string::npos);
  EXPECT_NE(error_of("{\"camera\": }").find("JSON syntax error"), std::string::npos);
  EXPECT_NE(error_of(R"({"camera": {"position": [0,0,5], "look_at": [0,0,0], "fov": 30, "resolution": [4,4]},
    "shapes": [{"type": "sphere", "radius": 1, "material": "x"}]})")
                .find("unknown material"),
            std::string::npos);
}

// Every shipped scene loads and renders a primary-hit albedo image without non-finite values.
TEST(SceneLoader, ShippedScenesLoadAndRender) {
  const std::filesystem::path dir = std::filesystem::path(TB_SOURCE_DIR) / "scenes";
  int n = 0;
  for (const auto& f : std::filesystem::directory_iterator(dir)) {
    if (f.path().extension() != ".json") continue;
    SCOPED_TRACE(f.path().string());
    std::unique_ptr<World> w;
    ASSERT_NO_THROW(w = load_world(f.path().string()));
    RenderSettings st;
    st.spp = 2;
    st.passes = 2;
    Film full(w->camera().width(), w->camera().height());
    EXPECT_EQ(render_albedo(*w, st, full), 2);
    EXPECT_EQ(full.nonfinite().count(), 0);
    double sum = 0;
    for (const Rgb& c : full.mean_image()) sum += c.r + c.g + c.b;
    EXPECT_GT(sum, 0.0);
    ++n;
  }
  EXPECT_GE(n, 1);
}

// scenes/smooth-mesh.json: the OBJ sphere's vn and the inline mesh's "normals" are the shading
// normals of the hits. The vertex normals are the exact sphere normals, so the interpolated
// shading normal is closer to the radial direction than the flat facet's geometric normal.
TEST(SceneLoader, SmoothMeshSceneUsesVertexNormals) {
  const auto w = load_world((std::filesystem::path(TB_SOURCE_DIR) / "scenes" / "smooth-mesh.json").string());
  struct Sphere {
    Vec3 centre;
    const char* name;
  };
  for (const Sphere& sp : {Sphere{Vec3(-0.5, 0.5, 0), "obj"}, Sphere{Vec3(0.55, 0.4, 0.25), "inline"}}) {
    SCOPED_TRACE(sp.name);
    int differ = 0;
    for (int i = 0; i < 25; ++i) {
      // Rays from +z at offsets across the sphere's disk (away from the facet centres).
      const Vec3 o = sp.centre + Vec3(0.06 * (i % 5 - 2) + 0.013, 0.06 * (i / 5 - 2) + 0.007, 3.0);
      const auto hit = w->geometry().intersect(Ray{o, Vec3(0, 0, -1)});
      ASSERT_TRUE(hit.has_value());
      const Vec3 radial = glm::normalize(hit->p - sp.centre);
      EXPECT_GE(glm::dot(hit->n, radial), glm::dot(hit->ng, radial) - 1e-12);
      if (1.0 - glm::dot(hit->n, hit->ng) > 1e-4) ++differ;
    }
    EXPECT_GE(differ, 20);
  }
}

}  // namespace
}  // namespace tb
