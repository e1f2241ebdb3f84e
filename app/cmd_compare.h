// tb compare: statistical comparison of renders, and equal-time comparison of integrators.
//   tb compare A.exr B.exr [--alpha 0.01] [--json R.json]     (.pfm inputs: exact references)
//   tb compare A.exr --reference-mean R.pfm --reference-variance V.pfm [--alpha] [--json]
//   tb compare SCENE --integrators A,B,... --time S [--reference REF.exr] [-o DIR] ...
// Image form:
// reads two EXRs written by tb render (mean, variance.R/G/B and count channels: the Welch
// statistics of their passes, lib/film/exr_io.h) and runs the tiled (default) or per-pixel Welch
// t-test with the Stouffer and sum-z^2 global tests (validate/image_compare.h). Exit code 0 when the images are
// consistent, 1 when they differ, 2 on bad input.
// Scene form (one positional argument, not an EXR): app/compare_scene.h, docs/compare.md.
// The positional arguments are dispatched on their form; options of one form given with the
// other are an error (settings are strict).
#pragma once

#include <atomic>
#include <string>
#include <vector>

#include "app/compare_scene.h"

namespace tb {

struct CompareArgs {
  std::vector<std::string> inputs;  // A.exr B.exr, or SCENE
  double alpha = 0.01;              // in (0, 1), enforced by the command line (app/cli_domains.h)
  std::string json_out;             // optional: the full result as JSON
  bool skew_correction = false;     // Hall's transformation of t where moment3 is stored (experimental, --test pixel)
  std::string test = "tiled";       // tiled | pixel (validate/image_compare.h, CompareTest)
  int tile = 0;                     // --tile K; 0: chosen from the stored third moments
  // Reference form (tb compare A.exr --reference-mean R.pfm --reference-variance V.pfm): the
  // reference as a mean image and a per-pixel variance of that mean (lib/film/pfm_io.h,
  // welch_from_reference; docs/integrator.md).
  std::string reference_mean, reference_variance;
  CompareSceneArgs scene;           // the scene form's options (scene.scene is set from inputs)
  // Names of the options given on the command line that belong to one form only, so that using
  // them with the other form is reported instead of ignored.
  std::vector<std::string> image_options_given, scene_options_given;
};

int cmd_compare(const CompareArgs& a, const std::atomic<bool>* interrupted = nullptr);

}  // namespace tb
