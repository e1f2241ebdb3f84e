#include "lib/scene/mitsuba_import.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>
#include <vector>

#include <fmt/format.h>
#include <pugixml.hpp>

#include "lib/core/math.h"
#include "lib/geometry/obj_loader.h"

namespace tb {

namespace {

using nlohmann::json;
using V3 = std::array<double, 3>;

// 4 x 4 matrices, row-major: m[row][col]; points are columns (p' = M p), as in Mitsuba.
struct M4 {
  double m[4][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}};
  M4 operator*(const M4& b) const {
    M4 r;
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) {
        double s = 0;
        for (int k = 0; k < 4; ++k) s += m[i][k] * b.m[k][j];
        r.m[i][j] = s;
      }
    return r;
  }
  V3 point(const V3& p) const {
    V3 q{};
    for (int i = 0; i < 3; ++i) q[size_t(i)] = m[i][0] * p[0] + m[i][1] * p[1] + m[i][2] * p[2] + m[i][3];
    return q;
  }
  V3 column(int c) const { return {m[0][c], m[1][c], m[2][c]}; }
  double det3() const {
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  }
  bool finite() const {
    for (const auto& r : m)
      for (double v : r)
        if (!std::isfinite(v)) return false;
    return true;
  }
  json rows() const {  // the [A | t] rows of this project's {"matrix": ...}
    json out = json::array();
    for (int r = 0; r < 3; ++r) out.push_back(json::array({m[r][0], m[r][1], m[r][2], m[r][3]}));
    return out;
  }
  static M4 translate(const V3& t) {
    M4 r;
    for (int i = 0; i < 3; ++i) r.m[i][3] = t[size_t(i)];
    return r;
  }
  static M4 scale(const V3& s) {
    M4 r;
    for (int i = 0; i < 3; ++i) r.m[i][i] = s[size_t(i)];
    return r;
  }
};

