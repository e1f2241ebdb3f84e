// The path-traced image both scene-import tests compare (imported scene against the project's own
// JSON): 16 passes of 32 spp at the scene's own max depth, as Welch sums for validate/image_compare.h.
#pragma once

#include <cstdint>

#include <gtest/gtest.h>

#include "lib/film/film.h"
#include "lib/registry/integrator_registry.h"
#include "lib/scene/world.h"
#include "validate/image_compare.h"

namespace tb::test {

inline WelchImage render_pt_for_import_test(const World& w, uint64_t seed) {
  RenderSettings st;
  st.seed = seed;
  st.spp = 16 * 32;
  st.passes = 16;
  st.max_depth = w.integrator_defaults().at("max_depth").get<int>();
  Film film(w.camera().width(), w.camera().height());
  const IntegratorInfo* pt = find_integrator("pt");
  EXPECT_NE(pt, nullptr);
  EXPECT_EQ(pt->render(w, st, film), st.passes);
  EXPECT_EQ(film.nonfinite().count(), 0);
  return film.welch();
}

}  // namespace tb::test
