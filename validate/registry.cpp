#include "validate/registry.h"

#include <algorithm>
#include <stdexcept>

namespace tb {

Registry& Registry::global() {
  static Registry r;
  return r;
}

void Registry::add(Check c) {
  if (c.name.empty() || !c.run) throw std::logic_error("check without a name or a run function");
  for (const Check& e : checks_)
    if (e.name == c.name) throw std::logic_error("check registered twice: " + c.name);
  auto it = std::lower_bound(checks_.begin(), checks_.end(), c.name,
                             [](const Check& a, const std::string& n) { return a.name < n; });
  checks_.insert(it, std::move(c));
}

namespace {
// Glob match with '*' (any run of characters) and '?' (one character).
bool glob_match(const char* p, const char* s) {
  if (*p == '\0') return *s == '\0';
  if (*p == '*') return glob_match(p + 1, s) || (*s != '\0' && glob_match(p, s + 1));
  if (*s != '\0' && (*p == '?' || *p == *s)) return glob_match(p + 1, s + 1);
  return false;
}
}  // namespace

std::vector<const Check*> Registry::select(const std::vector<std::string>& patterns) const {
  std::vector<const Check*> out;
  for (const Check& c : checks_) {
    bool take = patterns.empty();
    for (const std::string& p : patterns) {
      if (c.name == p || c.name.rfind(p + ".", 0) == 0 || glob_match(p.c_str(), c.name.c_str())) take = true;
    }
    if (take) out.push_back(&c);
  }
  return out;
}

}  // namespace tb
