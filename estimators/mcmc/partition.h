// Partitions of a state space into disjoint regions P_1..P_m (Otsu et al., Sec. 4.4 and 5.2; the
// regional adaptive Metropolis of Roberts & Rosenthal 2009, Sec. 3): region_of(x) is the unique k
// with x in P_k. Regional adaptation (adaptation.h, adaptive_chains.h) is generic over any type
// satisfying Partition. Three variants, each a named type, registered by name in
// partition_registry() (Otsu et al., Sec. 8: FIXED, GLOBAL, grid partitions):
//  - FixedPartition:  one region and no adaptation (the scale stays at lambda0);
//  - GlobalPartition: one region, adapted (the adaptive scaling of Andrieu & Thoms 2008);
//  - GridPartition:   a regular grid over a box of R^d; states outside the box fall in the
//                     nearest boundary cell, so the cells cover R^d.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <concepts>
#include <cstddef>
#include <functional>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>

namespace tb::mcmc {

template <class P>
concept Partition = requires(const P& p, const typename P::State& x) {
  typename P::State;
  { p.regions() } -> std::convertible_to<int>;
  { p.region_of(x) } -> std::convertible_to<int>;  // in [0, regions())
  { p.adapts() } -> std::convertible_to<bool>;     // false: the scales are never updated
};

// A partition behind one interface, for the registry.
template <class S>
class RegionPartition {
 public:
  using State = S;
  virtual ~RegionPartition() = default;
  virtual std::string name() const = 0;
  virtual int regions() const = 0;
  virtual int region_of(const State& x) const = 0;
  virtual bool adapts() const = 0;
};

template <size_t N>
class FixedPartition final : public RegionPartition<std::array<double, N>> {
 public:
  using State = std::array<double, N>;
  std::string name() const override { return "fixed"; }
  int regions() const override { return 1; }
  int region_of(const State&) const override { return 0; }
  bool adapts() const override { return false; }
};

template <size_t N>
class GlobalPartition final : public RegionPartition<std::array<double, N>> {
 public:
  using State = std::array<double, N>;
  std::string name() const override { return "global"; }
  int regions() const override { return 1; }
  int region_of(const State&) const override { return 0; }
  bool adapts() const override { return true; }
};

// cells[d] equal cells per dimension over [lo[d], hi[d]); flat index, dimension 0 fastest.
template <size_t N>
class GridPartition final : public RegionPartition<std::array<double, N>> {
 public:
  using State = std::array<double, N>;
  GridPartition(State lo, State hi, std::array<int, N> cells) : lo_(lo), hi_(hi), cells_(cells) {
    for (size_t d = 0; d < N; ++d)
      if (!(hi[d] > lo[d]) || cells[d] < 1) throw std::invalid_argument("GridPartition: empty box or no cells");
  }
  std::string name() const override { return "grid"; }
  int regions() const override {
    int r = 1;
    for (int c : cells_) r *= c;
    return r;
  }
  int cell(size_t d, double v) const {
    const double t = std::floor((v - lo_[d]) / (hi_[d] - lo_[d]) * cells_[d]);
    if (!(t >= 0.0)) return 0;  // below the box (or NaN): first cell
    return t >= cells_[d] ? cells_[d] - 1 : static_cast<int>(t);
  }
  int region_of(const State& x) const override {
    int idx = 0;
    for (size_t d = N; d-- > 0;) idx = idx * cells_[d] + cell(d, x[d]);
    return idx;
  }
  bool adapts() const override { return true; }

 private:
  State lo_, hi_;
  std::array<int, N> cells_;
};

static_assert(Partition<FixedPartition<1>> && Partition<GlobalPartition<2>> && Partition<GridPartition<2>>);
static_assert(Partition<RegionPartition<std::array<double, 1>>>);

// What a registered partition is built from: a box of R^N and cells per dimension (used by the
// grid; the one-region partitions ignore it).
template <size_t N>
struct PartitionBox {
  std::array<double, N> lo{}, hi{};
  std::array<int, N> cells{};
};

template <size_t N>
using PartitionFactory = std::function<std::shared_ptr<const RegionPartition<std::array<double, N>>>(const PartitionBox<N>&)>;

// The partitions by name: "fixed", "global", "grid". register_partition adds one at run time.
template <size_t N>
std::map<std::string, PartitionFactory<N>>& partition_registry() {
  static std::map<std::string, PartitionFactory<N>> r = {
      {"fixed", [](const PartitionBox<N>&) { return std::make_shared<const FixedPartition<N>>(); }},
      {"global", [](const PartitionBox<N>&) { return std::make_shared<const GlobalPartition<N>>(); }},
      {"grid", [](const PartitionBox<N>& b) { return std::make_shared<const GridPartition<N>>(b.lo, b.hi, b.cells); }},
  };
  return r;
}
template <size_t N>
void register_partition(const std::string& name, PartitionFactory<N> f) {
  partition_registry<N>()[name] = std::move(f);
}
template <size_t N>
std::shared_ptr<const RegionPartition<std::array<double, N>>> make_partition(const std::string& name,
                                                                            const PartitionBox<N>& box) {
  const auto& r = partition_registry<N>();
  const auto it = r.find(name);
  if (it == r.end()) throw std::invalid_argument("unknown partition: " + name);
  return it->second(box);
}

}  // namespace tb::mcmc
