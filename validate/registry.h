// The registry of named checks that `tb check` runs. A check is a function of a context
// (seed, size) that returns a CheckResult; it registers itself from a .cpp file in
// validate/checks/ with TB_REGISTER_CHECK, so adding a check needs no edit elsewhere.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "validate/check_result.h"

namespace tb {

struct CheckContext {
  uint64_t seed = 1;         // run seed; derive streams with Rng::for_sample(seed, key, i)
  bool full = false;         // --full: the larger sample sizes of docs/validation.md
  double sample_scale = 1.0; // multiplier on sample counts (the runner's 4x rerun uses 4)
  // Reports progress in [0, 1]; may be called from any thread.
  std::function<void(double)> progress = [](double) {};

  // Picks the quick or full size and applies sample_scale.
  int64_t size(int64_t quick, int64_t full_size) const {
    return static_cast<int64_t>(static_cast<double>(full ? full_size : quick) * sample_scale);
  }
};

enum class CheckKind {
  kStatistical,    // may fail by chance at rate alpha: rerun once with a fresh seed, 4x samples
  kDeterministic,  // no chance involved (identities, finite differences): never rerun
};

struct Check {
  std::string name;         // "core.warp.cosine_hemisphere.chi2": group.subject.what
  std::string description;  // one sentence: what is checked, against what
  CheckKind kind = CheckKind::kStatistical;
  std::function<CheckResult(const CheckContext&)> run;
};

class Registry {
 public:
  static Registry& global();
  void add(Check c);
  const std::vector<Check>& checks() const { return checks_; }
  // Checks whose name equals, or starts with "pattern.", or matches a glob with '*'.
  std::vector<const Check*> select(const std::vector<std::string>& patterns) const;

 private:
  std::vector<Check> checks_;
};

// Registers a check whose run also receives its own name (for its seeds and messages).
inline void add_named_check(const std::string& name, const std::string& desc, CheckKind kind,
                            std::function<CheckResult(const CheckContext&, const std::string&)> f) {
  Registry::global().add(
      Check{.name = name, .description = desc, .kind = kind, .run = [=](const CheckContext& cx) { return f(cx, name); }});
}

struct CheckRegistrar {
  explicit CheckRegistrar(Check c) { Registry::global().add(std::move(c)); }
};

}  // namespace tb

#define TB_CHECK_CONCAT_(a, b) a##b
#define TB_CHECK_CONCAT(a, b) TB_CHECK_CONCAT_(a, b)
// TB_REGISTER_CHECK({.name = ..., .description = ..., .kind = ..., .run = ...});
#define TB_REGISTER_CHECK(...) \
  static const ::tb::CheckRegistrar TB_CHECK_CONCAT(tb_check_registrar_, __LINE__){::tb::Check __VA_ARGS__}
