// The HTML report of an equal-time comparison (`tb compare SCENE --integrators ...`,
// app/compare_scene.h, docs/compare.md), made from its results.json alone: the summary and
// per-checkpoint tables, the rRMSE-against-time and efficiency plots (gnuplot), and the images
// (reference, each render at the largest budget and its relative error map).
#pragma once

#include <string>

#include <nlohmann/json.hpp>

namespace tb {

// Writes OUT_DIR/index.html and OUT_DIR/plots/*; the images named in the JSON are expected under
// OUT_DIR (paths relative to it).
void write_compare_report(const nlohmann::json& results, const std::string& out_dir);

}  // namespace tb
