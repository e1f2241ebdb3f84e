// Integrator parameters (tb render --param NAME=VALUE): names are checked against the
// integrator's list, values against their range, and a parameter changes the render.
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "lib/mcmc/pss/pss_driver.h"
#include "lib/registry/integrator_registry.h"
#include "validate/render/render_compare.h"

namespace tb {
namespace {

TEST(IntegratorParams, UnknownNamesAndNonFiniteValuesAreRejectedByName) {
  const IntegratorInfo* mmlt = find_integrator("mmlt");
  const IntegratorInfo* pt = find_integrator("pt");
  ASSERT_NE(mmlt, nullptr);
  ASSERT_NE(pt, nullptr);
  EXPECT_EQ(validate_params(*mmlt, {{"bootstrap", 4096}, {"chains", 16}}), "");
  const std::string typo = validate_params(*mmlt, {{"chain", 16}});
  EXPECT_NE(typo.find("'chain'"), std::string::npos) << typo;
  EXPECT_NE(typo.find("chains"), std::string::npos) << typo;  // names the known ones
  EXPECT_NE(validate_params(*pt, {{"chains", 16}}).find("takes none"), std::string::npos);
  EXPECT_NE(validate_params(*mmlt, {{"sigma", std::numeric_limits<double>::quiet_NaN()}}), "");
}

TEST(IntegratorParams, PssRangesAreEnforced) {
  pss::PssSettings p;
  pss::apply_params({{"bootstrap", 4096}, {"chains", 8}, {"large_step", 0.5}, {"sigma", 0.02}}, &p);
  EXPECT_EQ(p.bootstrap, 4096);
  EXPECT_EQ(p.chains, 8);
  EXPECT_EQ(p.large_step_probability, 0.5);
  EXPECT_EQ(p.sigma, 0.02);
  for (const auto& bad : std::map<std::string, double>{{"bootstrap", 0}, {"large_step", 1.5}, {"sigma", 0}, {"x", 1}})
    EXPECT_THROW(pss::apply_params({bad}, &p), std::invalid_argument) << bad.first;
}

TEST(IntegratorParams, AParameterReachesTheRenderer) {
  // The same seed with another chain count gives another image; the defaults given explicitly
  // give the same image as none.
  const auto world = load_scene_at_resolution("cornell-box.json", 8, 8);
  RenderSettings st;
  st.spp = 8;
  st.passes = 2;
  st.max_depth = 3;
  const RenderRun a = render_with("pssmlt", *world, st);
  st.params = {{"chains", 64}, {"large_step", 0.3}};
  const RenderRun same = render_with("pssmlt", *world, st);
  st.params = {{"chains", 8}};
  const RenderRun other = render_with("pssmlt", *world, st);
  ASSERT_TRUE(a.ok() && same.ok() && other.ok());
  EXPECT_EQ(a.film->welch().sum, same.film->welch().sum);
  EXPECT_NE(a.film->welch().sum, other.film->welch().sum);
}

}  // namespace
}  // namespace tb
