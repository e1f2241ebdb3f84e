#include "lib/material/bsdf_registry.h"

#include <functional>
#include <set>
#include <stdexcept>

#include "lib/material/lambert.h"
#include "lib/material/rough_conductor.h"
#include "lib/material/rough_dielectric.h"
#include "lib/material/smooth_conductor.h"
#include "lib/material/smooth_dielectric.h"

namespace tb {
namespace {

// Reads parameters and remembers which were read, so that unused keys can be reported.
class Params {
 public:
  Params(std::string_view owner, const nlohmann::json& j) : owner_(owner), j_(j) {
    if (!j_.is_object()) fail("parameters must be a JSON object");
  }
  double number(const char* key, double def) {
    if (!take(key)) return def;
    if (!j_[key].is_number()) fail(std::string("'") + key + "' must be a number");
    return j_[key].get<double>();
  }
  bool boolean(const char* key, bool def) {
    if (!take(key)) return def;
    if (!j_[key].is_boolean()) fail(std::string("'") + key + "' must be true or false");
    return j_[key].get<bool>();
  }
  std::string string(const char* key, const char* def) {
    if (!take(key)) return def;
    if (!j_[key].is_string()) fail(std::string("'") + key + "' must be a string");
    return j_[key].get<std::string>();
  }
  // An RGB triple [r, g, b] or a single number (grey).
  Rgb rgb(const char* key, const Rgb& def) {
    if (!take(key)) return def;
    const nlohmann::json& v = j_[key];
    if (v.is_number()) return Rgb(v.get<double>());
    if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() || !v[2].is_number())
      fail(std::string("'") + key + "' must be a number or [r, g, b]");
    return {v[0].get<double>(), v[1].get<double>(), v[2].get<double>()};
  }
  void finish() const {
    for (auto it = j_.begin(); it != j_.end(); ++it)
      if (!used_.count(it.key())) fail("unknown parameter '" + it.key() + "'");
  }

 private:
  bool take(const char* key) {
    used_.insert(key);
    return j_.contains(key);
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw std::invalid_argument("bsdf '" + owner_ + "': " + what);
  }
  std::string owner_;
  const nlohmann::json& j_;
  std::set<std::string> used_;
};

// Gold-like RGB conductor index (approximate values at 650/550/450 nm).
const Rgb kDefaultConductorEta(0.2, 0.92, 1.1);
const Rgb kDefaultConductorK(3.9, 2.45, 2.14);

MicrofacetDistribution read_distribution(Params& p) {
  const MicrofacetType type = microfacet_type_from_string(p.string("distribution", "ggx"));
  const double alpha = p.number("alpha", 0.1);
  if (!(alpha > 0)) throw std::invalid_argument("bsdf: 'alpha' must be > 0");
  return MicrofacetDistribution::from_beckmann_equivalent(type, alpha);
}

using Factory = std::function<std::unique_ptr<Bsdf>(Params&)>;

// The table of components: adding a BSDF adds one row.
const std::vector<std::pair<std::string, Factory>>& table() {
  static const std::vector<std::pair<std::string, Factory>> t = {
      {"lambert", [](Params& p) { return std::make_unique<LambertBsdf>(p.rgb("reflectance", Rgb(0.5))); }},
      {"smooth_conductor",
       [](Params& p) {
         const Rgb eta = p.rgb("eta", kDefaultConductorEta);
         return std::make_unique<SmoothConductorBsdf>(eta, p.rgb("k", kDefaultConductorK));
       }},
      {"smooth_dielectric", [](Params& p) { return std::make_unique<SmoothDielectricBsdf>(p.number("eta", 1.5)); }},
      {"rough_conductor",
       [](Params& p) {
         const Rgb eta = p.rgb("eta", kDefaultConductorEta);
         const Rgb k = p.rgb("k", kDefaultConductorK);
         const MicrofacetDistribution d = read_distribution(p);
         return std::make_unique<RoughConductorBsdf>(d, eta, k, p.boolean("visible_normals", false));
       }},
      {"rough_dielectric",
       [](Params& p) {
         const double eta = p.number("eta", 1.5);
         const MicrofacetDistribution d = read_distribution(p);
         return std::make_unique<RoughDielectricBsdf>(d, eta, p.boolean("visible_normals", false));
       }},
  };
  return t;
}

}  // namespace

std::unique_ptr<Bsdf> make_bsdf(std::string_view name, const nlohmann::json& params) {
  for (const auto& [n, factory] : table()) {
    if (n != name) continue;
    Params p(name, params);
    std::unique_ptr<Bsdf> b = factory(p);
    p.finish();
    return b;
  }
  std::string known;
  for (const auto& [n, f] : table()) known += (known.empty() ? "" : ", ") + n;
  throw std::invalid_argument("unknown bsdf '" + std::string(name) + "' (known: " + known + ")");
}

std::vector<std::string> bsdf_names() {
  std::vector<std::string> v;
  for (const auto& [n, f] : table()) v.push_back(n);
  return v;
}

}  // namespace tb
