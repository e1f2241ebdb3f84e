// Unit tests of the apt integrator (lib/mcmc/apt_integrator.h) and of its large step
// (estimators/mcmc/prefix_multiple_try.h; Zirr & Dachsbacher 2020, Sec. 7.2, Eq. 27-29):
// trace_forward_prefix against trace_forward, the candidate weights of a traced path against the
// fixed-length targets, the move's algebra (reverse of the reverse, detailed balance on the
// extended space, the acceptance of Eq. 29), the chain's bit-identical films for 1 and 2 threads.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "analytic/mcmc/prefix_target.h"
#include "estimators/mcmc/prefix_multiple_try.h"
#include "lib/core/parallel.h"
#include "lib/core/rng.h"
#include "lib/mcmc/apt_integrator.h"
#include "validate/mcmc/broken_variants.h"
#include "validate/render/render_compare.h"

namespace tb {
namespace {

using mcmc::ModelState;

std::vector<double> uniforms(Rng& rng, size_t n) {
  std::vector<double> u(n);
  for (double& v : u) v = rng.uniform();
  return u;
}

TEST(AptPrefixTrace, PrefixesAreTheFixedLengthTraces) {
  const auto world = load_scene_at_resolution("cornell-box.json", 32, 32);
  const mcmc::AptTarget longest(*world, 6);
  Rng rng = Rng::for_sample(3, 17, 0);
  int compared = 0;
  for (int i = 0; i < 200; ++i) {
    const std::vector<double> U = uniforms(rng, longest.dimension());
    const auto p = longest.trace_prefix(U);
    ASSERT_TRUE(p.has_value());
    for (int k = 1; k <= 6; ++k) {
      const mcmc::AptTarget t(*world, k);
      const std::vector<double> prefix(U.begin(), U.begin() + static_cast<long>(t.dimension()));
      const auto q = t.trace(prefix);
      ASSERT_EQ(q.has_value(), static_cast<int>(p->vertices.size()) >= k) << "k " << k;
      if (!q) continue;
      ++compared;
      for (int j = 0; j < k; ++j) EXPECT_EQ(q->vertices[j].p, p->vertices[j].p);
      EXPECT_EQ(t.density(prefix), luminance(mcmc::AptTarget::contribution(*world, *p, k)));
    }
  }
  EXPECT_GT(compared, 400);
}

TEST(AptPathFamily, WeightsAreTheTargetsOfThePrefixes) {
  const auto world = load_scene_at_resolution("cornell-box.json", 16, 16);
  const apt::AptPathFamily fam(*world, 5);
  ASSERT_EQ(fam.models(), 5);
  Rng rng = Rng::for_sample(5, 23, 0);
  int positive = 0;
  std::vector<double> w(5);
  for (int i = 0; i < 20000; ++i) {
    const std::vector<double> U = uniforms(rng, fam.dimension(4));
    fam.weights(U, &w);
    for (int j = 0; j < 5; ++j) {
      const ModelState x{j, std::vector<double>(U.begin(), U.begin() + static_cast<long>(fam.dimension(j)))};
      ASSERT_EQ(w[static_cast<size_t>(j)], fam.density(x)) << "draw " << i << " model " << j;
      positive += w[static_cast<size_t>(j)] > 0.0;
    }
  }
  EXPECT_GT(positive, 20);  // the emitter is hit by some prefixes
}

// pi(x) T(x -> m) a(x, m) = pi(y) T(y -> m') a(y, m') on the analytic prefix family, the reverse
// of the reverse is the move, and the acceptance is min{1, S(U_Y) / S(U_X)}.
TEST(PrefixMultipleTry, DetailedBalanceOnTheExtendedSpace) {
  const mcmc::PrefixMultipleTry<mcmc::PrefixTarget> k(mcmc::PrefixTarget{});
  Rng rng = Rng::for_sample(7, 29, 0);
  RngUniforms u(rng);
  for (int i = 0; i < 2000; ++i) {
    const ModelState x = k.family().sample_exact(u);
    const auto m = k.sample_move(x, u);
    ASSERT_TRUE(m.has_value());
    const ModelState y = k.destination(*m);
    const auto r = k.reverse(x, *m);
    EXPECT_EQ(k.destination(r), x);
    const auto rr = k.reverse(y, r);
    EXPECT_EQ(rr.draw, m->draw);
    EXPECT_EQ(rr.extension, m->extension);
    EXPECT_EQ(rr.selected, m->selected);
    EXPECT_EQ(r.w_forward, k.weights_of(x.u, m->extension));
    const double lhs = k.target_density(x) * k.move_density(x, *m) * k.acceptance(x, *m);
    const double rhs = k.target_density(y) * k.move_density(y, r) * k.acceptance(y, r);
    EXPECT_NEAR(lhs, rhs, 1e-12 * std::max(lhs, rhs));
    const double sy = mcmc::weight_sum(m->w_forward), sx = mcmc::weight_sum(m->w_reverse);
    EXPECT_DOUBLE_EQ(k.acceptance(x, *m), std::min(1.0, sy / sx));  // Eq. 29
  }
}

TEST(PrefixMultipleTry, WithoutReverseCandidatesBreaksBalance) {
  const mcmc::WithoutReverseCandidates broken(mcmc::PrefixMultipleTry(mcmc::PrefixTarget{}));
  Rng rng = Rng::for_sample(7, 31, 0);
  RngUniforms u(rng);
  int violations = 0;
  for (int i = 0; i < 500; ++i) {
    const ModelState x = broken.target().sample_exact(u);
    const auto m = broken.sample_move(x, u);
    ASSERT_TRUE(m.has_value());
    const ModelState y = broken.destination(*m);
    const auto r = broken.reverse(x, *m);
    const double lhs = broken.target_density(x) * broken.move_density(x, *m) * broken.acceptance(x, *m);
    const double rhs = broken.target_density(y) * broken.move_density(y, r) * broken.acceptance(y, r);
    violations += std::abs(lhs - rhs) > 1e-9 * std::max(lhs, rhs);
  }
  EXPECT_GT(violations, 100);
}

TEST(SelectWeighted, InvertsTheRunningSum) {
  const std::vector<double> w = {0.0, 1.0, 0.0, 3.0};
  EXPECT_EQ(mcmc::select_weighted(w, 0.0), 1);
  EXPECT_EQ(mcmc::select_weighted(w, 0.2499), 1);
  EXPECT_EQ(mcmc::select_weighted(w, 0.25), 3);
  EXPECT_EQ(mcmc::select_weighted(w, std::nextafter(1.0, 0.0)), 3);
  EXPECT_EQ(mcmc::select_weighted({0.0, 0.0}, 0.5), -1);
}

TEST(AptRender, DeterministicAcrossThreadCountsAndFinite) {
  const auto world = load_scene_at_resolution("cornell-box.json", 8, 8);
  RenderSettings st;
  st.spp = 16;
  st.passes = 2;
  st.max_depth = 3;
  apt::AptSettings a;
  a.bootstrap = 2048;
  a.chains = 7;
  a.segment = 50;
  auto run = [&](size_t threads, apt::AptStats* stats) {
    ThreadLimit limit(threads);
    Film film(8, 8);
    apt::run_apt(*world, st, a, film, stats);
    return film.welch().sum;
  };
  apt::AptStats s1, s2;
  const auto x = run(1, &s1), y = run(2, &s2);
  ASSERT_EQ(x.size(), y.size());
  double total = 0.0;
  for (size_t i = 0; i < x.size(); ++i) {
    ASSERT_EQ(x[i], y[i]) << "pixel " << i;
    total += luminance(x[i]);
  }
  EXPECT_GT(total, 0.0);
  EXPECT_EQ(s1.mutations, 16 * 64);  // spp 16 over 2 passes, 64 pixels
  EXPECT_EQ(s1.step_errors, 0);
  EXPECT_GT(s1.large.proposed, 0);
  EXPECT_GT(s1.small.accepted, 0);
  EXPECT_EQ(s1.large.accepted, s2.large.accepted);
}

TEST(AptRender, ParamsAreValidated) {
  apt::AptSettings a;
  apt::apply_params({{"large_step", 0.5}, {"chains", 8}}, &a);
  EXPECT_EQ(a.large_step_probability, 0.5);
  EXPECT_EQ(a.chains, 8);
  EXPECT_THROW(apt::apply_params({{"large_step", 0.0}}, &a), std::invalid_argument);
  EXPECT_THROW(apt::apply_params({{"sigma", 0.1}}, &a), std::invalid_argument);
}

}  // namespace
}  // namespace tb
