#include "validate/experiment.h"

#include <stdexcept>

namespace tb {

void to_json(nlohmann::json& j, const Table& t) { j = {{"title", t.title}, {"header", t.header}, {"rows", t.rows}}; }

void to_json(nlohmann::json& j, const ExperimentReport& r) {
  j = {{"passed", r.passed}, {"summary", r.summary}, {"claims", r.claims},
       {"tables", r.tables}, {"plots", r.plots},     {"data", r.data}};
}

ExperimentRegistry& ExperimentRegistry::global() {
  static ExperimentRegistry r;
  return r;
}

void ExperimentRegistry::add(Experiment e) {
  if (find(e.name)) throw std::logic_error("experiment registered twice: " + e.name);
  experiments_.push_back(std::move(e));
}

const Experiment* ExperimentRegistry::find(const std::string& name) const {
  for (const Experiment& e : experiments_)
    if (e.name == name) return &e;
  return nullptr;
}

}  // namespace tb
