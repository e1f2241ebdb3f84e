// tb compare: statistical comparison of renders.
//   tb compare A.exr B.exr [--alpha 0.01]
// reads two EXRs written by tb render (mean, variance.R/G/B and count channels: the Welch
// statistics of their passes, lib/film/exr_io.h) and runs the per-pixel Welch t-test with the
// Stouffer and sum-z^2 global tests (validate/image_compare.h). Exit code 0 when the images are
// consistent, 1 when they differ, 2 on bad input.
// The positional arguments are dispatched on their form so that further forms (a SCENE with
// --integrators for equal-time comparisons) can be added next to the image form.
#pragma once

#include <string>
#include <vector>

namespace tb {

struct CompareArgs {
  std::vector<std::string> inputs;  // A.exr B.exr
  double alpha = 0.01;
  std::string json_out;             // optional: the full result as JSON
};

int cmd_compare(const CompareArgs& a);

}  // namespace tb
