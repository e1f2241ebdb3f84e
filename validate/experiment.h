// Registry of reproducible experiments (`tb reproduce NAME`): a paper's canonical experiment
// run with stated seeds, producing tables, plots and data for the HTML report. Experiments
// register from validate/experiments/*.cpp with TB_REGISTER_EXPERIMENT.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "validate/plot_spec.h"

namespace tb {

struct Table {
  std::string title;
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
};
void to_json(nlohmann::json& j, const Table& t);

struct ExperimentContext {
  uint64_t seed = 1;
  bool full = false;  // full size (paper-scale replicate counts) vs quick
  std::function<void(double)> progress = [](double) {};
};

struct ExperimentReport {
  bool passed = true;            // the experiment's claims (each stated in `claims`) held
  std::string summary;           // paragraphs of plain text: what was run, what it shows
  std::vector<std::string> claims;  // "MMIS beats classical-only: ratio 0.41 [0.38, 0.44] (99% CI)"
  std::vector<Table> tables;
  std::vector<PlotSpec> plots;
  nlohmann::json data = nlohmann::json::object();  // raw numbers and the full configuration
};
void to_json(nlohmann::json& j, const ExperimentReport& r);

struct Experiment {
  std::string name;  // "mmis-fig1"
  std::string description;
  std::function<ExperimentReport(const ExperimentContext&)> run;
};

class ExperimentRegistry {
 public:
  static ExperimentRegistry& global();
  void add(Experiment e);
  const std::vector<Experiment>& experiments() const { return experiments_; }
  const Experiment* find(const std::string& name) const;

 private:
  std::vector<Experiment> experiments_;
};

struct ExperimentRegistrar {
  explicit ExperimentRegistrar(Experiment e) { ExperimentRegistry::global().add(std::move(e)); }
};

}  // namespace tb

#define TB_EXP_CONCAT_(a, b) a##b
#define TB_EXP_CONCAT(a, b) TB_EXP_CONCAT_(a, b)
#define TB_REGISTER_EXPERIMENT(...)                                                         \
  static const ::tb::ExperimentRegistrar TB_EXP_CONCAT(tb_experiment_registrar_, __LINE__){ \
      ::tb::Experiment __VA_ARGS__}