double dot(const V3& a, const V3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
V3 cross(const V3& a, const V3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double norm(const V3& a) { return std::sqrt(dot(a, a)); }
V3 sub(const V3& a, const V3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
V3 add(const V3& a, const V3& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
V3 mul(const V3& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
json j3(const V3& v) { return json::array({v[0], v[1], v[2]}); }

// Named indices of refraction of Mitsuba's documentation (the table both versions share).
const std::map<std::string, double>& ior_table() {
  static const std::map<std::string, double> t = {
      {"vacuum", 1.0},        {"helium", 1.000036},       {"hydrogen", 1.000132},    {"air", 1.000277},
      {"carbon dioxide", 1.00045}, {"water", 1.333},      {"acetone", 1.36},         {"ethanol", 1.361},
      {"carbon tetrachloride", 1.461}, {"glycerol", 1.4729}, {"benzene", 1.501},     {"silicone oil", 1.52045},
      {"bromine", 1.661},     {"water ice", 1.31},        {"fused quartz", 1.458},   {"pyrex", 1.47},
      {"acrylic glass", 1.49}, {"polypropylene", 1.49},   {"bk7", 1.5046},           {"sodium chloride", 1.544},
      {"amber", 1.55},        {"pet", 1.575},             {"diamond", 2.419}};
  return t;
}

const char* const kPropertyTags[] = {"float", "integer", "boolean", "string", "rgb", "srgb", "spectrum",
                                     "blackbody", "point", "vector", "transform"};
bool is_property_tag(const std::string& t) {
  return std::find(std::begin(kPropertyTags), std::end(kPropertyTags), t) != std::end(kPropertyTags);
}

bool tag_is(pugi::xml_node n, const char* t) { return std::string(n.name()) == t; }

class Importer;

// One plugin element (<bsdf type="...">, <shape ...>, ...): its property children by (canonical)
// name, its nested plugin children, and which properties the mapping read.
struct Plugin {
  const Importer* im;
  pugi::xml_node node;
  std::string kind, type;
  std::map<std::string, pugi::xml_node> props;
  std::vector<pugi::xml_node> children;
  mutable std::set<std::string> used;

  bool has(const std::string& name) const { return props.count(name) > 0; }
  pugi::xml_node prop(const std::string& name, const std::vector<std::string>& tags, const std::string& what) const;
  double number(const std::string& name, double fallback) const;
  double number(const std::string& name) const;
  int64_t integer(const std::string& name, int64_t fallback) const;
  bool boolean(const std::string& name, bool fallback) const;
  std::string string(const std::string& name, const std::string& fallback) const;
  V3 color(const std::string& name, const V3& fallback) const;
  V3 point(const std::string& name, const V3& fallback) const;
  M4 transform(const std::string& name) const;
  // A float or a named index of refraction.
  double ior(const std::string& name, double fallback) const;
  // Every property must have been read; `supported` lists them for the message.
  void finish(const std::vector<std::string>& supported) const;
  // Nested plugin elements must be among `tags`, each at most once.
  void only_children(const std::vector<std::string>& tags) const;
  pugi::xml_node child(const std::string& tag) const {
    for (const auto& c : children)
      if (tag == c.name()) return c;
    return {};
  }
};

class Importer {
 public:
  Importer(const std::string& text, const std::string& file, const std::string& base_dir)
      : text_(text), file_(file), base_dir_(base_dir) {
    line_starts_.push_back(0);
    for (size_t i = 0; i < text.size(); ++i)
      if (text[i] == '\n') line_starts_.push_back(i + 1);
  }

  json run();

  int line_at(ptrdiff_t offset) const {
    if (offset < 0) return 0;
    const auto it = std::upper_bound(line_starts_.begin(), line_starts_.end(), size_t(offset));
    return int(it - line_starts_.begin());
  }

  static std::string describe(pugi::xml_node n) {
    std::string attrs;
    for (const char* a : {"type", "name", "id"}) {
      const pugi::xml_attribute at = n.attribute(a);
      if (!at) continue;
      const std::string v = at.value();
      attrs += fmt::format(" {}=\"{}{}\"", a, v.substr(0, 40), v.size() > 40 ? "..." : "");
    }
    return fmt::format("<{}{}>", n.name(), attrs);
  }

  [[noreturn]] void fail(pugi::xml_node n, const std::string& what) const {
    throw MitsubaError(fmt::format("{}:{}: {}: {}", file_, line_at(n.offset_debug()), describe(n), what));
  }

  // Attributes of `n` must be among `allowed`.
  void attributes(pugi::xml_node n, const std::vector<std::string>& allowed) const {
    for (const pugi::xml_attribute a : n.attributes())
      if (std::find(allowed.begin(), allowed.end(), a.name()) == allowed.end())
        fail(n, fmt::format("attribute '{}' is not supported on <{}> by the Mitsuba import (supported: {})", a.name(),
                            n.name(), fmt::join(allowed, ", ")));
  }

  // Element children; text other than white space is an error.
  std::vector<pugi::xml_node> elements(pugi::xml_node n) const {
    std::vector<pugi::xml_node> out;
    for (const pugi::xml_node c : n.children()) {
      if (c.type() == pugi::node_element) {
        out.push_back(c);
      } else if (c.type() == pugi::node_pcdata || c.type() == pugi::node_cdata) {
        const std::string v = c.value();
        if (v.find_first_not_of(" \t\r\n") != std::string::npos) fail(n, "unexpected text inside the element");
      }
    }
    return out;
  }

  // Mitsuba 0.6 names parameters in camelCase; Mitsuba 3 (and its upgrade of 0.6 files) in
  // snake_case: "toWorld" -> "to_world", "intIOR" -> "int_ior".
  std::string canonical(const std::string& name) const {
    if (version_major_ >= 2) return name;
    std::string out;
    for (size_t i = 0; i < name.size(); ++i) {
      const char c = name[i];
      if (i > 0 && std::isupper(static_cast<unsigned char>(c)) &&
          (std::islower(static_cast<unsigned char>(name[i - 1])) || std::isdigit(static_cast<unsigned char>(name[i - 1]))))
        out += '_';
      out += char(std::tolower(static_cast<unsigned char>(c)));
    }
    return out;
  }

  Plugin plugin(pugi::xml_node n, const std::string& kind) const {
    Plugin p{this, n, kind, n.attribute("type").value(), {}, {}, {}};
    attributes(n, {"type", "id", "name"});
    if (!n.attribute("type")) fail(n, "missing attribute 'type'");
    for (const pugi::xml_node c : elements(n)) {
      const std::string tag = c.name();
      if (is_property_tag(tag)) {
        if (!c.attribute("name")) fail(c, "a property needs a 'name' attribute");
        const std::string name = canonical(c.attribute("name").value());
        if (p.props.count(name)) fail(c, fmt::format("parameter '{}' is given twice", name));
        p.props[name] = c;
      } else if (tag == "bsdf" || tag == "emitter" || tag == "film" || tag == "sampler" || tag == "rfilter" ||
                 tag == "ref") {
        p.children.push_back(c);
      } else if (tag == "texture" || tag == "medium" || tag == "shape" || tag == "sensor" || tag == "integrator") {
        fail(c, fmt::format("a nested <{}> inside a <{}> is not supported by the Mitsuba import", tag, kind));
      } else {
        fail(c, fmt::format("unknown element <{}>", tag));
      }
    }
    return p;
  }

  // Numbers separated by commas and/or white space, each finite.
  std::vector<double> numbers(pugi::xml_node n, const std::string& attr) const {
    const pugi::xml_attribute a = n.attribute(attr.c_str());
    if (!a) fail(n, fmt::format("missing attribute '{}'", attr));
    const std::string s = a.value();
    std::vector<double> out;
    size_t i = 0;
    while (i < s.size()) {
      if (s[i] == ',' || std::isspace(static_cast<unsigned char>(s[i]))) {
        ++i;
        continue;
      }
      size_t j = i;
      while (j < s.size() && s[j] != ',' && !std::isspace(static_cast<unsigned char>(s[j]))) ++j;
      const std::string tok = s.substr(i, j - i);
      double v = 0;
      const char* b = tok.data();
      const char* e = tok.data() + tok.size();
      if (*b == '+') ++b;
      const auto [ptr, ec] = std::from_chars(b, e, v);
      if (ec != std::errc() || ptr != e)
        fail(n, fmt::format("attribute {}=\"{}\": '{}' is not a number", attr, s, tok));
      if (!std::isfinite(v)) fail(n, fmt::format("attribute {}=\"{}\": '{}' is not finite", attr, s, tok));
      out.push_back(v);
      i = j;
    }
    return out;
  }
  double one_number(pugi::xml_node n, const std::string& attr) const {
    const auto v = numbers(n, attr);
    if (v.size() != 1) fail(n, fmt::format("attribute '{}' must be one number", attr));
    return v[0];
  }
  V3 three(pugi::xml_node n, const std::string& attr) const {
    const auto v = numbers(n, attr);
    if (v.size() != 3) fail(n, fmt::format("attribute '{}' must be three numbers", attr));
    return {v[0], v[1], v[2]};
  }
  // x, y, z attributes (each defaulting to `fallback`) or, in Mitsuba 3, value="x y z".
  V3 xyz(pugi::xml_node n, double fallback, bool allow_single_value) const {
    if (n.attribute("value")) {
      attributes(n, {"name", "value"});
      const auto v = numbers(n, "value");
      if (v.size() == 3) return {v[0], v[1], v[2]};
      if (v.size() == 1 && allow_single_value) return {v[0], v[0], v[0]};
      fail(n, allow_single_value ? "attribute 'value' must be one or three numbers" : "attribute 'value' must be three numbers");
    }
    attributes(n, {"name", "x", "y", "z"});
    V3 r{fallback, fallback, fallback};
    for (int k = 0; k < 3; ++k) {
      const char* a = k == 0 ? "x" : k == 1 ? "y" : "z";
      if (n.attribute(a)) r[size_t(k)] = one_number(n, a);
    }
    return r;
  }

  M4 parse_transform(pugi::xml_node t) const;

  struct Material {
    std::string name;  // in the converted document
    bool black = false;  // a diffuse of reflectance 0: scatters nothing
  };
  json parse_bsdf(pugi::xml_node n, bool in_twosided, bool* black) const;
  Material bsdf_for_shape(const Plugin& p, const std::string& shape_name);
  void parse_shape(pugi::xml_node n, size_t index);
  void parse_sensor(pugi::xml_node n);
  void parse_integrator(pugi::xml_node n);
  void parse_emitter(pugi::xml_node n);

  const std::string& text_;
  std::string file_, base_dir_;
  std::vector<size_t> line_starts_;
  int version_major_ = 3;
  std::map<std::string, Material> bsdf_ids_;
  json materials_ = json::array(), shapes_ = json::array(), lights_ = json::array();
  json camera_, integrator_ = json::object();
  int64_t spp_ = -1;
  std::set<std::string> shape_names_;
};

pugi::xml_node Plugin::prop(const std::string& name, const std::vector<std::string>& tags,
                            const std::string& what) const {
  const auto it = props.find(name);
  if (it == props.end()) return {};
  used.insert(name);
  const pugi::xml_node n = it->second;
  if (std::find(tags.begin(), tags.end(), n.name()) == tags.end()) {
    const std::string tag = n.name();
    if (tag == "srgb" || tag == "blackbody")
      im->fail(n, fmt::format("<{}> values are not supported by the Mitsuba import (give linear <rgb>)", tag));
    im->fail(n, fmt::format("parameter '{}' of a {} {} must be {} (<{}>)", name, type, kind, what, fmt::join(tags, ">, <")));
  }
  if (tag_is(n, "transform")) return n;
  if (!im->elements(n).empty()) im->fail(n, "a property element has no children");
  return n;
}


double Plugin::number(const std::string& name, double fallback) const {
  const pugi::xml_node n = prop(name, {"float", "integer"}, "a number");
  if (!n) return fallback;
  im->attributes(n, {"name", "value"});
  return im->one_number(n, "value");
}
double Plugin::number(const std::string& name) const {
  if (!has(name)) im->fail(node, fmt::format("missing parameter '{}'", name));
  return number(name, 0.0);
}
int64_t Plugin::integer(const std::string& name, int64_t fallback) const {
  const pugi::xml_node n = prop(name, {"integer"}, "an integer");
  if (!n) return fallback;
  im->attributes(n, {"name", "value"});
  const std::string s = n.attribute("value").value();
  int64_t v = 0;
  const char* b = s.data();
  const char* e = s.data() + s.size();
  if (b != e && *b == '+') ++b;
  const auto [ptr, ec] = std::from_chars(b, e, v);
  if (!n.attribute("value") || ec != std::errc() || ptr != e)
    im->fail(n, fmt::format("attribute value=\"{}\" is not an integer", s));
  return v;
}
bool Plugin::boolean(const std::string& name, bool fallback) const {
  const pugi::xml_node n = prop(name, {"boolean"}, "true or false");
  if (!n) return fallback;
  im->attributes(n, {"name", "value"});
  const std::string s = n.attribute("value").value();
  if (s == "true") return true;
  if (s == "false") return false;
  im->fail(n, fmt::format("attribute value=\"{}\" is not true or false", s));
}
std::string Plugin::string(const std::string& name, const std::string& fallback) const {
  const pugi::xml_node n = prop(name, {"string"}, "a string");
  if (!n) return fallback;
  im->attributes(n, {"name", "value"});
  if (!n.attribute("value")) im->fail(n, "missing attribute 'value'");
  return n.attribute("value").value();
}
V3 Plugin::color(const std::string& name, const V3& fallback) const {
  const pugi::xml_node n = prop(name, {"rgb", "spectrum", "float"}, "a colour");
  if (!n) return fallback;
  im->attributes(n, {"name", "value"});
  const auto v = im->numbers(n, "value");
  if (tag_is(n, "rgb") && v.size() == 3) return {v[0], v[1], v[2]};
  if (v.size() == 1) return {v[0], v[0], v[0]};
  if (tag_is(n, "spectrum"))
    im->fail(n, "a spectrum is supported as one constant value only (no wavelength:value pairs)");
  im->fail(n, "attribute 'value' must be three numbers (r, g, b) or one");
}
V3 Plugin::point(const std::string& name, const V3& fallback) const {
  const pugi::xml_node n = prop(name, {"point", "vector"}, "a point");
  if (!n) return fallback;
  return im->xyz(n, 0.0, false);
}
M4 Plugin::transform(const std::string& name) const {
  const pugi::xml_node n = prop(name, {"transform"}, "a transform");
  if (!n) return M4{};
  return im->parse_transform(n);
}
double Plugin::ior(const std::string& name, double fallback) const {
  const auto it = props.find(name);
  if (it != props.end() && tag_is(it->second, "string")) {
    const std::string s = string(name, "");
    const auto t = ior_table().find(s);
    if (t == ior_table().end()) im->fail(it->second, fmt::format("unknown named index of refraction '{}'", s));
    return t->second;
  }
  const double v = number(name, fallback);
  if (!(v > 0)) im->fail(props.at(name), "an index of refraction must be positive");
  return v;
}
void Plugin::finish(const std::vector<std::string>& supported) const {
  for (const auto& [name, n] : props)
    if (!used.count(name))
      im->fail(n, fmt::format("parameter '{}' of a {} {} is not supported by the Mitsuba import (supported: {})", name,
                              type, kind, supported.empty() ? "none" : fmt::format("{}", fmt::join(supported, ", "))));
}
void Plugin::only_children(const std::vector<std::string>& tags) const {
  std::set<std::string> seen;
  for (const auto& c : children) {
    const std::string t = c.name();
    if (std::find(tags.begin(), tags.end(), t) == tags.end())
      im->fail(c, fmt::format("a nested <{}> inside a {} {} is not supported by the Mitsuba import", t, type, kind));
    if (!seen.insert(t).second) im->fail(c, fmt::format("a second nested <{}>", t));
  }
}

M4 Importer::parse_transform(pugi::xml_node t) const {
  attributes(t, {"name"});
  M4 m;
  for (const pugi::xml_node op : elements(t)) {
    const std::string tag = op.name();
    if (!elements(op).empty()) fail(op, "a transform operation has no children");
    M4 step;
    if (tag == "translate") {
      step = M4::translate(xyz(op, 0.0, false));
    } else if (tag == "scale") {
      step = M4::scale(xyz(op, 1.0, true));
    } else if (tag == "rotate") {
      V3 axis{0, 0, 0};
      if (op.attribute("value")) {
        attributes(op, {"value", "angle"});
        axis = three(op, "value");
      } else {
        attributes(op, {"x", "y", "z", "angle"});
        for (int k = 0; k < 3; ++k) {
          const char* a = k == 0 ? "x" : k == 1 ? "y" : "z";
          if (op.attribute(a)) axis[size_t(k)] = one_number(op, a);
        }
      }
      const double deg = one_number(op, "angle");
      const double len = norm(axis);
      if (!(len > 0)) fail(op, "the rotation axis is zero");
      axis = mul(axis, 1.0 / len);
      // Rodrigues: R = cos I + sin [a]x + (1 - cos) a a^T (a right-handed rotation by `deg`).
      const double c = std::cos(deg * kPi / 180.0), s = std::sin(deg * kPi / 180.0);
      const double x = axis[0], y = axis[1], z = axis[2];
      const double r[3][3] = {{c + (1 - c) * x * x, (1 - c) * x * y - s * z, (1 - c) * x * z + s * y},
                              {(1 - c) * y * x + s * z, c + (1 - c) * y * y, (1 - c) * y * z - s * x},
                              {(1 - c) * z * x - s * y, (1 - c) * z * y + s * x, c + (1 - c) * z * z}};
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) step.m[i][j] = r[i][j];
    } else if (tag == "matrix") {
      attributes(op, {"value"});
      const auto v = numbers(op, "value");
      if (v.size() == 16) {
        for (int i = 0; i < 4; ++i)
          for (int j = 0; j < 4; ++j) step.m[i][j] = v[size_t(4 * i + j)];
        if (step.m[3][0] != 0 || step.m[3][1] != 0 || step.m[3][2] != 0 || step.m[3][3] != 1)
          fail(op, "a projective matrix (last row other than 0 0 0 1) is not supported");
      } else if (v.size() == 9) {
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) step.m[i][j] = v[size_t(3 * i + j)];
      } else {
        fail(op, "a matrix is 16 numbers (4 x 4, row by row) or 9 (3 x 3)");
      }
    } else if (tag == "lookat") {
      attributes(op, {"origin", "target", "up"});
      const V3 o = three(op, "origin"), target = three(op, "target");
      if (!op.attribute("up")) fail(op, "missing attribute 'up' (the importer does not choose one)");
      const V3 up = three(op, "up");
      const V3 d = sub(target, o);
      if (!(norm(d) > 0)) fail(op, "origin equals target: no viewing direction");
      const V3 dir = mul(d, 1.0 / norm(d));
      const V3 l = cross(up, dir);
      if (!(norm(l) > 1e-9 * norm(up))) fail(op, "up is zero or parallel to the viewing direction");
      // Mitsuba's look-at frame: columns left = up x dir (normalised), up' = dir x left, dir, origin.
      const V3 left = mul(l, 1.0 / norm(l));
      const V3 up2 = cross(dir, left);
      for (int i = 0; i < 3; ++i) {
        step.m[i][0] = left[size_t(i)];
        step.m[i][1] = up2[size_t(i)];
        step.m[i][2] = dir[size_t(i)];
        step.m[i][3] = o[size_t(i)];
      }
    } else {
      fail(op, fmt::format("unknown transform operation <{}> (supported: translate, scale, rotate, matrix, lookat)", tag));
    }
    m = step * m;  // each operation applies after the ones before it
    if (!m.finite()) fail(op, "the transform is not finite");
  }
  return m;
}

// The converted material of one <bsdf> element. *black: a diffuse of reflectance 0.
json Importer::parse_bsdf(pugi::xml_node n, bool in_twosided, bool* black) const {
  const Plugin p = plugin(n, "bsdf");
  *black = false;
  const std::string& t = p.type;
  if (t == "twosided") {
    if (in_twosided) fail(n, "a twosided inside a twosided is not supported");
    p.finish({});
    p.only_children({"bsdf"});
    if (p.children.empty()) {
      for (const pugi::xml_node c : elements(n))
        if (tag_is(c, "ref")) fail(c, "a <ref> inside a twosided is not supported: nest the BSDF itself");
      fail(n, "a twosided needs one nested <bsdf>");
    }
    return parse_bsdf(p.children[0], true, black);
  }
  if (t == "diffuse") {
    p.only_children({});
    const V3 r = p.color("reflectance", {0.5, 0.5, 0.5});
    for (double c : r)
      if (c < 0 || c > 1) fail(p.props.at("reflectance"), "reflectance components must lie in [0, 1]");
    p.finish({"reflectance"});
    *black = r[0] == 0 && r[1] == 0 && r[2] == 0;
    if (!in_twosided && !*black)
      fail(n, "a diffuse BSDF outside a twosided is black from behind in Mitsuba, which the bench (shading "
              "non-transmissive surfaces two-sided) does not model: wrap it in <bsdf type=\"twosided\">");
    return {{"type", "lambert"}, {"reflectance", j3(r)}};
  }
  if (t == "conductor") {
    p.only_children({});
    if (!in_twosided)
      fail(n, "a conductor outside a twosided is black from behind in Mitsuba, which the bench does not model: wrap it "
              "in <bsdf type=\"twosided\">");
    V3 eta{0, 0, 0}, k{1, 1, 1};  // material "none": a perfect mirror (purely imaginary index)
    if (p.has("eta") || p.has("k")) {
      if (!p.has("eta") || !p.has("k")) fail(n, "give both eta and k (or material=\"none\")");
      if (p.has("material")) fail(p.props.at("material"), "give either material or eta and k");
      eta = p.color("eta", eta);
      k = p.color("k", k);
      for (double c : eta)
        if (c < 0) fail(p.props.at("eta"), "eta must be non-negative");
      for (double c : k)
        if (c < 0) fail(p.props.at("k"), "k must be non-negative");
    } else {
      // Mitsuba 0.6 defaults to copper, Mitsuba 3 to "none"; named presets are spectral tables.
      const std::string mat = p.string("material", version_major_ >= 2 ? "none" : "Cu");
      if (mat != "none")
        fail(p.has("material") ? p.props.at("material") : n,
             fmt::format("the conductor preset '{}' (spectral data) is not supported: give eta and k as <rgb>, or "
                         "material=\"none\"",
                         mat));
    }
    const V3 sr = p.color("specular_reflectance", {1, 1, 1});
    if (sr != V3{1, 1, 1}) fail(p.props.at("specular_reflectance"), "only specular_reflectance 1 is supported");
    std::vector<std::string> supported = {"material", "eta", "k", "specular_reflectance"};
    if (version_major_ < 2) {
      // Mitsuba 0.6 takes eta and k relative to the exterior index (default air).
      const double ext = p.ior("ext_eta", ior_table().at("air"));
      eta = mul(eta, 1.0 / ext);
      k = mul(k, 1.0 / ext);
      supported.push_back("ext_eta");
    }
    p.finish(supported);
    return {{"type", "smooth_conductor"}, {"eta", j3(eta)}, {"k", j3(k)}};
  }
  if (t == "dielectric") {
    p.only_children({});
    if (in_twosided) fail(n, "a dielectric inside a twosided is not supported (Mitsuba rejects it too)");
    const double in = p.ior("int_ior", ior_table().at("bk7"));
    const double ext = p.ior("ext_ior", ior_table().at("air"));
    for (const char* s : {"specular_reflectance", "specular_transmittance"}) {
      const V3 v = p.color(s, {1, 1, 1});
      if (v != V3{1, 1, 1}) fail(p.props.at(s), fmt::format("only {} 1 is supported", s));
    }
    p.finish({"int_ior", "ext_ior", "specular_reflectance", "specular_transmittance"});
    const double eta = in / ext;
    if (!(eta > 0) || !std::isfinite(eta)) fail(n, "int_ior / ext_ior must be positive and finite");
    return {{"type", "smooth_dielectric"}, {"eta", eta}};
  }
  if (t == "roughconductor" || t == "roughdielectric" || t == "roughplastic" || t == "roughdiffuse")
    fail(n, fmt::format("unsupported BSDF type '{}': Mitsuba's rough BSDFs (their microfacet shadowing term, "
                        "sampling and defaults) differ from the bench's, so a mapping would approximate (supported: "
                        "diffuse, conductor, dielectric, twosided)",
                        t));
  fail(n, fmt::format("unsupported BSDF type '{}' (supported: diffuse, conductor, dielectric, twosided)", t));
}

Importer::Material Importer::bsdf_for_shape(const Plugin& p, const std::string& shape_name) {
  pugi::xml_node inline_bsdf = p.child("bsdf"), ref = p.child("ref");
  if (inline_bsdf && ref) fail(ref, "a shape has one BSDF: both a nested <bsdf> and a <ref>");
  if (ref) {
    attributes(ref, {"id", "name"});
    if (ref.attribute("name") && std::string(ref.attribute("name").value()) != "bsdf")
      fail(ref, "a <ref> in a shape may name only its bsdf");
    if (!elements(ref).empty()) fail(ref, "a <ref> has no children");
    const std::string id = ref.attribute("id").value();
    const auto it = bsdf_ids_.find(id);
    if (it == bsdf_ids_.end()) fail(ref, fmt::format("no top-level <bsdf> with id '{}'", id));
    return it->second;
  }
  if (!inline_bsdf)
    fail(p.node, "a shape without a BSDF gets Mitsuba's default (a one-sided diffuse of reflectance 0.5), which the "
                 "bench does not model: give a <bsdf> (a diffuse of reflectance 0 for a pure emitter)");
  if (inline_bsdf.attribute("id")) fail(inline_bsdf, "a nested <bsdf> with an id is not supported: define it at the top level");
  bool black = false;
  json m = parse_bsdf(inline_bsdf, false, &black);
  m["name"] = shape_name + ".bsdf";
  materials_.push_back(m);
  return {shape_name + ".bsdf", black};
}

void Importer::parse_shape(pugi::xml_node n, size_t index) {
  const Plugin p = plugin(n, "shape");
  const std::string& t = p.type;
  static const std::vector<std::string> kShapes = {"rectangle", "disk", "sphere", "cube", "obj"};
  if (std::find(kShapes.begin(), kShapes.end(), t) == kShapes.end())
    fail(n, fmt::format("unsupported shape type '{}' (supported: {})", t, fmt::join(kShapes, ", ")));
  p.only_children({"bsdf", "ref", "emitter"});
  std::string name = n.attribute("id") ? n.attribute("id").value() : fmt::format("{}#{}", t, index);
  if (!shape_names_.insert(name).second) name = fmt::format("{}#{}", t, index);

  // Emission (an area emitter nested in the shape).
  V3 emission{0, 0, 0};
  if (const pugi::xml_node e = p.child("emitter")) {
    const Plugin ep = plugin(e, "emitter");
    ep.only_children({});
    if (ep.type != "area") fail(e, fmt::format("a {} emitter inside a shape is not supported (only area)", ep.type));
    if (!ep.has("radiance")) fail(e, "missing parameter 'radiance'");
    emission = ep.color("radiance", emission);
    for (double c : emission)
      if (c < 0) fail(ep.props.at("radiance"), "radiance must be non-negative");
    ep.finish({"radiance"});
  }
  const bool emissive = emission[0] > 0 || emission[1] > 0 || emission[2] > 0;
  const Material mat = bsdf_for_shape(p, name);

  const M4 m = p.transform("to_world");
  const pugi::xml_node where = p.has("to_world") ? p.props.at("to_world") : n;
  if (!(std::abs(m.det3()) >= 1e-12)) fail(where, "the transform is singular (zero scale?)");
  const bool flip = p.boolean("flip_normals", false);

  json s = json::object();
  s["name"] = name;
  if (!(mat.black && emissive)) s["material"] = mat.name;  // a black diffuse on an emitter scatters nothing
  if (emissive) s["emission"] = j3(emission);
  if (t == "rectangle" || t == "disk") {
    // Mitsuba's rectangle is [-1, 1]^2 and its disk the unit disk, both in z = 0 with normal +z:
    // this project's rectangle of half size 1 and disk of radius 1 (docs/geometry.md).
    p.finish({"to_world", "flip_normals"});
    // Mitsuba 3 rejects a rectangle whose to_world shears it (its edges must stay orthogonal).
    if (t == "rectangle" && std::abs(dot(m.column(0), m.column(1))) > 1e-9 * norm(m.column(0)) * norm(m.column(1)))
      fail(where, "a rectangle's transform must not shear it (Mitsuba rejects it too)");
    s["type"] = t;
    if (t == "rectangle")
      s["half_size"] = json::array({1.0, 1.0});
    else
      s["radius"] = 1.0;
    s["transform"] = {{"matrix", m.rows()}};
    s["flip_normal"] = flip;
  } else if (t == "sphere") {
    const V3 c = p.point("center", {0, 0, 0});
    const double r = p.number("radius", 1.0);
    if (!(r > 0)) fail(p.props.at("radius"), "the radius must be positive");
    p.finish({"center", "radius", "to_world", "flip_normals"});
    // Mitsuba permits only rotations, uniform scales and translations of a sphere.
    const V3 c0 = m.column(0), c1 = m.column(1), c2 = m.column(2);
    const double sc = std::cbrt(std::abs(m.det3()));
    const double tol = 1e-9 * sc;
    if (std::abs(norm(c0) - sc) > tol || std::abs(norm(c1) - sc) > tol || std::abs(norm(c2) - sc) > tol ||
        std::abs(dot(c0, c1)) > tol * sc || std::abs(dot(c0, c2)) > tol * sc || std::abs(dot(c1, c2)) > tol * sc)
      fail(where, "a sphere's transform must be a rotation, a uniform scale and a translation");
    M4 placed = m;
    const V3 centre = m.point(c);
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) placed.m[i][j] = m.m[i][j] / sc;
      placed.m[i][3] = centre[size_t(i)];
    }
    s["type"] = "sphere";
    s["radius"] = r * sc;
    s["transform"] = {{"matrix", placed.rows()}};
    s["flip_normal"] = flip;
  } else if (t == "cube") {
    p.finish({"to_world", "flip_normals"});
    if (flip) fail(p.props.at("flip_normals"), "flip_normals on a cube is not supported");
    // Mitsuba's cube is [-1, 1]^3, this project's [-1/2, 1/2]^3.
    s["type"] = "cube";
    s["transform"] = {{"matrix", (m * M4::scale({2, 2, 2})).rows()}};
  } else {  // obj
    const std::string file = p.string("filename", "");
    if (file.empty()) fail(n, "missing parameter 'filename'");
    const bool face_normals = p.boolean("face_normals", false);
    p.boolean("flip_tex_coords", false);  // texture coordinates are not used
    p.finish({"filename", "to_world", "flip_normals", "face_normals", "flip_tex_coords"});
    const std::filesystem::path path =
        std::filesystem::path(file).is_absolute() ? std::filesystem::path(file) : std::filesystem::path(base_dir_) / file;
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec))
      fail(p.props.at("filename"), fmt::format("mesh file not found: {}", path.string()));
    Mat3 a(1.0);
    Vec3 tr(0.0);
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) a[c][r] = m.m[r][c];
      tr[r] = m.m[r][3];
    }
    bool has_normals = false;
    try {
      has_normals = load_obj(path.string(), AffineTransform(a, tr), flip).has_normals();
    } catch (const std::exception& e) {
      fail(p.props.at("filename"), e.what());
    }
    // Mitsuba computes smooth vertex normals for an OBJ without them unless face_normals is
    // set, and discards the file's normals when it is; the bench uses a file's normals if
    // every face has them and facet normals otherwise.
    if (face_normals && has_normals)
      fail(p.props.at("face_normals"), "face_normals with an OBJ that has vertex normals is not supported");
    if (!face_normals && !has_normals)
      fail(p.props.at("filename"), "an OBJ without vertex normals gets smooth normals computed by Mitsuba, which the "
                                   "bench does not compute: add vn lines or set face_normals to true");
    s["type"] = "obj";
    s["file"] = std::filesystem::absolute(path).lexically_normal().string();
    s["transform"] = {{"matrix", m.rows()}};
    s["flip_normal"] = flip;
  }
  shapes_.push_back(s);
}

