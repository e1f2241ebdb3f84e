// The shipped scenes that the image agreement checks render: every one of them with pt, lt and
// bdpt against a long BDPT reference (integrator.agreement.<key>.<integrator>) and with every PSS
// integrator (render.<integrator>.<key>.unbiased). The feature-coverage check
// (scene.feature_coverage) requires every feature the scene format accepts to appear in one of
// them, so a feature no estimator is compared on cannot hide a bug.
#pragma once

#include <string>
#include <vector>

namespace tb {

struct CheckedScene {
  std::string key, file;
};

inline const std::vector<CheckedScene>& agreement_scenes() {
  static const std::vector<CheckedScene> v = {
      {"cornell-box", "cornell-box.json"},
      {"glossy", "glossy.json"},
      {"caustic", "caustic.json"},
      // Coarse meshes with per-vertex shading normals (an OBJ with vn, and inline "normals").
      {"smooth-mesh", "smooth-mesh.json"},
      // Curved smooth mirrors (sphere, cylinder, paraboloid, torus) under an area light.
      {"dg-curved-mirrors", "dg-curved-mirrors.json"},
      // Thin lens, six lights of four kinds and different power, the remaining shapes.
      {"features", "features.json"},
  };
  return v;
}

}  // namespace tb
