// Sampling an index from non-negative weights. Two implementations of one distribution:
//  - AliasTable: Vose's alias method (Vose 1991, "A linear algorithm for generating random
//    numbers with a given distribution"), O(1) per sample, no inverse.
//  - DiscreteCdf: binary search in the cumulative sums, O(log n), invertible.
// Both return the remapped uniform (the part of u not used to pick the index, again uniform
// on [0, 1)) so a caller can reuse it. Zero weights are never sampled; all-zero, negative or
// non-finite weights give an empty optional from create(). Densities are probability MASSES
// (counting measure on the indices).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

namespace tb {

struct DiscreteSample {
  size_t index = 0;
  double u_remapped = 0;  // uniform on [0, 1), independent of index
};

class AliasTable {
 public:
  static std::optional<AliasTable> create(std::span<const double> weights);

  // u in [0, 1): bin = floor(u n), then the fraction of u decides between the bin and its alias.
  DiscreteSample sample(double u) const;
  double pmf(size_t i) const { return pmf_[i]; }
  size_t size() const { return pmf_.size(); }

 private:
  struct Bin {
    double q = 1;       // probability of keeping the bin (else its alias)
    uint32_t alias = 0;
  };
  std::vector<double> pmf_;
  std::vector<Bin> bins_;
};

class DiscreteCdf {
 public:
  static std::optional<DiscreteCdf> create(std::span<const double> weights);

  DiscreteSample sample(double u) const;
  // The inverse of sample: the u that gives (index, u_remapped).
  double invert(size_t index, double u_remapped) const;
  double pmf(size_t i) const { return cdf_[i + 1] - cdf_[i]; }
  double cdf(size_t i) const { return cdf_[i]; }  // P(index < i)
  size_t size() const { return cdf_.size() - 1; }

 private:
  std::vector<double> cdf_;  // n + 1 entries, cdf_[0] = 0, cdf_[n] = 1
};

}  // namespace tb
