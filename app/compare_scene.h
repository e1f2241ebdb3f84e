// tb compare SCENE --integrators A,B,... --time S [--reference REF.exr] [-o DIR]: the equal-time
// comparison of integrators on one scene (docs/compare.md).
//
// For each integrator, independent renders with time budgets t_k = S / 2^(K-1-k), k = 0..K-1
// (K = --checkpoints, default 5: S/16, S/8, S/4, S/2, S), each with its own seed, so the rRMSE
// values at different checkpoints are those of independent runs (no film snapshot of one run is
// reused). Each render stops at the end of the pass (MCMC: batch of chains) in which its budget
// runs out; the measured wall time, not the budget, is what the fit and the efficiency use. A pass
// is --pass-spp samples per pixel (MCMC: mutations per pixel), by default 1, and enough for the
// primary-sample-space driver's mutations to outnumber its per-pass bootstrap.
// Per run: rRMSE against the reference (app/compare_metrics.h), efficiency 1 / (rRMSE^2 t), and
// for MCMC integrators mutations/s and acceptance per mutation type (RenderSettings::report).
// Per integrator: a Ceres fit rRMSE = C t^(-alpha) over the checkpoints
// (stats::fit_time_power_law, validate/stats/convergence_fit.h).
// Without --reference a BDPT reference is rendered for 4 S first (announced on stdout).
// Output: DIR/results.json, DIR/index.html (reports/compare_report.h), DIR/images/*.png (the
// renders at S, their relative error maps, the reference), DIR/runs/*.exr|json (every run, used
// by --resume), and the table on stdout.
#pragma once

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

namespace tb {

// The numeric fields' domains are enforced where the command line is parsed (app/cli_domains.h,
// app/main.cpp): K in [3, 16], floor in [0, 1), error scale > 0, threads and pass_spp >= 0.
struct CompareSceneArgs {
  std::string scene;
  std::vector<std::string> integrators;
  double time_s = 0;             // S: the largest checkpoint's budget per integrator
  std::string reference;         // REF.exr; empty: render one with bdpt for 4 S
  std::string out;               // empty: reports/out/compare-<scene stem>
  int checkpoints = 5;           // K >= 3 (the fit has two parameters)
  std::string resolution;        // "WxH" overrides the scene camera's
  int64_t pass_spp = 0;          // samples per pixel per pass; 0: 1, PSS-driver integrators more (.cpp)
  uint64_t seed = 1;
  int threads = 0;               // 0: all cores
  double floor_fraction = 0.01;  // pixel-channels with reference <= this * mean reference are left out
  double error_scale = 0.5;      // relative error shown white in the error maps
  bool resume = false;           // reuse runs of an earlier invocation with the same settings
  bool no_progress = false;
};

// Exit code: 0 done, 2 bad input, 130 interrupted (finished runs are kept; rerun with --resume).
int cmd_compare_scene(const CompareSceneArgs& a, const std::atomic<bool>* interrupted);

}  // namespace tb
