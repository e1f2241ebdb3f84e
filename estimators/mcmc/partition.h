// Partitions of a state space into disjoint regions P_1..P_m (Otsu et al., Sec. 4.4 and 5.2; the
// regional adaptive Metropolis of Roberts & Rosenthal 2009, Sec. 3): region_of(x) is the unique k
// with x in P_k. Regional adaptation (adaptation.h, adaptive_chains.h) is generic over any type
// satisfying Partition. Three variants, each a named type, registered by name in
// partition_registry() (Otsu et al., Sec. 8: FIXED, GLOBAL, grid partitions):
//  - FixedPartition:  one region and no adaptation (the scale stays at lambda0);
//  - GlobalPartition: one region, adapted (the adaptive scaling of Andrieu & Thoms 2008);
//  - GridPartition:   a regular grid over a box of R^d; states outside the box fall in the
//                     nearest boundary cell, so the cells cover R^d;
//  - QuadtreePartition (2d only, "quadtree"): the leaves of a quadtree over a box of R^2 (Otsu et
//                     al., Sec. 6.1-6.2), one region at first; split(leaf) refines a leaf into four
//                     (the driver decides when: Otsu Sec. 6.2, visits above M_split). States
//                     outside the box fall in the nearest boundary leaf.
//  - GridQuadtreePartition (4d, "quadtree4d"): Otsu et al.'s 4d partition (Sec. 5.4, Eq. 7; Sec.
//                     6.3, Fig. 7): an n x n grid over dimensions 0-1 (screen space), each cell
//                     holding its own QuadtreePartition over dimensions 2-3 (the cylindrical
//                     direction at the first non-specular vertex); the regions are the pairs
//                     (cell, leaf). "grid4d" is the 4d GridPartition (N_top^2 x N_bottom^2 cells).
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
#include <utility>
#include <vector>

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
  GridPartition(State lo, State hi, std::array<int, N> cells, std::string name = "grid")
      : lo_(lo), hi_(hi), cells_(cells), name_(std::move(name)) {
    for (size_t d = 0; d < N; ++d)
      if (!(hi[d] > lo[d]) || cells[d] < 1) throw std::invalid_argument("GridPartition: empty box or no cells");
  }
  std::string name() const override { return name_; }
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
  std::string name_;
};

// Otsu et al., Sec. 6.2: regions are the leaves; initially the root (the whole box). Splitting leaf
// r keeps index r for its first child (lower x, lower y) and appends the other three as regions
// regions() .. regions() + 2, so the indices of all other leaves stay valid.
class QuadtreePartition final : public RegionPartition<std::array<double, 2>> {
 public:
  using State = std::array<double, 2>;
  QuadtreePartition(State lo, State hi, int max_depth = 12) : max_depth_(max_depth) {
    if (!(hi[0] > lo[0]) || !(hi[1] > lo[1])) throw std::invalid_argument("QuadtreePartition: empty box");
    nodes_.push_back({lo, hi, {-1, -1, -1, -1}, 0, 0});
    leaf_node_.push_back(0);
  }
  std::string name() const override { return "quadtree"; }
  int regions() const override { return static_cast<int>(leaf_node_.size()); }
  int region_of(const State& x) const override {
    int n = 0;
    while (nodes_[static_cast<size_t>(n)].child[0] >= 0) n = nodes_[static_cast<size_t>(n)].child[quadrant(n, x)];
    return nodes_[static_cast<size_t>(n)].leaf;
  }
  bool adapts() const override { return true; }
  int depth(int leaf) const { return nodes_[static_cast<size_t>(leaf_node_[static_cast<size_t>(leaf)])].depth; }
  State lo(int leaf) const { return nodes_[static_cast<size_t>(leaf_node_[static_cast<size_t>(leaf)])].lo; }
  State hi(int leaf) const { return nodes_[static_cast<size_t>(leaf_node_[static_cast<size_t>(leaf)])].hi; }
  bool can_split(int leaf) const { return depth(leaf) < max_depth_; }
  // Splits a leaf into four; returns the index of the first appended region (-1: at max depth).
  int split(int leaf) {
    if (!can_split(leaf)) return -1;
    const int n = leaf_node_[static_cast<size_t>(leaf)];
    const Node parent = nodes_[static_cast<size_t>(n)];
    const State mid{0.5 * (parent.lo[0] + parent.hi[0]), 0.5 * (parent.lo[1] + parent.hi[1])};
    const int first_new = regions();
    for (int q = 0; q < 4; ++q) {
      Node c;
      c.lo = {q & 1 ? mid[0] : parent.lo[0], q & 2 ? mid[1] : parent.lo[1]};
      c.hi = {q & 1 ? parent.hi[0] : mid[0], q & 2 ? parent.hi[1] : mid[1]};
      c.depth = parent.depth + 1;
      c.leaf = q == 0 ? leaf : first_new + q - 1;
      const int id = static_cast<int>(nodes_.size());
      nodes_.push_back(c);
      nodes_[static_cast<size_t>(n)].child[q] = id;
      if (q == 0)
        leaf_node_[static_cast<size_t>(leaf)] = id;
      else
        leaf_node_.push_back(id);
    }
    nodes_[static_cast<size_t>(n)].leaf = -1;
    return first_new;
  }

