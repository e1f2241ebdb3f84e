// A new mutation is one class and one registration: registered at run time here, it is picked up
// by the checks that loop over the registries (validate/mcmc/registered_mutations.h, the functions
// behind mcmc.pss.cornell.registered_mutations.{pairwise,chi2}, mlt.path_space.registered_mutations.pairwise
// mlt.path_space.registered_mutations.flux_bins and, with its declared projection,
// mlt.path_space.registered_mutations.chi2), and by the renderers' drivers.
#include <cmath>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <vector>
#include <limits>
#include <memory>
#include <string>

#include <gtest/gtest.h>

#include "lib/mcmc/path_space/lens_perturbation.h"
#include "lib/mcmc/path_space/mlt.h"
#include "lib/mcmc/path_space/path_mutations.h"
#include "lib/mcmc/pss/pss_driver.h"
#include "lib/mcmc/pss/pss_steps.h"
#include "validate/mcmc/path_space/path_projections.h"
#include "validate/mcmc/path_space/proposal_projections.h"
#include "validate/mcmc/registered_mutations.h"
#include "validate/render/render_compare.h"

namespace tb {
namespace {

// A trivial PSS mutation: an independent proposal (a second large step under another name).
class TrivialIndependentStep final : public pss::PssMutation {
 public:
  explicit TrivialIndependentStep(double log_ratio_error = 0.0) : err_(log_ratio_error) {}
  std::string name() const override { return err_ == 0.0 ? "test independent step" : "test misstated step"; }
  double weight() const override { return 0.1; }
  bool independent() const override { return true; }
  double scale(double, double) const override { return 0.0; }
  void begin(pss::PssState& s, double) const override { s.start_iteration(true); }
  // Symmetric: T(y -> x) / T(x -> y) = 1; the misstated variant claims exp(err).
  double log_reverse_over_forward(const pss::PssMove&) const override { return err_; }
  double log_density(const pss::DenseState&, const pss::DenseState& y, const pss::PssMove&) const override {
    for (double v : y)
      if (!(v >= 0.0 && v < 1.0)) return -std::numeric_limits<double>::infinity();
    return 0.0;
  }

 private:
  double err_;
};

// A small step of its own sigma on D(x) ∩ D(y) (the rescaled step's lazy update with a fixed
// scale) and sigma0 elsewhere; symmetric. stated_factor != 1 states the density of a step that
// much wider on D(x) ∩ D(y) (a misstated density; the sampler is unchanged).
class ToySmallStep final : public pss::PssMutation {
 public:
  ToySmallStep(std::string name, double sigma0, double sigma, double stated_factor = 1.0)
      : name_(std::move(name)), sigma0_(sigma0), sigma_(sigma), stated_(stated_factor) {}
  std::string name() const override { return name_; }
  double weight() const override { return 0.1; }
  bool symmetric() const override { return true; }
  double scale(double, double) const override { return sigma_; }
  void begin(pss::PssState& s, double) const override {
    s.set_rescaled(true);
    s.start_iteration(false, sigma_);
  }
  double log_density(const pss::DenseState& x, const pss::DenseState& y, const pss::PssMove& m) const override {
    double lp = 0.0;
    for (size_t i = 0; i < x.size(); ++i) {
      const size_t j = i / pss::kStreams, st = i % pss::kStreams;
      const bool both = j < m.reads_x[st] && j < m.reads_y[st];
      lp += std::log(pss::wrapped_normal_pdf(y[i] - x[i], both ? sigma_ * stated_ : sigma0_));
    }
    return lp;
  }

 private:
  std::string name_;
  double sigma0_, sigma_, stated_;
};

// The fixed small step whose stated density couples coordinates 0 and 1 (does not factorise).
class CoupledSmallStep final : public pss::PssMutation {
 public:
  explicit CoupledSmallStep(double sigma0) : sigma0_(sigma0) {}
  std::string name() const override { return "test coupled step"; }
  double weight() const override { return 0.1; }
  bool symmetric() const override { return true; }
  double scale(double, double) const override { return sigma0_; }
  void begin(pss::PssState& s, double) const override {
    s.set_rescaled(false);
    s.start_iteration(false);
  }
  double log_density(const pss::DenseState& x, const pss::DenseState& y, const pss::PssMove&) const override {
    double lp = 0.0;
    for (size_t i = 0; i < x.size(); ++i) lp += std::log(pss::wrapped_normal_pdf(y[i] - x[i], sigma0_));
    const double d0 = std::remainder(y[0] - x[0], 1.0), d1 = std::remainder(y[1] - x[1], 1.0);
    return lp + d0 * d1 / (sigma0_ * sigma0_);
  }

