#include "validate/check_result.h"

#include <cmath>

namespace tb {

namespace {
// JSON has no NaN or Inf: write them as strings so nothing is lost silently.
nlohmann::json number(double v) {
  if (std::isfinite(v)) return v;
  if (std::isnan(v)) return "NaN";
  return v > 0 ? "Inf" : "-Inf";
}
nlohmann::json numbers(const std::vector<double>& v) {
  nlohmann::json a = nlohmann::json::array();
  for (double x : v) a.push_back(number(x));
  return a;
}
}  // namespace

void to_json(nlohmann::json& j, const PlotSeries& s) {
  j = {{"label", s.label}, {"x", numbers(s.x)}, {"y", numbers(s.y)}, {"style", s.style}};
  if (!s.y_err.empty()) j["y_err"] = numbers(s.y_err);
}

void to_json(nlohmann::json& j, const PlotSpec& p) {
  j = {{"title", p.title}, {"x_label", p.x_label}, {"y_label", p.y_label},
       {"log_x", p.log_x}, {"log_y", p.log_y},     {"series", p.series}};
  if (!p.heatmap.empty()) {
    nlohmann::json rows = nlohmann::json::array();
    for (const auto& r : p.heatmap) rows.push_back(numbers(r));
    j["heatmap"] = rows;
    j["extent"] = {p.x_min, p.x_max, p.y_min, p.y_max};
  }
}

void to_json(nlohmann::json& j, const CheckResult& r) {
  j = {{"name", r.name},
       {"passed", r.passed},
       {"statistic_name", r.statistic_name},
       {"statistic", number(r.statistic)},
       {"p_value", r.p_value < 0 ? nlohmann::json(nullptr) : number(r.p_value)},
       {"alpha", number(r.alpha)},
       {"samples", r.samples},
       {"message", r.message},
       {"min_detectable_effect", std::isfinite(r.min_detectable_effect) ? number(r.min_detectable_effect) : nlohmann::json(nullptr)},
       {"effect_kind", r.effect_kind},
       {"seed", r.seed},
       {"seconds", r.seconds},
       {"reproducer", r.reproducer},
       {"details", r.details},
       {"plots", r.plots}};
}

}  // namespace tb
