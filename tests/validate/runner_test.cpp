#include "validate/runner.h"

#include <filesystem>

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

}  // namespace
}  // namespace tb