void Importer::parse_sensor(pugi::xml_node n) {
  const Plugin p = plugin(n, "sensor");
  if (p.type != "perspective")
    fail(n, fmt::format("unsupported sensor type '{}' (supported: perspective)", p.type));
  p.only_children({"film", "sampler"});
  if (!p.has("fov")) fail(n, "missing parameter 'fov' (the importer does not assume a focal length)");
  const double fov = p.number("fov");
  if (!(fov > 0 && fov < 180)) fail(p.props.at("fov"), "the field of view must lie in (0, 180) degrees");
  const std::string axis = p.string("fov_axis", "x");
  const M4 m = p.transform("to_world");
  p.finish({"fov", "fov_axis", "to_world"});

  // Film.
  const pugi::xml_node fn = p.child("film");
  if (!fn) fail(n, "missing <film> (Mitsuba's default film has a Gaussian reconstruction filter)");
  const Plugin f = plugin(fn, "film");
  if (f.type != "hdrfilm") fail(fn, fmt::format("unsupported film type '{}' (supported: hdrfilm)", f.type));
  f.only_children({"rfilter"});
  const int64_t w = f.integer("width", 768), h = f.integer("height", 576);
  if (w < 1 || h < 1 || w > 16384 || h > 16384) fail(fn, "width and height must lie in [1, 16384]");
  // Output settings: they do not change the image's values.
  f.string("pixel_format", "");
  f.string("component_format", "");
  f.string("file_format", "");
  f.boolean("banner", false);
  f.boolean("attach_log", false);
  f.finish({"width", "height", "pixel_format", "component_format", "file_format", "banner", "attach_log"});
  const pugi::xml_node rn = f.child("rfilter");
  if (!rn) fail(fn, "missing <rfilter type=\"box\"> (Mitsuba's default is a Gaussian filter, which the bench does not model)");
  const Plugin rf = plugin(rn, "rfilter");
  rf.only_children({});
  if (rf.type != "box")
    fail(rn, fmt::format("unsupported reconstruction filter '{}' (supported: box, the pixel-area box of the bench's film)",
                         rf.type));
  if (rf.number("radius", 0.5) != 0.5) fail(rf.props.at("radius"), "only a box of radius 0.5 (one pixel) is supported");
  rf.finish({"radius"});

  // Sampler: its count is the default spp; the pattern changes the variance only.
  spp_ = 4;
  if (const pugi::xml_node sn = p.child("sampler")) {
    const Plugin sp = plugin(sn, "sampler");
    static const std::vector<std::string> kSamplers = {"independent", "stratified", "multijitter", "ldsampler",
                                                       "orthogonal", "halton", "hammersley", "sobol"};
    if (std::find(kSamplers.begin(), kSamplers.end(), sp.type) == kSamplers.end())
      fail(sn, fmt::format("unsupported sampler type '{}' (supported: {})", sp.type, fmt::join(kSamplers, ", ")));
    sp.only_children({});
    spp_ = sp.integer("sample_count", 4);
    if (spp_ < 1) fail(sp.props.at("sample_count"), "sample_count must be at least 1");
    sp.integer("seed", 0);
    sp.boolean("jitter", true);
    sp.integer("scramble", 0);
    sp.integer("dimension", 0);
    sp.finish({"sample_count", "seed", "jitter", "scramble", "dimension"});
  }

  // Field of view: this project's is vertical.
  const double aspect = double(w) / double(h);
  std::string ax = axis;
  if (ax == "smaller") ax = aspect > 1 ? "y" : "x";
  if (ax == "larger") ax = aspect > 1 ? "x" : "y";
  const double t = std::tan(0.5 * fov * kPi / 180.0);
  double tv = 0;
  if (ax == "x")
    tv = t / aspect;
  else if (ax == "y")
    tv = t;
  else if (ax == "diagonal")
    tv = t * double(h) / std::sqrt(double(w) * double(w) + double(h) * double(h));
  else
    fail(p.props.at("fov_axis"), fmt::format("unknown fov_axis '{}' (supported: x, y, diagonal, smaller, larger)", axis));
  const double vfov = 2.0 * std::atan(tv) * 180.0 / kPi;

  // Placement: a rigid motion (columns left, up, forward with left = up x forward).
  const V3 left = m.column(0), up = m.column(1), dir = m.column(2);
  const pugi::xml_node where = p.has("to_world") ? p.props.at("to_world") : n;
  const double tol = 1e-9;
  if (std::abs(norm(left) - 1) > tol || std::abs(norm(up) - 1) > tol || std::abs(norm(dir) - 1) > tol ||
      std::abs(dot(left, up)) > tol || std::abs(dot(left, dir)) > tol || std::abs(dot(up, dir)) > tol)
    fail(where, "a sensor transform must be a rotation and a translation (no scale or shear)");
  if (!(m.det3() > 0)) fail(where, "a mirroring sensor transform (negative determinant) is not supported");
  const V3 eye = m.point({0, 0, 0});
  camera_ = {{"type", "pinhole"},       {"position", j3(eye)}, {"look_at", j3(add(eye, dir))},
             {"up", j3(up)},            {"fov", vfov},          {"resolution", json::array({w, h})}};
}

