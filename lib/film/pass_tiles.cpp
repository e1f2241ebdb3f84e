#include "lib/film/pass_tiles.h"

#include <algorithm>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

namespace tb {

PassTiles::PassTiles(int width, int height, int gx, int gy)
    : width_(width), height_(height), gx_(std::clamp(gx, 1, std::max(1, width))),
      gy_(std::clamp(gy, 1, std::max(1, height))) {}

int PassTiles::tile_of(int x, int y) const {
  const int i = static_cast<int>(static_cast<int64_t>(x) * gx_ / width_);
  const int j = static_cast<int>(static_cast<int64_t>(y) * gy_ / height_);
  return j * gx_ + i;
}

void PassTiles::add_pass(const std::vector<Rgb>& pass) {
  if (pass.size() != static_cast<size_t>(width_) * static_cast<size_t>(height_))
    throw std::logic_error("PassTiles::add_pass: pass size does not match the image");
  const size_t at = sums_.size();
  sums_.resize(at + static_cast<size_t>(tiles()), Rgb(0.0));
  for (int y = 0; y < height_; ++y)
    for (int x = 0; x < width_; ++x)
      sums_[at + static_cast<size_t>(tile_of(x, y))] += pass[static_cast<size_t>(y) * static_cast<size_t>(width_) + x];
  ++passes_;
}

std::string PassTiles::to_json() const {
  nlohmann::json j;
  j["format"] = "tb pass tiles 1";
  j["width"] = width_;
  j["height"] = height_;
  j["grid"] = {gx_, gy_};
  j["passes"] = passes_;
  nlohmann::json s = nlohmann::json::array();
  for (const Rgb& v : sums_) s.insert(s.end(), {v[0], v[1], v[2]});
  j["sums"] = std::move(s);  // pass-major, tile-major (row of tiles first), RGB
  return j.dump();
}

PassTiles PassTiles::read(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path);
  std::stringstream ss;
  ss << in.rdbuf();
  try {
    const nlohmann::json j = nlohmann::json::parse(ss.str());
    if (j.at("format") != "tb pass tiles 1") throw std::runtime_error("unknown format");
    PassTiles t(j.at("width").get<int>(), j.at("height").get<int>(), j.at("grid").at(0).get<int>(),
                j.at("grid").at(1).get<int>());
    if (t.gx_ != j.at("grid").at(0).get<int>() || t.gy_ != j.at("grid").at(1).get<int>())
      throw std::runtime_error("grid larger than the image");
    t.passes_ = j.at("passes").get<int64_t>();
    const auto& s = j.at("sums");
    if (t.passes_ < 0 || s.size() != static_cast<size_t>(t.passes_) * static_cast<size_t>(t.tiles()) * 3)
      throw std::runtime_error("sums hold " + std::to_string(s.size()) + " values, expected passes x tiles x 3");
    t.sums_.resize(s.size() / 3);
    for (size_t i = 0; i < t.sums_.size(); ++i)
      t.sums_[i] = Rgb(s[3 * i].get<double>(), s[3 * i + 1].get<double>(), s[3 * i + 2].get<double>());
    return t;
  } catch (const std::exception& e) {
    throw std::runtime_error(path + ": not a pass-tiles file written by tb render (" + e.what() + ")");
  }
}

}  // namespace tb