 private:
  double sigma0_;
};

// A lens perturbation (r2 = 2 pixels) whose density is stated by one with r2 = 2.2 pixels: 10 %
// too wide, the sampler unchanged.
class MisstatedSmallLens final : public path_space::PathMutation {
 public:
  explicit MisstatedSmallLens(const PathContext& ctx) : sampler_(ctx, 0.1, 2.0), stated_(ctx, 0.1, 2.2) {}
  std::string name() const override { return "test misstated lens"; }
  double weight(const path_space::MltPath&) const override { return 0.1; }
  std::optional<path_space::MltPath> propose(const path_space::MltPath& x, Uniforms& u) const override {
    return sampler_.propose(x, u);
  }
  double density(const path_space::MltPath& x, const path_space::MltPath& y) const override {
    return stated_.density(x, y);
  }
  const path_space::LensPerturbation& sampler() const { return sampler_; }

 private:
  path_space::LensPerturbation sampler_, stated_;
};

// The raster-offset projection (proposal_projections.h) of a test lens mutation, on Cornell-box
// paths of 2 segments.
path_space::PathProjectionInfo small_lens_projection(const std::string& name) {
  using namespace path_space;
  return {.name = name,
          .coordinate = "raster offset (phi, ln r)",
          .scenes = {"cornell-box.json"},
          .paths = [](const PathContext& ctx, const PathMutation&,
                      uint64_t seed) { return std::vector<MltPath>{path_with_segments(ctx, 2, 4, seed)}; },
          .make = [](const PathProjectionInput& in, const MltPath& x) -> PathProjectionList {
            const LensPerturbation* lens = nullptr;
            if (const auto* m = dynamic_cast<const PathProposalMutation<LensPerturbation>*>(&in.registered))
              lens = &m->proposal();
            if (const auto* m = dynamic_cast<const MisstatedSmallLens*>(&in.registered)) lens = &m->sampler();
            if (!lens) throw std::logic_error("not a test lens");
            PathProjectionList out;
            out.push_back(std::make_unique<const PathProjectionOf<LensOffsetProjection>>(
                LensOffsetProjection{lens, &in.ctx, x, &in.checked}, "k=2"));
            return out;
          },
          .quick_samples = 20000};
}

CheckContext quick() {
  CheckContext c;
  c.seed = 3;
  return c;
}

TEST(MutationRegistry, NewPssMutationIsPickedUpByTheChecks) {
  pss::register_pss_mutation({"test independent step", "a trivial mutation registered by a test",
                              [](const pss::PssStepSettings&) -> std::shared_ptr<const pss::PssMutation> {
                                return std::make_shared<const TrivialIndependentStep>();
                              }});
  const CheckResult r = pss_registered_mutations_pairwise(quick(), "test.pss.registered");
  pss::unregister_pss_mutation("test independent step");
  ASSERT_TRUE(r.details["mutations"].contains("test independent step")) << r.message;
  EXPECT_TRUE(r.details["mutations"]["test independent step"]["passed"].get<bool>()) << r.message;
  EXPECT_TRUE(r.passed) << r.message;

  // A mutation whose acceptance ratio is misstated: the same check must fail on it.
  pss::register_pss_mutation({"test misstated step", "a broken mutation registered by a test",
                              [](const pss::PssStepSettings&) -> std::shared_ptr<const pss::PssMutation> {
                                return std::make_shared<const TrivialIndependentStep>(0.7);
                              }});
  const CheckResult b = pss_registered_mutations_pairwise(quick(), "test.pss.registered.broken");
  pss::unregister_pss_mutation("test misstated step");
  ASSERT_TRUE(b.details["mutations"].contains("test misstated step")) << b.message;
  EXPECT_FALSE(b.details["mutations"]["test misstated step"]["passed"].get<bool>()) << b.message;
  EXPECT_FALSE(b.passed);
}

TEST(MutationRegistry, NewPssMutationIsPickedUpByTheProposalChiSquare) {
  CheckContext c = quick();
  c.sample_scale = 0.5;  // 2e4 proposals per test
  pss::register_pss_mutation({"test small step 0.03", "a small step of sigma 0.03 registered by a test",
                              [](const pss::PssStepSettings& s) -> std::shared_ptr<const pss::PssMutation> {
                                return std::make_shared<const ToySmallStep>("test small step 0.03", s.sigma, 0.03);
                              }});
  const CheckResult r = pss_registered_mutations_chi2(c, "test.pss.registered.chi2");
  pss::unregister_pss_mutation("test small step 0.03");
  ASSERT_TRUE(r.details["mutations"].contains("test small step 0.03")) << r.message;
  const auto& toy = r.details["mutations"]["test small step 0.03"];
  EXPECT_EQ(toy["tests"].size(), 6u) << toy.dump(1);  // 3 states x 2 coordinates
  EXPECT_TRUE(toy["factorises"].get<bool>()) << toy.dump(1);
  EXPECT_TRUE(toy["passed"].get<bool>()) << toy.dump(1);
  EXPECT_TRUE(r.passed) << r.message;

  // A toy whose stated density is 10 % too wide (its sampler unchanged) must be rejected, and one
  // whose stated density does not factorise must be reported as such and fail the check.
  pss::register_pss_mutation({"test misstated small step", "a misstated small step registered by a test",
                              [](const pss::PssStepSettings& s) -> std::shared_ptr<const pss::PssMutation> {
                                return std::make_shared<const ToySmallStep>("test misstated small step", s.sigma, 0.03,
                                                                            1.1);
                              }});
  pss::register_pss_mutation({"test coupled step", "a small step with a non-factorising stated density",
                              [](const pss::PssStepSettings& s) -> std::shared_ptr<const pss::PssMutation> {
                                return std::make_shared<const CoupledSmallStep>(s.sigma);
                              }});
  const CheckResult b = pss_registered_mutations_chi2(c, "test.pss.registered.chi2.broken");
  pss::unregister_pss_mutation("test misstated small step");
  pss::unregister_pss_mutation("test coupled step");
  ASSERT_TRUE(b.details["mutations"].contains("test misstated small step")) << b.message;
  EXPECT_TRUE(b.details["mutations"]["test misstated small step"]["rejected"].get<bool>()) << b.message;
  EXPECT_FALSE(b.details["mutations"]["test misstated small step"]["passed"].get<bool>()) << b.message;
  ASSERT_TRUE(b.details["mutations"].contains("test coupled step")) << b.message;
  EXPECT_FALSE(b.details["mutations"]["test coupled step"]["factorises"].get<bool>()) << b.message;
  EXPECT_FALSE(b.details["mutations"]["test coupled step"]["passed"].get<bool>()) << b.message;
  EXPECT_NE(b.message.find("DOES NOT FACTORISE"), std::string::npos) << b.message;
  EXPECT_FALSE(b.passed) << b.message;
  // The registered mutations themselves still pass in that run.
  for (const char* m : {"large step", "small step", "rescaled small step"})
    EXPECT_TRUE(b.details["mutations"][m]["passed"].get<bool>()) << m << ": " << b.message;
}

TEST(MutationRegistry, NewPathMutationIsPickedUpByTheChecksAndTheDriver) {
  using namespace path_space;
  // A second lens perturbation with a smaller outer radius, under its own name.
  register_path_mutation({"test small lens", "the lens perturbation with r2 = 2 pixels", 0.1,
                          [](const PathContext& ctx, const PathMutationSettings&, double w)
                              -> std::shared_ptr<const PathMutation> {
                            return std::make_shared<const PathProposalMutation<LensPerturbation>>(
                                "test small lens", w, LensPerturbation(ctx, 0.1, 2.0));
                          }});
  const CheckResult r = path_registered_mutations_pairwise(quick(), "test.path.registered");
  const CheckResult flux = path_registered_mutations_flux_bins(quick(), "test.path.registered.flux");
  // The driver runs it too: its statistics name it and it is proposed.
  const auto world = load_scene_at_resolution("cornell-box.json", 8, 8);
  RenderSettings st;
  st.spp = 16;
  st.passes = 2;
  st.max_depth = 3;
  Film film(8, 8);
  const MltStats stats = run_mlt(*world, st, film);
  unregister_path_mutation("test small lens");
  ASSERT_TRUE(r.details["mutations"].contains("test small lens")) << r.details.dump(1);
  EXPECT_TRUE(r.details["mutations"]["test small lens"]["passed"].get<bool>()) << r.message;
  EXPECT_TRUE(r.passed) << r.details.dump(1);
  ASSERT_TRUE(flux.details["mutations"].contains("test small lens")) << flux.details.dump(1);
  EXPECT_GT(flux.details["mutations"]["test small lens"]["pairs_tested"].get<int64_t>(), 0) << flux.message;
  EXPECT_TRUE(flux.passed) << flux.message;
  bool seen = false;
  for (const auto& m : stats.mutations)
    if (m.name == "test small lens") {
      seen = true;
      EXPECT_GT(m.proposed, 0);
    }
  EXPECT_TRUE(seen);
}

TEST(MutationRegistry, NewPathMutationIsPickedUpByTheProposalChiSquare) {
  using namespace path_space;
  CheckContext c = quick();
  c.sample_scale = 0.5;
  const auto small_lens = [](const std::string& name) {
    return PathMutationInfo{name, "the lens perturbation with r2 = 2 pixels", 0.1,
                            [](const PathContext& ctx, const PathMutationSettings&, double w)
                                -> std::shared_ptr<const PathMutation> {
                              return std::make_shared<const PathProposalMutation<LensPerturbation>>(
                                  "test small lens", w, LensPerturbation(ctx, 0.1, 2.0));
                            }};
  };
  register_path_mutation(small_lens("test small lens"));
  register_path_projection(small_lens_projection("test small lens"));
  const CheckResult r = path_registered_mutations_chi2(c, "test.path.registered.chi2");
  unregister_path_projection("test small lens");
  unregister_path_mutation("test small lens");
  ASSERT_TRUE(r.details["mutations"].contains("test small lens")) << r.message;
  const auto& toy = r.details["mutations"]["test small lens"];
  EXPECT_EQ(toy["status"].get<std::string>(), "tested") << toy.dump(1);
  EXPECT_EQ(toy["tests"].size(), 1u) << toy.dump(1);
  EXPECT_TRUE(toy["passed"].get<bool>()) << toy.dump(1);
  EXPECT_TRUE(r.passed) << r.message;

  // A toy whose stated density is 10 % too wide in r2 (its sampler unchanged) must be rejected,
  // and a mutation registered without a projection must fail the check, named in its message.
  register_path_mutation({"test misstated lens", "a lens perturbation with a misstated density", 0.1,
                          [](const PathContext& ctx, const PathMutationSettings&, double)
                              -> std::shared_ptr<const PathMutation> {
                            return std::make_shared<const MisstatedSmallLens>(ctx);
                          }});
  register_path_projection(small_lens_projection("test misstated lens"));
  register_path_mutation(small_lens("test lens without projection"));
  register_path_mutation(small_lens("test exempt lens"));
  register_path_projection({.name = "test exempt lens", .no_projection_reason = "a declared reason"});
  const CheckResult b = path_registered_mutations_chi2(c, "test.path.registered.chi2.broken");
  unregister_path_projection("test misstated lens");
  unregister_path_mutation("test misstated lens");
  unregister_path_mutation("test lens without projection");
  unregister_path_projection("test exempt lens");
  unregister_path_mutation("test exempt lens");
  ASSERT_TRUE(b.details["mutations"].contains("test exempt lens")) << b.message;
  EXPECT_EQ(b.details["mutations"]["test exempt lens"]["status"].get<std::string>(), "exempt");
  EXPECT_TRUE(b.details["mutations"]["test exempt lens"]["passed"].get<bool>());
  EXPECT_NE(b.message.find("test exempt lens: not tested: a declared reason"), std::string::npos) << b.message;
  ASSERT_TRUE(b.details["mutations"].contains("test misstated lens")) << b.message;
  EXPECT_TRUE(b.details["mutations"]["test misstated lens"]["rejected"].get<bool>()) << b.message;
  EXPECT_FALSE(b.details["mutations"]["test misstated lens"]["passed"].get<bool>()) << b.message;
  ASSERT_TRUE(b.details["mutations"].contains("test lens without projection")) << b.message;
  EXPECT_EQ(b.details["mutations"]["test lens without projection"]["status"].get<std::string>(), "no projection");
  EXPECT_FALSE(b.details["mutations"]["test lens without projection"]["passed"].get<bool>()) << b.message;
  EXPECT_NE(b.message.find("test lens without projection: NO CHI-SQUARE PROJECTION DECLARED"), std::string::npos)
      << b.message;
  EXPECT_FALSE(b.passed) << b.message;
  // The registered mutations themselves still pass in that run: each is tested, or exempt with
  // the reason its registration declares.
  for (const auto& m : path_mutations()) {
    const auto& e = b.details["mutations"][m.name];
    EXPECT_TRUE(e["passed"].get<bool>()) << m.name << ": " << b.message;
    const auto* projection = find_path_projection(m.name);
    ASSERT_NE(projection, nullptr) << m.name;
    EXPECT_EQ(e["status"].get<std::string>(), projection->no_projection_reason.empty() ? "tested" : "exempt")
        << m.name << ": " << b.message;
  }
  EXPECT_EQ(find_path_projection("test misstated lens"), nullptr);
  EXPECT_EQ(find_path_mutation("test lens without projection"), nullptr);
}

}  // namespace
}  // namespace tb
