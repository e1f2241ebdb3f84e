// A sum type of marginal techniques sharing one Sample type, itself a MarginalTechnique: lets one
// MMIS call combine techniques of different families (e.g. an ExtrudedTechnique next to a truly
// marginal one, West et al. 2022 Fig. 1 top). The Aux of alternative k is stored at variant index k.
#pragma once

#include <optional>
#include <utility>
#include <variant>

#include "estimators/concepts.h"

namespace tb {

template <MarginalTechnique First, MarginalTechnique... Rest>
  requires(std::same_as<typename First::Sample, typename Rest::Sample> && ...)
class AnyMarginalTechnique {
 public:
  using Sample = typename First::Sample;
  using Aux = std::variant<typename First::Aux, typename Rest::Aux...>;

  template <class M>
  AnyMarginalTechnique(M m) : v_(std::move(m)) {}

  std::optional<Aux> sample_aux(Uniforms& u) const {
    return visit_indexed([&]<size_t K>(const auto& m) -> std::optional<Aux> {
      auto a = m.sample_aux(u);
      if (!a) return std::nullopt;
      return Aux(std::in_place_index<K>, std::move(*a));
    });
  }
  std::optional<Sample> sample(const Aux& a, Uniforms& u) const {
    return visit_indexed([&]<size_t K>(const auto& m) { return m.sample(std::get<K>(a), u); });
  }
  double pdf(const Sample& x, const Aux& a) const {
    return visit_indexed([&]<size_t K>(const auto& m) { return static_cast<double>(m.pdf(x, std::get<K>(a))); });
  }

 private:
  // Calls f.template operator()<K>(alternative K) for the held alternative.
  template <class F>
  decltype(auto) visit_indexed(F&& f) const {
    return visit_impl(std::forward<F>(f), std::make_index_sequence<1 + sizeof...(Rest)>{});
  }
  template <class F, size_t... K>
  decltype(auto) visit_impl(F&& f, std::index_sequence<K...>) const {
    using R = decltype(f.template operator()<0>(std::get<0>(v_)));
    R r{};
    ((v_.index() == K ? (void)(r = f.template operator()<K>(std::get<K>(v_))) : (void)0), ...);
    return r;
  }
  std::variant<First, Rest...> v_;
};

}  // namespace tb
