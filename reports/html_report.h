// The HTML reports: made from the JSON results alone (results.json of `tb check`,
// report.json of `tb reproduce`), so a report can be regenerated from its file.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

namespace tb {

std::string html_escape(const std::string& s);

// Writes OUT_DIR/index.html (and plots under OUT_DIR/plots/) for a `tb check` run.
void write_check_report(const nlohmann::json& results, const std::string& out_dir);

// Writes OUT_DIR/index.html for one experiment of `tb reproduce`.
void write_experiment_report(const std::string& name, const nlohmann::json& report, const std::string& out_dir);

// The <style> element shared by the reports (for report pages written elsewhere in reports/).
std::string report_style();

}  // namespace tb
