// Multi-vertex filtering's denominator (estimators/mmis_filtering.h, West et al. 2022, Eq. 14): the product
// of per-kernel sums equals the explicit sum over every prefix combination, costs Σ_k m_k evaluations,
// picks the sample's own factors out of the same evaluations, and its weights over all combinations
// sum to one. The random-case version with negative controls is validate/checks/mmis_filtering_checks.cpp.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "estimators/mmis_filtering.h"

namespace tb {
namespace {

// p_k(x_k | y_{k,j}) of one output sample over three kernels with 2, 3 and 1 prefixes.
const std::vector<std::vector<double>> kTable{{0.5, 2.0}, {1.0, 0.25, 3.0}, {0.7}};
const std::vector<int> kPrefixes{2, 3, 1};
double table(size_t k, int j) { return kTable[k][static_cast<size_t>(j)]; }

TEST(MmisFiltering, ProductOfSumsEqualsTheEnumeration) {
  int64_t fast = 0, slow = 0;
  const double p = filtering_product_of_sums(std::span<const int>(kPrefixes), table, &fast);
  const double e = filtering_sum_of_products(std::span<const int>(kPrefixes), table, &slow);
  EXPECT_NEAR(p, 2.5 * 4.25 * 0.7, 1e-15);
  EXPECT_NEAR(p, e, 1e-12 * e);
  EXPECT_EQ(fast, 2 + 3 + 1);
  EXPECT_EQ(slow, 3 * (2 * 3 * 1));
  EXPECT_EQ(filtering_technique_count(std::span<const int>(kPrefixes)), 6);
}

TEST(MmisFiltering, OwnWeightAndWeightsSumToOne) {
  const std::vector<int> own{1, 2, 0};
  int64_t calls = 0;
  const auto counted = [&](size_t k, int j) {
    ++calls;
    return table(k, j);
  };
  const double classical = 0.3;
  const FilteringWeight w = filtering_mmis_weight(std::span<const int>(kPrefixes), std::span<const int>(own), counted, classical);
  EXPECT_EQ(calls, 6);  // the own factors come from the same evaluations
  EXPECT_EQ(w.pdf_evals, 6);
  EXPECT_DOUBLE_EQ(w.own_pdf, 2.0 * 3.0 * 0.7);
  EXPECT_NEAR(w.denominator, classical + 2.5 * 4.25 * 0.7, 1e-15);
  EXPECT_DOUBLE_EQ(w.weight, w.own_pdf / w.denominator);
  // Σ over every combination j̄ of Π_k p_k / D, plus the classical technique's classical / D, is one.
  double sum = classical / w.denominator;
  std::vector<int> j(3, 0);
  int combinations = 0;
  do {
    sum += table(0, j[0]) * table(1, j[1]) * table(2, j[2]) / w.denominator;
    ++combinations;
  } while (next_filtering_combination(std::span<int>(j), std::span<const int>(kPrefixes)));
  EXPECT_EQ(combinations, 6);
  EXPECT_NEAR(sum, 1.0, 1e-12);
}

TEST(MmisFiltering, EmptyKernelHasNoTechnique) {
  const std::vector<int> m{2, 0};
  EXPECT_EQ(filtering_sum_of_products(std::span<const int>(m), table), 0.0);
  EXPECT_EQ(filtering_product_of_sums(std::span<const int>(m), table), 0.0);
}

}  // namespace
}  // namespace tb
