// Runs registered checks the way docs/validation.md prescribes: a scrambled seed per check
// (hash of the run seed and the check's name), a rerun with a fresh seed and 4x the samples
// when a statistical check rejects (fail only if the rerun rejects too, report both), one
// record per check written atomically as soon as it finishes (so an interrupted run loses
// nothing and `--resume` picks up where it stopped), and a reproducer for every failure.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "validate/registry.h"

namespace tb {

inline constexpr double kRerunAlphaFactor = 0.05;

// Controls (a broken variant that must be caught): names containing "negative_control" or
// ".control."; they pass by rejecting, so the power and false-alarm figures leave them out.
bool is_control_check(const std::string& name);

struct RunOptions {
  uint64_t seed = 1;
  bool full = false;
  int attempt = 0;           // 0: normal run; k >= 1: run directly the k-th rerun (fresh seed, 4x samples)
  std::string out_dir;       // where records/ and results.json go ("" = write nothing)
  bool resume = false;       // reuse records in out_dir/records that match seed and size
  // Called before and after each check (index, total, check, record or null when starting).
  std::function<void(size_t, size_t, const Check&, const nlohmann::json*)> on_check = {};
  // Progress of the running check in [0, 1]; may be called from any thread.
  std::function<void(double)> on_progress = [](double) {};
  const std::atomic<bool>* interrupted = nullptr;  // stop between checks when set
  // The rerun's level is this factor times the check's alpha (docs/statistics.md, "The suite's
  // false-alarm rate"): under H0 a check then fails with probability <= factor alpha^2, and the
  // quick suite's sum of alpha^2 (0.0129) gives a suite-level rate <= 6.4e-4 by construction.
  // Applied where the rerun's rejection is by its p-value (p < alpha recorded) and the check is
  // not a control; any other rejection of the rerun fails the check as before.
  double rerun_alpha_factor = kRerunAlphaFactor;
};

// The seed a check's context receives for a given run seed and attempt.
uint64_t check_seed(uint64_t run_seed, const std::string& name, int attempt);
// The command that reproduces one check's result.
std::string reproducer_command(const std::string& name, uint64_t run_seed, bool full, int attempt);

// Runs one check (with its rerun policy) and returns its record:
// {"name", "passed", "verdict": "pass" | "pass-on-rerun" | "fail", "first": CheckResult,
//  "rerun": CheckResult (if any), "kind", "description", "full", "run_seed"}.
nlohmann::json run_one(const Check& check, const RunOptions& opt);

struct RunSummary {
  nlohmann::json results;  // {"config": {...}, "checks": [records...], "passed": n, "failed": n}
  size_t passed = 0, failed = 0, resumed = 0;
  bool interrupted = false;
};

RunSummary run_checks(const std::vector<const Check*>& checks, const RunOptions& opt);

// `tb check --calibrate K` (docs/statistics.md, "The suite's false-alarm rate"): runs the checks
// under K run seeds (base.seed, base.seed + 1, ...; records of seed s under
// base.out_dir/calibrate/seed-s, so an interrupted calibration resumes with base.resume) and
// measures, with 95% Clopper-Pearson intervals: per check, the rate of first-attempt rejections
// and of final failures (after the rerun); for negative controls, the rate at which they are
// missed; for the suite, the rate of seeds on which any check (controls aside) fails. It also
// states the bound by construction: under H0 the two attempts are independent, so a check fails
// with probability alpha * (rerun_alpha_factor alpha) and the suite with at most the sum.
// on_seed is called after each seed with its summary; the result is rewritten after each seed
// to base.out_dir/calibrate.json when base.out_dir is set.
nlohmann::json calibrate_checks(const std::vector<const Check*>& checks, const RunOptions& base, int seeds,
                                const std::function<void(int, const RunSummary&)>& on_seed = {});

// The power of a run's checks (docs/statistics.md, "What a passing check rules out"): how many
// state their minimum detectable effect (CheckResult::min_detectable_effect, of the first
// attempt), and, per effect kind, how many detect `target` (default 2%) at 90% power and which
// do not, largest first: {"stated": n, "not_stated": n (statistical checks that state none, named in
// "not_stated_checks"), "deterministic": n (no p-value, no effect size), "target": t, "kinds": {kind: {"checks": n,
// "meet_target": n, "median": m, "above_target": [{"name", "mde", "samples_scale_for_target"}...]}}}
// (the factor on the samples that would reach the target, (mde / target)^2). Negative controls are
// left out (their job is to be rejected, not to bound a bias).
nlohmann::json power_summary(const nlohmann::json& check_records, double target = 0.02);

}  // namespace tb
