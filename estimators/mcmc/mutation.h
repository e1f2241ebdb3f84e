// Mutations as registered components (Veach 1997, Sec. 11.4: "a mixture of mutation strategies";
// Otsu et al., Sec. 3.2: strategy j chosen with the state-dependent suitability s(j | x)). A
// mutation is one object behind one interface: its name, its selection weight at a state (0 where
// it does not apply), its proposal, its density T(x -> y) in the measure of the state space, and an
// optional step scale that may depend on the region of the state (regional adaptive MLT replaces
// it with a per-region scale). A MutationMixture over any list of them is a ProposalMixture, so the
// Metropolis-Hastings kernel, the one chain step and every checker take a new mutation without
// further code: adding one is a class and a registration line in the state space's table.
#pragma once

#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "estimators/mcmc/concepts.h"
#include "estimators/mcmc/proposal_mixture.h"

namespace tb::mcmc {

template <class S>
class Mutation {
 public:
  using State = S;
  virtual ~Mutation() = default;
  virtual std::string name() const = 0;
  // Unnormalised selection weight w(x) >= 0; c_k(x) = w_k(x) / sum_j w_j(x). 0: does not apply at x.
  virtual double weight(const State& x) const = 0;
  // y ~ T(x -> .) (empty: the proposal failed, the chain stays).
  virtual std::optional<State> propose(const State& x, Uniforms& u) const = 0;
  // T(x -> y), Jacobians included, in the reference measure of the state space.
  virtual double density(const State& x, const State& y) const = 0;
  // The step scale the mutation uses at x (1 unless the mutation has a region-dependent scale).
  virtual double scale(const State&) const { return 1.0; }
};

template <class S>
using MutationList = std::vector<std::shared_ptr<const Mutation<S>>>;

// A ProposalMixture over registered mutations: c_k(x) = w_k(x) / sum_j w_j(x).
template <class S>
class MutationMixture {
 public:
  using State = S;
  MutationMixture() = default;
  explicit MutationMixture(MutationList<S> parts) : parts_(std::move(parts)) {}

  int components() const { return static_cast<int>(parts_.size()); }
  const Mutation<S>& component(int k) const { return *parts_[static_cast<size_t>(k)]; }
  std::string name(int k) const { return component(k).name(); }
  const MutationList<S>& parts() const { return parts_; }

  double selection(int k, const State& x) const {
    double sum = 0.0, wk = 0.0;
    for (int j = 0; j < components(); ++j) {
      const double w = component(j).weight(x);
      if (j == k) wk = w;
      sum += w;
    }
    return sum > 0.0 && wk > 0.0 ? wk / sum : 0.0;
  }
  // All weights at x into w (resized); returns their sum. A chain caches them for its state.
  double weights(const State& x, std::vector<double>* w) const {
    w->resize(parts_.size());
    double sum = 0.0;
    for (size_t j = 0; j < parts_.size(); ++j) sum += (*w)[j] = parts_[j]->weight(x);
    return sum;
  }
  // The component for uniform v, by inversion of the running sum of weights (one pass over the
  // weights; -1 when no component applies at x).
  int select(const State& x, double v) const {
    thread_local std::vector<double> w;
    return select_from(w, weights(x, &w), v);
  }
  // The same from weights already computed (w, their sum).
  static int select_from(const std::vector<double>& w, double sum, double v) {
    if (!(sum > 0.0)) return -1;
    const double target = v * sum;
    double acc = 0.0;
    int last_positive = -1;
    for (size_t j = 0; j < w.size(); ++j) {
      if (w[j] > 0.0) last_positive = static_cast<int>(j);
      acc += w[j];
      if (target < acc && w[j] > 0.0) return static_cast<int>(j);
    }
    return last_positive;  // rounding: the sum fell just below target
  }
  std::optional<State> propose(int k, const State& x, Uniforms& u) const { return component(k).propose(x, u); }
  double density(int k, const State& x, const State& y) const { return component(k).density(x, y); }

 private:
  MutationList<S> parts_;
};

// A Proposal (concepts.h) as a registered mutation with a constant weight.
template <Proposal P>
class ProposalMutation final : public Mutation<typename P::State> {
 public:
  using State = typename P::State;
  ProposalMutation(std::string name, double weight, P p) : name_(std::move(name)), weight_(weight), p_(std::move(p)) {}
  std::string name() const override { return name_; }
  double weight(const State&) const override { return weight_; }
  std::optional<State> propose(const State& x, Uniforms& u) const override { return p_.propose(x, u); }
  double density(const State& x, const State& y) const override { return p_.density(x, y); }
  const P& proposal() const { return p_; }

 private:
  std::string name_;
  double weight_;
  P p_;
};

// A registry table of mutation entries (each with a `name`): lookup, run-time registration (a name
// registered twice is an error) and removal. The state spaces' registries (path space, primary
// sample space) are such tables.
template <class Info>
const Info* find_named(const std::vector<Info>& table, const std::string& name) {
  for (const Info& e : table)
    if (e.name == name) return &e;
  return nullptr;
}
template <class Info>
void add_named(std::vector<Info>& table, Info info, const char* what) {
  if (find_named(table, info.name)) throw std::invalid_argument(std::string(what) + " registered twice: " + info.name);
  table.push_back(std::move(info));
}
template <class Info>
void remove_named(std::vector<Info>& table, const std::string& name) {
  std::erase_if(table, [&](const Info& e) { return e.name == name; });
}

}  // namespace tb::mcmc
