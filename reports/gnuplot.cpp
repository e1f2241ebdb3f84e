#include "reports/gnuplot.h"

#include <cstdlib>
#include <filesystem>
#include <sstream>

#include <fmt/format.h>

#include "lib/core/atomic_file.h"

namespace tb {

namespace {

std::string quote(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

// A file name for gnuplot: single-quoted, no enhanced-text escapes.
std::string quote_path(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += (c == '\'' ? std::string("''") : std::string(1, c));
  return out + "'";
}

double num(const nlohmann::json& v) {
  if (v.is_number()) return v.get<double>();
  return std::numeric_limits<double>::quiet_NaN();
}

}  // namespace

bool gnuplot_available() {
  static const bool ok = std::system("gnuplot --version > /dev/null 2>&1") == 0;
  return ok;
}

std::optional<std::string> render_plot(const nlohmann::json& plot, const std::string& dir, const std::string& basename) {
  namespace fs = std::filesystem;
  fs::create_directories(dir);
  const std::string dat = basename + ".dat", svg = basename + ".svg";
  std::ostringstream data, gp;
  gp << "set terminal svg size 640,420 dynamic enhanced font 'Helvetica,12' background rgb 'white'\n";
  gp << "set output " << quote_path((fs::path(dir) / svg).string()) << "\n";
  gp << "set title " << quote(plot.value("title", "")) << " noenhanced\n";
  gp << "set xlabel " << quote(plot.value("x_label", "")) << " noenhanced\n";
  gp << "set ylabel " << quote(plot.value("y_label", "")) << " noenhanced\n";
  gp << "set grid\nset key inside top right box opaque font \",10\"\n";
  const std::string datpath = quote_path((fs::path(dir) / dat).string());

  if (plot.contains("heatmap")) {
    const auto& rows = plot["heatmap"];
    const auto ext = plot.value("extent", std::vector<double>{0, 1, 0, 1});
    const size_t ny = rows.size(), nx = ny ? rows[0].size() : 0;
    for (size_t iy = 0; iy < ny; ++iy) {
      for (size_t ix = 0; ix < nx; ++ix) {
        const double x = ext[0] + (ext[1] - ext[0]) * (static_cast<double>(ix) + 0.5) / static_cast<double>(nx);
        const double y = ext[2] + (ext[3] - ext[2]) * (static_cast<double>(iy) + 0.5) / static_cast<double>(ny);
        data << x << ' ' << y << ' ' << num(rows[iy][ix]) << '\n';
      }
      data << '\n';
    }
    gp << fmt::format("set xrange [{}:{}]\nset yrange [{}:{}]\n", ext[0], ext[1], ext[2], ext[3]);
    gp << "set view map\nset palette rgbformulae 21,22,23\nunset key\n";
    gp << "plot " << datpath << " using 1:2:3 with image\n";
  } else {
    if (plot.value("log_x", false)) gp << "set logscale x\n";
    if (plot.value("log_y", false)) gp << "set logscale y\n";
    std::vector<std::string> clauses;
    size_t block = 0;
    for (const auto& s : plot.value("series", nlohmann::json::array())) {
      const auto& xs = s["x"];
      const auto& ys = s["y"];
      const bool err = s.contains("y_err");
      for (size_t i = 0; i < xs.size() && i < ys.size(); ++i) {
        data << num(xs[i]) << ' ' << num(ys[i]);
        if (err) data << ' ' << num(s["y_err"][i]);
        data << '\n';
      }
      data << "\n\n";
      std::string style = s.value("style", "linespoints");
      if (err) style = "yerrorlines";
      clauses.push_back(fmt::format("{} index {} using 1:2{} with {} title {} noenhanced", datpath, block, err ? ":3" : "",
                                    style, quote(s.value("label", ""))));
      ++block;
    }
    if (clauses.empty()) return std::nullopt;
    gp << "plot ";
    for (size_t i = 0; i < clauses.size(); ++i) gp << (i ? ", \\\n     " : "") << clauses[i];
    gp << "\n";
  }
  write_file_atomic((fs::path(dir) / dat).string(), data.str());
  const std::string script = (fs::path(dir) / (basename + ".gp")).string();
  write_file_atomic(script, gp.str());
  if (!gnuplot_available()) return std::nullopt;
  const std::string cmd = fmt::format("gnuplot '{}' > '{}' 2>&1", script, (fs::path(dir) / (basename + ".log")).string());
  if (std::system(cmd.c_str()) != 0) return std::nullopt;
  return svg;
}

}  // namespace tb
