#include "reports/html_report.h"

#include <cmath>
#include <filesystem>
#include <sstream>

#include <fmt/format.h>

#include "lib/core/atomic_file.h"
#include "reports/gnuplot.h"

namespace tb {

std::string html_escape(const std::string& s) {
  std::string o;
  o.reserve(s.size());
  for (char c : s) {
    switch (c) {
      case '&': o += "&amp;"; break;
      case '<': o += "&lt;"; break;
      case '>': o += "&gt;"; break;
      case '"': o += "&quot;"; break;
      default: o += c;
    }
  }
  return o;
}

namespace {

const char* kStyle = R"(<style>
body{font-family:Helvetica,Arial,sans-serif;margin:2em;max-width:1200px;color:#222}
table{border-collapse:collapse;font-size:13px}td,th{border:1px solid #ccc;padding:3px 6px;text-align:left;vertical-align:top}
th{background:#f0f0f0}.pass{color:#176f2c;font-weight:bold}.fail{color:#b00020;font-weight:bold}
.rerun{color:#a65f00;font-weight:bold}code,pre{font-size:12px;background:#f6f6f6}pre{padding:6px;overflow-x:auto;max-height:400px}
img{max-width:640px;border:1px solid #ddd;margin:4px}
</style>)";

std::string fmt_num(const nlohmann::json& v) {
  if (v.is_null()) return "–";
  if (v.is_string()) return v.get<std::string>();
  if (v.is_number_integer()) return std::to_string(v.get<int64_t>());
  if (!v.is_number()) return v.dump();
  const double x = v.get<double>();
  if (x == 0) return "0";
  if (std::abs(x) >= 1e-3 && std::abs(x) < 1e5) return fmt::format("{:.4g}", x);
  return fmt::format("{:.3e}", x);
}

std::string slug(const std::string& s) {
  std::string o;
  for (char c : s) o += (std::isalnum(static_cast<unsigned char>(c)) ? c : '_');
  return o;
}

// Renders the plots of one result; returns the HTML for them.
std::string plots_html(const nlohmann::json& plots, const std::string& out_dir, const std::string& prefix) {
  std::string html;
  const std::string plot_dir = (std::filesystem::path(out_dir) / "plots").string();
  size_t k = 0;
  for (const auto& p : plots) {
    const std::string base = fmt::format("{}_{}", slug(prefix), k++);
    const auto svg = render_plot(p, plot_dir, base);
    if (svg)
      html += fmt::format("<img src=\"plots/{}\" alt=\"{}\">", *svg, html_escape(p.value("title", "")));
    else
      html += fmt::format("<p>plot “{}” not rendered (gnuplot missing or failed); data in plots/{}.dat</p>",
                          html_escape(p.value("title", "")), base);
  }
  return html;
}

// The smallest effect a check detects with 90% power, as a percentage; "—" when not stated.
std::string mde_cell(const nlohmann::json& v) {
  if (!v.is_number()) return "&mdash;";
  return fmt::format("{:.3g}%", 100.0 * v.get<double>());
}

std::string result_row(const nlohmann::json& r, const char* which) {
  return fmt::format("<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{:.2f}</td><td>{}</td><td><code>{}</code></td></tr>\n",
                     which, html_escape(r.value("statistic_name", "")), fmt_num(r.value("statistic", nlohmann::json())),
                     fmt_num(r.value("p_value", nlohmann::json())), fmt_num(r.value("alpha", nlohmann::json())),
                     fmt_num(r.value("samples", nlohmann::json())), r.value("seconds", 0.0),
                     html_escape(r.value("message", "")), html_escape(r.value("reproducer", "")));
}

}  // namespace

std::string report_style() { return kStyle; }

void write_check_report(const nlohmann::json& results, const std::string& out_dir) {
  std::ostringstream h;
  const auto& cfg = results["config"];
  h << "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>tb check report</title>" << kStyle << "</head><body>\n";
  h << "<h1>tb check</h1>\n";
  h << fmt::format("<p>{} passed, {} failed{} &middot; seed {} &middot; {} size{}</p>\n", results.value("passed", 0),
                   results.value("failed", 0), results.value("interrupted", false) ? " &middot; <b>interrupted</b>" : "",
                   fmt_num(cfg.value("seed", nlohmann::json())), cfg.value("full", false) ? "full" : "quick",
                   cfg.value("attempt", 0) > 0 ? fmt::format(" &middot; attempt {}", cfg.value("attempt", 0)) : "");
  h << "<p>Statistical checks that reject are rerun once with a fresh seed and 4&times; the samples; they fail only "
       "if the rerun rejects too, at 0.05 &alpha; where its rejection is by its p-value (both results are shown). &alpha; is the level after the check's own multiple-comparison "
       "correction. MDE is the smallest effect the check rejects with 90% power at that &alpha; and its sample "
       "size (hover for which effect; &mdash;: not stated).</p>\n";
  h << "<table><tr><th>check</th><th>verdict</th><th>statistic</th><th>value</th><th>p</th><th>&alpha;</th>"
       "<th>n</th><th>MDE</th><th>time [s]</th><th>message</th></tr>\n";
  for (const auto& rec : results["checks"]) {
    const std::string verdict = rec.value("verdict", "fail");
    const char* cls = verdict == "pass" ? "pass" : verdict == "fail" ? "fail" : "rerun";
    const auto& r = rec["first"];
    h << fmt::format("<tr><td><a href=\"#{}\">{}</a></td><td class=\"{}\">{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td title=\"{}\">{}</td><td>{:.2f}</td><td>{}</td></tr>\n",
                     slug(rec.value("name", "")), html_escape(rec.value("name", "")), cls, verdict,
                     html_escape(r.value("statistic_name", "")), fmt_num(r.value("statistic", nlohmann::json())),
                     fmt_num(r.value("p_value", nlohmann::json())), fmt_num(r.value("alpha", nlohmann::json())),
                     fmt_num(r.value("samples", nlohmann::json())), html_escape(r.value("effect_kind", "")),
                     mde_cell(r.value("min_detectable_effect", nlohmann::json())), r.value("seconds", 0.0),
                     html_escape(r.value("message", "")));
  }
  h << "</table>\n<h2>Details</h2>\n";
  for (const auto& rec : results["checks"]) {
    const std::string name = rec.value("name", "");
    h << fmt::format("<h3 id=\"{}\">{}</h3>\n<p>{} ({})</p>\n", slug(name), html_escape(name),
                     html_escape(rec.value("description", "")), html_escape(rec.value("kind", "")));
    h << "<table><tr><th>run</th><th>statistic</th><th>value</th><th>p</th><th>&alpha;</th><th>n</th><th>time [s]</th>"
         "<th>message</th><th>reproducer</th></tr>\n";
    h << result_row(rec["first"], "first");
    if (rec.contains("rerun")) h << result_row(rec["rerun"], "rerun (4&times; samples)");
    h << "</table>\n";
    h << plots_html(rec["first"].value("plots", nlohmann::json::array()), out_dir, name);
    const auto& d = rec["first"].value("details", nlohmann::json::object());
    if (!d.empty())
      h << "<details><summary>details</summary><pre>" << html_escape(d.dump(1)) << "</pre></details>\n";
  }
  h << "</body></html>\n";
  write_file_atomic((std::filesystem::path(out_dir) / "index.html").string(), h.str());
}

void write_experiment_report(const std::string& name, const nlohmann::json& report, const std::string& out_dir) {
  std::ostringstream h;
  h << "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>" << html_escape(name) << "</title>" << kStyle
    << "</head><body>\n";
  h << "<h1>tb reproduce " << html_escape(name) << "</h1>\n";
  const bool passed = report.value("passed", false);
  h << fmt::format("<p class=\"{}\">{}</p>\n", passed ? "pass" : "fail",
                   passed ? "All stated claims held." : "At least one stated claim did not hold.");
  std::istringstream summary(report.value("summary", ""));
  for (std::string para; std::getline(summary, para);)
    if (!para.empty()) h << "<p>" << html_escape(para) << "</p>\n";
  if (!report.value("claims", nlohmann::json::array()).empty()) {
    h << "<h2>Claims</h2><ul>\n";
    for (const auto& c : report["claims"]) h << "<li>" << html_escape(c.get<std::string>()) << "</li>\n";
    h << "</ul>\n";
  }
  for (const auto& t : report.value("tables", nlohmann::json::array())) {
    h << "<h2>" << html_escape(t.value("title", "")) << "</h2>\n<table><tr>";
    for (const auto& c : t["header"]) h << "<th>" << html_escape(c.get<std::string>()) << "</th>";
    h << "</tr>\n";
    for (const auto& row : t["rows"]) {
      h << "<tr>";
      for (const auto& c : row) h << "<td>" << html_escape(c.get<std::string>()) << "</td>";
      h << "</tr>\n";
    }
    h << "</table>\n";
  }
  h << "<h2>Figures</h2>\n" << plots_html(report.value("plots", nlohmann::json::array()), out_dir, name);
  h << "<details><summary>configuration and data</summary><pre>"
    << html_escape(report.value("data", nlohmann::json::object()).dump(1)) << "</pre></details>\n";
  h << "</body></html>\n";
  write_file_atomic((std::filesystem::path(out_dir) / "index.html").string(), h.str());
}

}  // namespace tb
