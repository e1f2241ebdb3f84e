// Image comparisons over groups of pixels, for MCMC renderers whose per-pixel estimates are too
// heavy-tailed for a per-pixel Welch test.
//
// Why: a Metropolis light transport chain started by importance resampling (docs/mlt-path-space.md)
// gives an unbiased image for every chain length, but a pixel whose paths form a mode the
// mutations rarely enter is carried only by the chains that start in it (or wander into it).
// With C chains and a pixel holding a share s of the image's luminance, about C s chains start
// there; when C s is of order one, the chain average is a sum of a few large values and mostly
// zero, its sample variance underestimates the spread, and Welch's t rejects far more often
// than alpha (measured: docs/mlt-path-space.md, "pixels carried by few chains").
//
// The remedy is to compare sums over groups of pixels whose reference share is at least
// min_share = K / C, so that K chains are expected to start in each group: the per-chain group
// sum then averages over many chains' worth of mass and the t statistic regains its
// distribution. Groups are cut from the pixels in Morton (Z) order, so that a group is a
// compact block of the image where the image is dim and a single pixel where it is bright; the
// grouping uses only the reference, never the image under test.
#pragma once

#include <vector>

#include "lib/core/spectrum.h"
#include "lib/film/film.h"
#include "lib/film/welch_image.h"

namespace tb {

// Group index of every pixel (row-major): consecutive pixels in Morton order share a group
// until the group's luminance reaches min_share of the image total; a pixel holding that share
// on its own is a group of its own (the open pixels before it join the previous group); a
// remainder below the share joins the previous group. All pixels belong to some group. A reference with zero total gives one
// group.
std::vector<int> group_pixels_by_share(const std::vector<Rgb>& reference_mean, int width, int height,
                                       double min_share);

int group_count(const std::vector<int>& groups);

// A Welch image with one "pixel" per group (width = number of groups, height 1): each observed
// pass contributes the sum over the group's pixels of the pass's Welch samples.
class GroupedWelch {
 public:
  explicit GroupedWelch(std::vector<int> groups);
  // Feeds this object every pass of the film (Film::set_pass_observer); the film must outlive
  // neither this object nor the render (the observer is cleared by detach()).
  void attach(Film& film);
  void detach(Film& film);
  void add_pass(const std::vector<Rgb>& pass);
  const WelchImage& welch() const { return welch_; }
  const std::vector<int>& groups() const { return groups_; }

 private:
  std::vector<int> groups_;
  WelchImage welch_;
  std::vector<Rgb> scratch_;
};

}  // namespace tb
