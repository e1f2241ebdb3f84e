#include "lib/core/strict_json.h"

#include <gtest/gtest.h>

namespace tb {
namespace {

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const JsonError& e) {
    return e.what();
  }
  return "";
}

const char* kText = R"({
  "camera": {"fov": 40, "position": [0, 1, 2]},
  "shapes": [
    {"type": "sphere", "radius": 1},
    {"type": "sphere",
     "radius": 2,
     "roughnes": 0.1}
  ]
})";

TEST(StrictJson, NamesLineAndPointerOfAnUnknownKeyWithASuggestion) {
  auto doc = JsonDocument::parse(kText, "scene.json");
  StrictObject root = StrictObject::root(doc);
  root.object("camera");  // consumed below
  const auto shapes = root.objects("shapes");
  ASSERT_EQ(shapes.size(), 2u);
  EXPECT_EQ(shapes[1].string("type"), "sphere");
  EXPECT_EQ(shapes[1].number("radius"), 2.0);
  const std::string err = error_of([&] { shapes[1].finish({"roughness"}); });
  EXPECT_NE(err.find("scene.json:7"), std::string::npos) << err;
  EXPECT_NE(err.find("/shapes/1/roughnes"), std::string::npos) << err;
  EXPECT_NE(err.find("did you mean 'roughness'"), std::string::npos) << err;
}

TEST(StrictJson, WrongTypesMissingKeysAndSyntaxErrorsAreNamed) {
  auto doc = JsonDocument::parse(kText, "scene.json");
  StrictObject root = StrictObject::root(doc);
  const StrictObject cam = root.object("camera");
  EXPECT_NE(error_of([&] { cam.string("fov"); }).find("scene.json:2: /camera/fov: expected a string"), std::string::npos);
  EXPECT_NE(error_of([&] { cam.number("aperture"); }).find("missing required key 'aperture'"), std::string::npos);
  EXPECT_NE(error_of([&] { cam.vec2("position"); }).find("expected 2 numbers"), std::string::npos);
  EXPECT_NE(error_of([] { JsonDocument::parse("{\n \"a\": 1,\n \"b\": ]\n}", "x.json"); }).find("x.json:3"),
            std::string::npos);
  EXPECT_NE(error_of([] { JsonDocument::load("/nonexistent/scene.json"); }).find("/nonexistent/scene.json"),
            std::string::npos);
}

TEST(StrictJson, ChoicesAndPositivity) {
  auto doc = JsonDocument::parse(R"({"kind": "ggx", "alpha": -1, "v": [1, 2, 3]})");
  StrictObject o = StrictObject::root(doc);
  EXPECT_NE(error_of([&] { o.choice("kind", {"beckmann", "lambert"}); }).find("not one of: beckmann, lambert"),
            std::string::npos);
  EXPECT_NE(error_of([&] { o.positive("alpha"); }).find("must be positive"), std::string::npos);
  EXPECT_EQ(o.vec3("v"), Vec3(1, 2, 3));
  EXPECT_EQ(o.rgb("missing", Vec3(0.5)), Vec3(0.5));
  o.finish();  // every key was read
}

TEST(EditDistance, Basics) {
  EXPECT_EQ(edit_distance("roughness", "roughnes"), 1u);
  EXPECT_EQ(edit_distance("", "abc"), 3u);
  EXPECT_EQ(edit_distance("kitten", "sitting"), 3u);
}

}  // namespace
}  // namespace tb