 private:
  struct Node {
    State lo{}, hi{};
    std::array<int, 4> child{-1, -1, -1, -1};  // quadrant q: bit 0 upper x half, bit 1 upper y half
    int leaf = -1;                              // region index of a leaf
    int depth = 0;
  };
  int quadrant(int n, const State& x) const {
    const Node& nd = nodes_[static_cast<size_t>(n)];
    return (x[0] >= 0.5 * (nd.lo[0] + nd.hi[0]) ? 1 : 0) + (x[1] >= 0.5 * (nd.lo[1] + nd.hi[1]) ? 2 : 0);
  }
  int max_depth_;
  std::vector<Node> nodes_;
  std::vector<int> leaf_node_;
};

// Otsu et al., Sec. 6.3 (Fig. 7): a grid over (x0, x1) whose every cell holds a quadtree over
// (x2, x3). Regions are numbered cell by cell at first (cell l's root is region l); splitting
// region r (QuadtreePartition::split in its cell) keeps r for the first child and appends the
// other three at regions(), so every other index stays valid (as the 2d quadtree). cell_of(r) is
// the screen cell of region r.
class GridQuadtreePartition final : public RegionPartition<std::array<double, 4>> {
 public:
  using State = std::array<double, 4>;
  GridQuadtreePartition(State lo, State hi, int cells, int max_depth = 12)
      : top_({lo[0], lo[1]}, {hi[0], hi[1]}, {cells, cells}) {
    for (int l = 0; l < cells * cells; ++l) {
      trees_.emplace_back(std::array<double, 2>{lo[2], lo[3]}, std::array<double, 2>{hi[2], hi[3]}, max_depth);
      global_.push_back({l});
      owner_.push_back({l, 0});
    }
  }
  std::string name() const override { return "quadtree4d"; }
  int regions() const override { return static_cast<int>(owner_.size()); }
  int region_of(const State& x) const override {
    const int l = top_.region_of({x[0], x[1]});
    const int leaf = trees_[static_cast<size_t>(l)].region_of({x[2], x[3]});
    return global_[static_cast<size_t>(l)][static_cast<size_t>(leaf)];
  }
  bool adapts() const override { return true; }
  int cells() const { return top_.regions(); }
  int cell_of(int region) const { return owner_[static_cast<size_t>(region)][0]; }
  const QuadtreePartition& tree(int cell) const { return trees_[static_cast<size_t>(cell)]; }
  int leaf_of(int region) const { return owner_[static_cast<size_t>(region)][1]; }
  bool can_split(int region) const { return tree(cell_of(region)).can_split(leaf_of(region)); }
  // Splits region r in its cell's quadtree; returns the first appended region (-1: at max depth).
  int split(int region) {
    const int l = cell_of(region);
    QuadtreePartition& t = trees_[static_cast<size_t>(l)];
    const int first_local = t.split(leaf_of(region));
    if (first_local < 0) return -1;
    const int first = regions();
    for (int q = 0; q < 3; ++q) {
      global_[static_cast<size_t>(l)].push_back(first + q);
      owner_.push_back({l, first_local + q});
    }
    return first;
  }

 private:
  GridPartition<2> top_;
  std::vector<QuadtreePartition> trees_;
  std::vector<std::vector<int>> global_;      // per cell: local leaf -> region
  std::vector<std::array<int, 2>> owner_;     // region -> (cell, local leaf)
};

static_assert(Partition<FixedPartition<1>> && Partition<GlobalPartition<2>> && Partition<GridPartition<2>>);
static_assert(Partition<QuadtreePartition>);
static_assert(Partition<GridQuadtreePartition>);
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

// The partitions by name: "fixed", "global", "grid" (and, in 2d, "quadtree": the root alone; its
// refinement needs the non-const QuadtreePartition; in 4d, "grid4d" and "quadtree4d"). register_partition adds one at run time.
template <size_t N>
std::map<std::string, PartitionFactory<N>>& partition_registry() {
  static std::map<std::string, PartitionFactory<N>> r = [] {
    std::map<std::string, PartitionFactory<N>> m = {
        {"fixed", [](const PartitionBox<N>&) { return std::make_shared<const FixedPartition<N>>(); }},
        {"global", [](const PartitionBox<N>&) { return std::make_shared<const GlobalPartition<N>>(); }},
        {"grid", [](const PartitionBox<N>& b) { return std::make_shared<const GridPartition<N>>(b.lo, b.hi, b.cells); }},
    };
    if constexpr (N == 2)
      m["quadtree"] = [](const PartitionBox<N>& b) { return std::make_shared<const QuadtreePartition>(b.lo, b.hi); };
    // Otsu et al., Sec. 5.4 / 6.3: cells[0] x cells[1] screen cells, cells[2] x cells[3] direction
    // cells per screen cell (grid4d; Sec. 8.1: N_top = 20, N_bottom = 50), or a quadtree per screen
    // cell (quadtree4d, the roots alone; cells[0] = cells[1] = N_top).
    if constexpr (N == 4) {
      m["grid4d"] = [](const PartitionBox<N>& b) {
        return std::make_shared<const GridPartition<N>>(b.lo, b.hi, b.cells, "grid4d");
      };
      m["quadtree4d"] = [](const PartitionBox<N>& b) {
        return std::make_shared<const GridQuadtreePartition>(b.lo, b.hi, b.cells[0]);
      };
    }
    return m;
  }();
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