void Importer::parse_integrator(pugi::xml_node n) {
  const Plugin p = plugin(n, "integrator");
  p.only_children({});
  if (p.boolean("hide_emitters", false)) fail(p.props.at("hide_emitters"), "hide_emitters is not supported");
  if (p.boolean("strict_normals", false)) fail(p.props.at("strict_normals"), "strict_normals is not supported");
  if (p.type == "path") {
    if (!p.has("max_depth"))
      fail(n, "missing parameter 'max_depth' (Mitsuba's default -1, unbounded paths, is not supported)");
    const int64_t d = p.integer("max_depth", -1);
    if (d == -1) fail(p.props.at("max_depth"), "max_depth -1 (unbounded paths) is not supported");
    // Mitsuba counts path segments, this project scattering events.
    if (d < 2) fail(p.props.at("max_depth"), "max_depth must be at least 2 (max_depth - 1 scattering events >= 1)");
    const int64_t rr = p.integer("rr_depth", 5);  // Russian roulette changes the variance only
    if (rr < 1) fail(p.props.at("rr_depth"), "rr_depth must be at least 1");
    p.finish({"max_depth", "rr_depth", "hide_emitters", "strict_normals"});
    integrator_["max_depth"] = d - 1;
  } else if (p.type == "direct") {
    // Emission seen directly plus one scattering event (max_depth 2 of the path integrator).
    for (const char* k : {"emitter_samples", "bsdf_samples", "shading_samples", "luminaire_samples"})
      if (p.integer(k, 1) < 0) fail(p.props.at(k), "a sample count must be non-negative");
    p.finish({"emitter_samples", "bsdf_samples", "shading_samples", "luminaire_samples", "hide_emitters",
              "strict_normals"});
    integrator_["max_depth"] = 1;
  } else {
    fail(n, fmt::format("unsupported integrator type '{}' (supported: path, direct)", p.type));
  }
}

