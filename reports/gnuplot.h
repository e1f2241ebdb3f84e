// Renders plots (the JSON form of validate/plot_spec.h) to SVG with gnuplot. Data and script
// are kept beside the SVG, so every figure can be regenerated or restyled by hand.
#pragma once

#include <optional>
#include <string>

#include <nlohmann/json.hpp>

namespace tb {

// True when a gnuplot executable is on PATH.
bool gnuplot_available();

// Writes DIR/BASENAME.dat, DIR/BASENAME.gp and, if gnuplot runs, DIR/BASENAME.svg.
// Returns the SVG file name (relative to DIR) or nullopt when it could not be produced.
std::optional<std::string> render_plot(const nlohmann::json& plot, const std::string& dir, const std::string& basename);

}  // namespace tb
