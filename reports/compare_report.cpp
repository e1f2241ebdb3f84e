#include "reports/compare_report.h"

#include <filesystem>
#include <sstream>

#include <fmt/format.h>

#include "lib/core/atomic_file.h"
#include "reports/gnuplot.h"
#include "reports/html_report.h"

namespace tb {

namespace {

std::string text(const nlohmann::json& v) {
  if (v.is_string()) return v.get<std::string>();
  if (v.is_number_float()) return fmt::format("{:.4g}", v.get<double>());
  return v.dump();
}

void table_html(std::ostringstream& h, const nlohmann::json& t) {
  h << "<h2>" << html_escape(t.value("title", "")) << "</h2>\n<table><tr>";
  for (const auto& c : t["header"]) h << "<th>" << html_escape(text(c)) << "</th>";
  h << "</tr>\n";
  for (const auto& row : t["rows"]) {
    h << "<tr>";
    for (const auto& c : row) h << "<td>" << html_escape(text(c)) << "</td>";
    h << "</tr>\n";
  }
  h << "</table>\n";
}

std::string figure(const std::string& src, const std::string& caption) {
  return fmt::format("<figure style=\"display:inline-block;margin:4px\"><img src=\"{}\" alt=\"{}\" "
                     "style=\"width:256px;image-rendering:pixelated\"><figcaption>{}</figcaption></figure>",
                     html_escape(src), html_escape(caption), html_escape(caption));
}

}  // namespace

void write_compare_report(const nlohmann::json& results, const std::string& out_dir) {
  const auto& cfg = results["config"];
  std::ostringstream h;
  const std::string scene = cfg.value("scene", "");
  h << "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>tb compare " << html_escape(scene) << "</title>"
    << report_style() << "</head><body>\n";
  h << "<h1>tb compare " << html_escape(scene) << "</h1>\n";
  const auto res = cfg.value("resolution", nlohmann::json::array({0, 0}));
  h << fmt::format("<p>{}&times;{}, equal time S = {} s per integrator, checkpoints {} s ({}); seed {}, {} threads "
                   "({} hardware threads).</p>\n",
                   text(res[0]), text(res[1]), text(cfg.value("time_s", nlohmann::json())),
                   html_escape(cfg.value("checkpoints_s", nlohmann::json::array()).dump()),
                   html_escape(cfg.value("checkpoint_mode", "")), text(cfg.value("seed", nlohmann::json())),
                   cfg.value("threads", 0) > 0 ? text(cfg["threads"]) : "all",
                   text(cfg.value("hardware_threads", nlohmann::json())));
  if (cfg.value("reference_rendered", false))
    h << fmt::format("<p><b>Reference rendered by this run</b> ({} for {} s), no --reference given: its own noise "
                     "(rRMSE<sub>ref</sub> below) limits what the comparison resolves.</p>\n",
                     html_escape(cfg.value("reference_integrator", "")),
                     text(cfg.value("reference_budget_s", nlohmann::json())));
  else
    h << "<p>Reference: <code>" << html_escape(cfg.value("reference", "")) << "</code></p>\n";
  const auto& rs = results.value("reference_stats", nlohmann::json::object());
  h << fmt::format("<p>rRMSE over {} pixel-channels with reference &gt; {} ({} &times; the mean reference value; {} "
                   "left out). The reference's own noise: rRMSE<sub>ref</sub> = {}.</p>\n",
                   text(rs.value("channels", nlohmann::json())), text(cfg.value("floor", nlohmann::json())),
                   text(cfg.value("floor_fraction", nlohmann::json())), text(rs.value("below_floor", nlohmann::json())),
                   text(rs.value("rrmse_ref", nlohmann::json())));
  for (const auto& t : results.value("tables", nlohmann::json::array())) table_html(h, t);

  h << "<h2>Definitions</h2><ul>\n";
  const nlohmann::json definitions = results.value("definitions", nlohmann::json::object());
  for (const auto& [k, v] : definitions.items())
    h << "<li><b>" << html_escape(k) << "</b>: " << html_escape(text(v)) << "</li>\n";
  h << "</ul>\n<h2>Plots</h2>\n";
  const std::string plot_dir = (std::filesystem::path(out_dir) / "plots").string();
  size_t k = 0;
  for (const auto& p : results.value("plots", nlohmann::json::array())) {
    const std::string base = fmt::format("compare_{}", k++);
    const auto svg = render_plot(p, plot_dir, base);
    if (svg)
      h << fmt::format("<img src=\"plots/{}\" alt=\"{}\">", *svg, html_escape(p.value("title", "")));
    else
      h << fmt::format("<p>plot “{}” not rendered (gnuplot missing or failed); data in plots/{}.dat</p>",
                       html_escape(p.value("title", "")), base);
  }

  h << "<h2>Images at S</h2>\n<p>Per integrator, the render (sRGB preview, exposure 0) and to its right its "
       "per-pixel relative error map (" << html_escape(definitions.value("error_map", ""))
    << ").</p>\n<div>" << figure(rs.value("image", "images/reference.png"), "reference") << "</div>\n";
  for (const auto& i : results.value("integrators", nlohmann::json::array())) {
    if (!i.contains("final")) {
      h << "<p>" << html_escape(i.value("name", "")) << ": " << html_escape(i.value("error", "no runs")) << "</p>\n";
      continue;
    }
    const auto& f = i["final"];
    h << "<div>" << figure(f.value("image", ""), fmt::format("{}: rRMSE {}", i.value("name", ""), text(f["rrmse"])))
      << figure(f.value("error_map", ""), fmt::format("{}: |I - R| / R", i.value("name", ""))) << "</div>\n";
  }
  h << "<details><summary>configuration and data</summary><pre>" << html_escape(results.dump(1))
    << "</pre></details>\n</body></html>\n";
  write_file_atomic((std::filesystem::path(out_dir) / "index.html").string(), h.str());
}

}  // namespace tb