void Importer::parse_emitter(pugi::xml_node n) {
  const Plugin p = plugin(n, "emitter");
  p.only_children({});
  if (p.type == "point") {
    if (p.has("position") && p.has("to_world")) fail(n, "give either position or to_world");
    V3 pos = p.point("position", {0, 0, 0});
    if (p.has("to_world")) pos = p.transform("to_world").point({0, 0, 0});
    const V3 i = p.color("intensity", {1, 1, 1});
    for (double c : i)
      if (c < 0) fail(p.props.at("intensity"), "intensity must be non-negative");
    p.finish({"position", "to_world", "intensity"});
    lights_.push_back({{"type", "point"}, {"position", j3(pos)}, {"intensity", j3(i)}});
  } else if (p.type == "constant") {
    const V3 r = p.color("radiance", {1, 1, 1});
    for (double c : r)
      if (c < 0) fail(p.props.at("radiance"), "radiance must be non-negative");
    p.finish({"radiance"});
    lights_.push_back({{"type", "environment"}, {"radiance", j3(r)}});
  } else if (p.type == "area") {
    fail(n, "an area emitter must be nested in a shape");
  } else {
    fail(n, fmt::format("unsupported emitter type '{}' (supported: area inside a shape, point, constant)", p.type));
  }
}

json Importer::run() {
  pugi::xml_document doc;
  const pugi::xml_parse_result res = doc.load_buffer(text_.data(), text_.size(), pugi::parse_default, pugi::encoding_utf8);
  if (!res)
    throw MitsubaError(fmt::format("{}:{}: XML syntax error: {}", file_, line_at(res.offset), res.description()));
  pugi::xml_node root;
  for (const pugi::xml_node c : doc.children()) {
    if (c.type() == pugi::node_element) {
      if (root) fail(c, "a second top-level element");
      root = c;
    } else if (c.type() == pugi::node_pcdata || c.type() == pugi::node_cdata) {
      throw MitsubaError(fmt::format("{}:{}: text outside the <scene> element", file_, line_at(c.offset_debug())));
    }
  }
  if (!root) throw MitsubaError(fmt::format("{}:1: no <scene> element", file_));
  if (std::string(root.name()) != "scene") fail(root, "the top-level element must be <scene>");
  attributes(root, {"version"});
  const std::string version = root.attribute("version").value();
  if (version.empty()) fail(root, "missing attribute 'version' (e.g. \"0.6.0\" or \"3.0.0\")");
  {
    int major = -1;
    const auto [ptr, ec] = std::from_chars(version.data(), version.data() + version.size(), major);
    if (ec != std::errc() || (ptr != version.data() + version.size() && *ptr != '.') || !(major == 0 || major == 2 || major == 3))
      fail(root, fmt::format("unsupported version \"{}\" (supported: 0.x (0.6), 2.x and 3.x)", version));
    version_major_ = major;
  }

  const auto children = elements(root);
  // Top-level BSDFs first, so that refs resolve wherever the definition stands.
  std::set<std::string> ids;
  for (const pugi::xml_node c : children) {
    if (c.attribute("id") && !ids.insert(c.attribute("id").value()).second)
      fail(c, fmt::format("id '{}' is defined twice", c.attribute("id").value()));
    if (!tag_is(c, "bsdf")) continue;
    if (!c.attribute("id")) fail(c, "a top-level <bsdf> needs an id to be referenced by");
    const std::string id = c.attribute("id").value();
    bool black = false;
    json m = parse_bsdf(c, false, &black);
    m["name"] = id;
    materials_.push_back(m);
    bsdf_ids_[id] = {id, black};
  }
  bool have_sensor = false, have_integrator = false;
  size_t shape_index = 0;
  for (const pugi::xml_node c : children) {
    const std::string tag = c.name();
    if (tag == "bsdf") continue;
    if (tag == "shape") {
      parse_shape(c, shape_index++);
    } else if (tag == "sensor") {
      if (have_sensor) fail(c, "a second <sensor> is not supported");
      have_sensor = true;
      parse_sensor(c);
    } else if (tag == "integrator") {
      if (have_integrator) fail(c, "a second <integrator>");
      have_integrator = true;
      parse_integrator(c);
    } else if (tag == "emitter") {
      parse_emitter(c);
    } else if (tag == "texture" || tag == "medium" || tag == "include" || tag == "default" || tag == "alias" ||
               tag == "path" || tag == "phase" || tag == "volume") {
      fail(c, fmt::format("<{}> is not supported by the Mitsuba import", tag));
    } else {
      fail(c, fmt::format("unknown element <{}> (supported at the top level: integrator, sensor, bsdf, shape, emitter)", tag));
    }
  }
  if (!have_sensor) fail(root, "no <sensor>");
  if (!have_integrator)
    fail(root, "no <integrator> (Mitsuba's default path tracer has unbounded depth, which is not supported)");
  if (shapes_.empty()) fail(root, "a scene needs at least one <shape>");
  integrator_["spp"] = spp_;

  json out = json::object();
  out["description"] =
      "Imported from the Mitsuba XML scene " + file_ + " (docs/scene.md, 'Importing Mitsuba scenes')";
  out["camera"] = camera_;
  out["materials"] = materials_;
  out["shapes"] = shapes_;
  if (!lights_.empty()) out["lights"] = lights_;
  out["integrator"] = integrator_;
  return out;
}

}  // namespace

bool is_mitsuba_scene(const std::string& text) {
  size_t i = 0;
  if (text.size() >= 3 && text.compare(0, 3, "\xEF\xBB\xBF") == 0) i = 3;
  while (i < text.size() && std::isspace(static_cast<unsigned char>(text[i]))) ++i;
  return i < text.size() && text[i] == '<';
}

json mitsuba_to_scene_json(const std::string& text, const std::string& file, const std::string& base_dir) {
  Importer im(text, file, base_dir.empty() ? "." : base_dir);
  return im.run();
}

}  // namespace tb
