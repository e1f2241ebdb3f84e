#include "validate/render/pixel_groups.h"

#include <algorithm>
#include <cstdint>
#include <stdexcept>

namespace tb {

namespace {

// Interleaves the bits of x and y (x in the even bits): the Morton code of a pixel.
uint64_t morton(uint32_t x, uint32_t y) {
  auto spread = [](uint64_t v) {
    v &= 0xffffffffULL;
    v = (v | (v << 16)) & 0x0000ffff0000ffffULL;
    v = (v | (v << 8)) & 0x00ff00ff00ff00ffULL;
    v = (v | (v << 4)) & 0x0f0f0f0f0f0f0f0fULL;
    v = (v | (v << 2)) & 0x3333333333333333ULL;
    v = (v | (v << 1)) & 0x5555555555555555ULL;
    return v;
  };
  return spread(x) | (spread(y) << 1);
}

}  // namespace

std::vector<int> group_pixels_by_share(const std::vector<Rgb>& reference_mean, int width, int height,
                                       double min_share) {
  const size_t P = static_cast<size_t>(width) * static_cast<size_t>(height);
  if (reference_mean.size() != P) throw std::invalid_argument("group_pixels_by_share: image size mismatch");
  std::vector<size_t> order(P);
  for (size_t i = 0; i < P; ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return morton(uint32_t(a % size_t(width)), uint32_t(a / size_t(width))) <
           morton(uint32_t(b % size_t(width)), uint32_t(b / size_t(width)));
  });
  double total = 0.0;
  for (const Rgb& c : reference_mean) total += std::max(0.0, luminance(c));
  std::vector<int> group(P, 0);
  if (!(total > 0.0)) return group;
  const double need = min_share * total;
  int g = 0;
  double acc = 0.0;
  std::vector<size_t> open;  // pixels of the current, not yet closed group
  for (size_t i : order) {
    const double li = std::max(0.0, luminance(reference_mean[i]));
    // A pixel that holds the share on its own is a group of its own: the open pixels before it
    // join the previous group, or, when there is none yet, stay open in the next one.
    if (li >= need && !open.empty()) {
      if (g > 0) {
        for (size_t j : open) group[j] = g - 1;
        open.clear();
        acc = 0.0;
      } else {
        group[i] = g++;
        for (size_t j : open) group[j] = g;
        continue;
      }
    }
    group[i] = g;
    open.push_back(i);
    acc += li;
    if (acc >= need) {
      ++g;
      acc = 0.0;
      open.clear();
    }
  }
  if (!open.empty() && g > 0)  // the remainder below min_share joins the last closed group
    for (size_t i : open) group[i] = g - 1;
  return group;
}

int group_count(const std::vector<int>& groups) {
  int n = 0;
  for (int g : groups) n = std::max(n, g + 1);
  return n;
}

GroupedWelch::GroupedWelch(std::vector<int> groups)
    : groups_(std::move(groups)), welch_(group_count(groups_), 1), scratch_(size_t(group_count(groups_))) {}

void GroupedWelch::attach(Film& film) {
  if (static_cast<size_t>(film.pixel_count()) != groups_.size())
    throw std::invalid_argument("GroupedWelch: film size does not match the grouping");
  film.set_pass_observer([this](const std::vector<Rgb>& pass) { add_pass(pass); });
}

void GroupedWelch::detach(Film& film) { film.set_pass_observer({}); }

void GroupedWelch::add_pass(const std::vector<Rgb>& pass) {
  std::fill(scratch_.begin(), scratch_.end(), Rgb(0.0));
  for (size_t i = 0; i < pass.size() && i < groups_.size(); ++i) scratch_[size_t(groups_[i])] += pass[i];
  for (size_t g = 0; g < scratch_.size(); ++g) welch_.add(g, scratch_[g]);
}

}  // namespace tb
