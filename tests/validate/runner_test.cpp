#include "validate/runner.h"

#include <cmath>
#include <filesystem>
#include <limits>

#include <gtest/gtest.h>

#include "lib/core/atomic_file.h"

namespace tb {
namespace {

Check make_check(std::string name, CheckKind kind, std::function<CheckResult(const CheckContext&)> run) {
  return Check{.name = std::move(name), .description = "test", .kind = kind, .run = std::move(run)};
}

TEST(Runner, StatisticalRejectionIsRerunWithFreshSeedAndFourTimesTheSamples) {
  std::vector<CheckContext> seen;
  const Check c = make_check("t.flaky", CheckKind::kStatistical, [&](const CheckContext& ctx) {
    seen.push_back(ctx);
    CheckResult r;
    r.passed = ctx.sample_scale > 1.0;  // rejects at 1x, passes at 4x
    return r;
  });
  RunOptions opt;
  opt.seed = 5;
  const nlohmann::json rec = run_one(c, opt);
  ASSERT_EQ(seen.size(), 2u);
  EXPECT_EQ(seen[1].sample_scale, 4.0);
  EXPECT_NE(seen[0].seed, seen[1].seed);
  EXPECT_EQ(rec["verdict"], "pass-on-rerun");
  EXPECT_TRUE(rec["passed"].get<bool>());
  EXPECT_NE(rec["rerun"]["reproducer"].get<std::string>().find("--attempt 1"), std::string::npos);
}

TEST(Runner, FailsWhenTheRerunRejectsToo) {
  const Check c = make_check("t.biased", CheckKind::kStatistical, [](const CheckContext&) { return CheckResult{}; });
  const nlohmann::json rec = run_one(c, RunOptions{});
  EXPECT_EQ(rec["verdict"], "fail");
  EXPECT_TRUE(rec.contains("rerun"));
}

TEST(Runner, DeterministicChecksAreNotRerun) {
  int calls = 0;
  const Check c = make_check("t.det", CheckKind::kDeterministic, [&](const CheckContext&) {
    ++calls;
    return CheckResult{};
  });
  const nlohmann::json rec = run_one(c, RunOptions{});
  EXPECT_EQ(calls, 1);
  EXPECT_EQ(rec["verdict"], "fail");
  EXPECT_FALSE(rec.contains("rerun"));
}

TEST(Runner, ExceptionsBecomeFailuresWithTheirMessage) {
  const Check c = make_check("t.throw", CheckKind::kDeterministic,
                             [](const CheckContext&) -> CheckResult { throw std::runtime_error("boom"); });
  const nlohmann::json rec = run_one(c, RunOptions{});
  EXPECT_FALSE(rec["passed"].get<bool>());
  EXPECT_NE(rec["first"]["message"].get<std::string>().find("boom"), std::string::npos);
}

TEST(Runner, SeedsDependOnNameAndRunSeedOnly) {
  EXPECT_EQ(check_seed(1, "a.b", 0), check_seed(1, "a.b", 0));
  EXPECT_NE(check_seed(1, "a.b", 0), check_seed(2, "a.b", 0));
  EXPECT_NE(check_seed(1, "a.b", 0), check_seed(1, "a.c", 0));
  EXPECT_NE(check_seed(1, "a.b", 0), check_seed(1, "a.b", 1));
}

TEST(Runner, ResumeReusesFinishedRecordsOfTheSameConfiguration) {
  const std::string dir = (std::filesystem::temp_directory_path() / "tb_runner_resume_test").string();
  std::filesystem::remove_all(dir);
  int calls = 0;
  const Check c = make_check("t.count", CheckKind::kDeterministic, [&](const CheckContext&) {
    ++calls;
    CheckResult r;
    r.passed = true;
    return r;
  });
  RunOptions opt;
  opt.out_dir = dir;
  opt.seed = 3;
  run_checks({&c}, opt);
  EXPECT_TRUE(std::filesystem::exists(dir + "/records/t.count.json"));
  opt.resume = true;
  RunSummary s = run_checks({&c}, opt);
  EXPECT_EQ(calls, 1);
  EXPECT_EQ(s.resumed, 1u);
  opt.seed = 4;  // another seed: the record does not match, the check runs again
  s = run_checks({&c}, opt);
  EXPECT_EQ(calls, 2);
  EXPECT_EQ(s.resumed, 0u);
  std::filesystem::remove_all(dir);
}

TEST(Runner, StopsBetweenChecksWhenInterrupted) {
  std::atomic<bool> stop{true};
  const Check c = make_check("t.never", CheckKind::kDeterministic, [](const CheckContext&) { return CheckResult{}; });
  RunOptions opt;
  opt.interrupted = &stop;
  const RunSummary s = run_checks({&c}, opt);
  EXPECT_TRUE(s.interrupted);
  EXPECT_EQ(s.passed + s.failed, 0u);
}

TEST(Registry, SelectsByNamePrefixAndGlob) {
  Registry r;
  for (const char* n : {"core.warp.disk.chi2", "core.warp.disk.inverse", "core.rng.determinism", "stats.x"})
    r.add(make_check(n, CheckKind::kDeterministic, [](const CheckContext&) { return CheckResult{}; }));
  EXPECT_EQ(r.select({}).size(), 4u);
  EXPECT_EQ(r.select({"core.warp"}).size(), 2u);
  EXPECT_EQ(r.select({"core.wa"}).size(), 0u);  // prefixes are whole name segments
  EXPECT_EQ(r.select({"*.chi2"}).size(), 1u);
  EXPECT_EQ(r.select({"stats.x"}).size(), 1u);
  EXPECT_THROW(r.add(make_check("stats.x", CheckKind::kDeterministic, [](const CheckContext&) { return CheckResult{}; })),
               std::logic_error);
}

TEST(AtomicFile, WritesAndReadsBack) {
  const std::string p = (std::filesystem::temp_directory_path() / "tb_atomic_test/sub/f.txt").string();
  write_file_atomic(p, "hello");
  EXPECT_EQ(read_file(p), "hello");
  write_file_atomic(p, "again");
  EXPECT_EQ(read_file(p), "again");
  EXPECT_THROW(read_file(p + ".missing"), std::runtime_error);
}

// The power census: records from run_one with and without a stated effect, a negative control
// (left out), and the ordering and sample factors of the checks above the 2% target.
TEST(Runner, PowerSummaryCountsStatedEffectsAndNamesTheWeakest) {
  const auto check_with = [](std::string name, double mde) {
    return make_check(std::move(name), CheckKind::kStatistical, [mde](const CheckContext&) {
      CheckResult r;
      r.passed = true;
      r.p_value = 0.5;
      r.alpha = 0.01;
      r.min_detectable_effect = mde;
      if (std::isfinite(mde)) r.effect_kind = "uniform relative bias of the image";
      return r;
    });
  };
  RunOptions opt;
  nlohmann::json records = nlohmann::json::array();
  records.push_back(run_one(check_with("a.ok", 0.01), opt));
  records.push_back(run_one(check_with("a.weak", 0.04), opt));
  records.push_back(run_one(check_with("a.weaker", 0.06), opt));
  records.push_back(run_one(check_with("a.unstated", std::numeric_limits<double>::infinity()), opt));
  records.push_back(run_one(check_with("a.negative_control.x", 0.5), opt));
  records.push_back(run_one(make_check("a.exact", CheckKind::kDeterministic,
                                       [](const CheckContext&) {
                                         CheckResult r;
                                         r.passed = true;
                                         return r;
                                       }),
                            opt));
  const nlohmann::json p = power_summary(records, 0.02);
  EXPECT_EQ(p["stated"], 3);
  EXPECT_EQ(p["not_stated"], 1);
  EXPECT_EQ(p["deterministic"], 1);
  ASSERT_EQ(p["not_stated_checks"].size(), 1u);
  EXPECT_EQ(p["not_stated_checks"][0], "a.unstated");
  const auto& k = p["kinds"]["uniform relative bias of the image"];
  EXPECT_EQ(k["checks"], 3);
  EXPECT_EQ(k["meet_target"], 1);
  EXPECT_DOUBLE_EQ(k["median"].get<double>(), 0.04);
  ASSERT_EQ(k["above_target"].size(), 2u);
  EXPECT_EQ(k["above_target"][0]["name"], "a.weaker");
  EXPECT_NEAR(k["above_target"][0]["samples_scale_for_target"].get<double>(), 9.0, 1e-12);
  EXPECT_NEAR(k["above_target"][1]["samples_scale_for_target"].get<double>(), 4.0, 1e-12);
  // The record itself carries the statement (null when not stated).
  EXPECT_DOUBLE_EQ(records[0]["first"]["min_detectable_effect"].get<double>(), 0.01);
  EXPECT_TRUE(records[3]["first"]["min_detectable_effect"].is_null());
}

// --calibrate: a check that rejects on a known set of seeds (first attempt only, so the rerun
// passes), one that fails outright on some, a negative control that is missed on some; counts,
// suite rates, the alpha^2 bound and the resumable per-seed records.
TEST(Runner, CalibrateCountsRejectionsPerCheckAndForTheSuite) {
  const auto seed_bit = [](const CheckContext& ctx, int bit) { return ((ctx.seed >> bit) & 1u) != 0; };
  const Check flaky = make_check("c.flaky", CheckKind::kStatistical, [&](const CheckContext& ctx) {
    CheckResult r;
    r.alpha = 0.01;
    r.passed = ctx.sample_scale > 1.0 || !seed_bit(ctx, 3);  // first attempt rejects on about half the seeds
    return r;
  });
  const Check broken = make_check("c.broken", CheckKind::kStatistical, [&](const CheckContext& ctx) {
    CheckResult r;
    r.alpha = 0.02;
    r.details["family_alpha"] = 0.05;  // the family level is what counts
    r.passed = !seed_bit(ctx, 5) && ctx.sample_scale == 1.0;  // rejected on both attempts on some seeds
    return r;
  });
  const Check control = make_check("c.negative_control.x", CheckKind::kStatistical, [&](const CheckContext& ctx) {
    CheckResult r;
    r.alpha = 0.01;
    r.passed = !seed_bit(ctx, 7);  // caught unless the bit is set (on both attempts: derived from one run seed)
    return r;
  });
  const std::string dir = (std::filesystem::temp_directory_path() / "tb_runner_calibrate_test").string();
  std::filesystem::remove_all(dir);
  RunOptions opt;
  opt.seed = 10;
  opt.out_dir = dir;
  const std::vector<const Check*> checks{&flaky, &broken, &control};
  const nlohmann::json j = calibrate_checks(checks, opt, 12);
  // Recount directly from the seeds the runner derives.
  int64_t flaky_first = 0, broken_fail = 0, control_missed = 0, suite_fail = 0, suite_first = 0;
  for (uint64_t s = 10; s < 22; ++s) {
    CheckContext c0;
    c0.seed = check_seed(s, "c.flaky", 0);
    const bool f = seed_bit(c0, 3);
    CheckContext b0;
    b0.seed = check_seed(s, "c.broken", 0);
    const bool b_rejects_first = seed_bit(b0, 5);
    const bool b_fail = b_rejects_first;  // its rerun (sample_scale 4) always rejects
    CheckContext n0, n1;
    n0.seed = check_seed(s, "c.negative_control.x", 0);
    n1.seed = check_seed(s, "c.negative_control.x", 1);
    const bool missed = seed_bit(n0, 7) && seed_bit(n1, 7);
    flaky_first += f;
    broken_fail += b_fail;
    control_missed += missed;
    suite_fail += b_fail;
    suite_first += f || b_rejects_first;
  }
  EXPECT_EQ(j["seeds_done"], 12);
  const auto& per = j["checks"];
  ASSERT_EQ(per.size(), 3u);
  EXPECT_EQ(per[0]["first_attempt_rejected"]["count"], flaky_first);
  EXPECT_EQ(per[0]["failed"]["count"], 0);
  EXPECT_EQ(per[1]["failed"]["count"], broken_fail);
  EXPECT_DOUBLE_EQ(per[1]["alpha"].get<double>(), 0.05);
  EXPECT_EQ(per[2]["missed"]["count"], control_missed);
  EXPECT_EQ(j["suite_failed"]["count"], suite_fail);
  EXPECT_EQ(j["suite_first_attempt_rejected"]["count"], suite_first);
  EXPECT_NEAR(j["bound_suite_failure"].get<double>(), kRerunAlphaFactor * (0.01 * 0.01 + 0.05 * 0.05), 1e-15);
  EXPECT_GT(flaky_first, 0);
  EXPECT_LT(flaky_first, 12);
  // Each seed's records are kept, and the summary is on disk.
  EXPECT_TRUE(std::filesystem::exists(std::filesystem::path(dir) / "calibrate" / "seed-15" / "records" / "c.flaky.json"));
  EXPECT_TRUE(std::filesystem::exists(std::filesystem::path(dir) / "calibrate.json"));
  std::filesystem::remove_all(dir);
}

// The rerun is judged at kRerunAlphaFactor times the check's alpha when its rejection is by its
// p-value; a rejection for another reason (p at or above alpha, no p), a p below the rerun level,
// and controls keep failing.
TEST(Runner, RerunIsJudgedAtTheRerunLevel) {
  const auto with_rerun = [](std::string name, double rerun_p, bool p_rejects = true) {
    return make_check(std::move(name), CheckKind::kStatistical, [=](const CheckContext& ctx) {
      CheckResult r;
      r.alpha = 0.01;
      r.p_value = ctx.sample_scale > 1.0 ? rerun_p : 1e-6;
      r.passed = !p_rejects ? false : r.p_value >= r.alpha;
      return r;
    });
  };
  RunOptions opt;
  const double level = kRerunAlphaFactor * 0.01;
  EXPECT_EQ(run_one(with_rerun("r.between", 2.0 * level), opt)["verdict"], "pass-on-rerun");
  EXPECT_TRUE(run_one(with_rerun("r.between", 2.0 * level), opt).value("rerun_passed_at_rerun_level", false));
  EXPECT_EQ(run_one(with_rerun("r.below", 0.5 * level), opt)["verdict"], "fail");
  EXPECT_EQ(run_one(with_rerun("r.other_reason", 0.5, false), opt)["verdict"], "fail");
  EXPECT_EQ(run_one(with_rerun("r.negative_control.x", 2.0 * level), opt)["verdict"], "fail");
  EXPECT_EQ(run_one(with_rerun("r.control.x", 2.0 * level), opt)["verdict"], "fail");
  // The reproducer of the rerun (--attempt 1) gives the same verdict.
  RunOptions direct;
  direct.attempt = 1;
  EXPECT_TRUE(run_one(with_rerun("r.between", 2.0 * level), direct).value("passed", false));
  EXPECT_FALSE(run_one(with_rerun("r.below", 0.5 * level), direct).value("passed", true));
  // Negative control of the policy: with the factor 1 the first case fails as before.
  RunOptions plain;
  plain.rerun_alpha_factor = 1.0;
  EXPECT_EQ(run_one(with_rerun("r.between", 2.0 * level), plain)["verdict"], "fail");
}

}  // namespace
}  // namespace tb
