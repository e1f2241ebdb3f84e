#include "lib/core/strict_json.h"

#include <algorithm>
#include <cmath>
#include <iterator>

#include <fmt/format.h>

#include "lib/core/atomic_file.h"

namespace tb {

namespace {

// An input iterator over a char buffer that publishes how far the parser has read, so the
// parse callback can attach a line number to each key and value.
struct CountingIterator {
  using iterator_category = std::input_iterator_tag;
  using value_type = char;
  using difference_type = std::ptrdiff_t;
  using pointer = const char*;
  using reference = const char&;

  const char* p = nullptr;
  const char* base = nullptr;
  size_t* consumed = nullptr;

  reference operator*() const { return *p; }
  CountingIterator& operator++() {
    ++p;
    *consumed = static_cast<size_t>(p - base);
    return *this;
  }
  CountingIterator operator++(int) {
    CountingIterator t = *this;
    ++*this;
    return t;
  }
  bool operator==(const CountingIterator& o) const { return p == o.p; }
};

std::string escape_pointer_token(const std::string& k) {
  std::string o;
  for (char c : k) {
    if (c == '~')
      o += "~0";
    else if (c == '/')
      o += "~1";
    else
      o += c;
  }
  return o;
}

struct JsonFrame {
  bool array = false;
  size_t index = 0;
  std::string key;
  std::string pointer;
};

}  // namespace

std::shared_ptr<const JsonDocument> JsonDocument::parse(const std::string& text, const std::string& file) {
  auto doc = std::make_shared<JsonDocument>();
  doc->file = file;
  std::vector<size_t> line_starts{0};
  for (size_t i = 0; i < text.size(); ++i)
    if (text[i] == '\n') line_starts.push_back(i + 1);
  size_t consumed = 0;
  auto line_at = [&](size_t offset) {
    // The parser has read one character past a token at most; step back onto it.
    const size_t o = offset > 0 ? offset - 1 : 0;
    return static_cast<int>(std::upper_bound(line_starts.begin(), line_starts.end(), o) - line_starts.begin());
  };
  std::vector<JsonFrame> frames;
  auto child_pointer = [&]() -> std::string {
    if (frames.empty()) return "";
    const JsonFrame& f = frames.back();
    return f.pointer + "/" + (f.array ? std::to_string(f.index) : escape_pointer_token(f.key));
  };
  auto element_done = [&]() {
    if (!frames.empty() && frames.back().array) ++frames.back().index;
  };
  using E = nlohmann::json::parse_event_t;
  auto cb = [&](int, E event, nlohmann::json& parsed) -> bool {
    const int line = line_at(consumed);
    switch (event) {
      case E::object_start:
      case E::array_start: {
        // Every open level stores its JSON pointer, so memory grows with depth^2; no scene
        // or configuration nests anywhere near this deep.
        constexpr size_t kMaxDepth = 256;
        if (frames.size() >= kMaxDepth)
          throw JsonError(fmt::format("{}:{}: JSON nested deeper than {} levels", file, line, kMaxDepth));
        const std::string ptr = child_pointer();
        doc->lines.emplace(ptr, line);
        frames.push_back(JsonFrame{event == E::array_start, 0, "", ptr});
        break;
      }
      case E::key:
        frames.back().key = parsed.get<std::string>();
        doc->lines.emplace(child_pointer(), line);
        break;
      case E::object_end:
      case E::array_end:
        frames.pop_back();
        element_done();
        break;
      case E::value:
        doc->lines.emplace(child_pointer(), line);
        element_done();
        break;
    }
    return true;
  };
  CountingIterator first{text.data(), text.data(), &consumed}, last{text.data() + text.size(), text.data(), &consumed};
  try {
    doc->root = nlohmann::json::parse(first, last, cb, /*allow_exceptions=*/true, /*ignore_comments=*/true);
  } catch (const nlohmann::json::parse_error& e) {
    throw JsonError(fmt::format("{}:{}: JSON syntax error: {}", file, line_at(e.byte), e.what()));
  }
  return doc;
}

std::shared_ptr<const JsonDocument> JsonDocument::load(const std::string& path) {
  std::string text;
  try {
    text = read_file(path);
  } catch (const std::exception& e) {
    throw JsonError(e.what());
  }
  return parse(text, path);
}

std::string JsonDocument::where(const std::string& pointer) const {
  std::string p = pointer;
  while (true) {
    auto it = lines.find(p);
    if (it != lines.end()) return fmt::format("{}:{}", file, it->second);
    if (p.empty()) return file;
    p = p.substr(0, p.find_last_of('/'));
  }
}

size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (size_t j = 1; j <= b.size(); ++j)
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

StrictObject::StrictObject(std::shared_ptr<const JsonDocument> doc, std::string pointer)
    : doc_(std::move(doc)), pointer_(std::move(pointer)) {
  obj_ = &doc_->root.at(nlohmann::json::json_pointer(pointer_));
  if (!obj_->is_object())
    throw JsonError(fmt::format("{}: {}: expected an object, found {}", doc_->where(pointer_),
                                pointer_.empty() ? "/" : pointer_, obj_->type_name()));
}

std::string StrictObject::child(const std::string& key) const { return pointer_ + "/" + escape_pointer_token(key); }

void StrictObject::fail(const std::string& key, const std::string& what) const {
  const std::string p = key.empty() ? pointer_ : child(key);
  throw JsonError(fmt::format("{}: {}: {}", doc_->where(p), p.empty() ? "/" : p, what));
}

bool StrictObject::has(const std::string& key) const { return obj_->contains(key); }

std::vector<std::string> StrictObject::keys() const {
  std::vector<std::string> k;
  for (const auto& [key, v] : obj_->items()) k.push_back(key);
  return k;
}

const nlohmann::json& StrictObject::value(const std::string& key) const {
  auto it = obj_->find(key);
  if (it == obj_->end()) fail(key, "missing required key '" + key + "'");
  used_.insert(key);
  return *it;
}

const nlohmann::json& StrictObject::raw(const std::string& key) const { return value(key); }

double StrictObject::number(const std::string& key) const {
  const auto& v = value(key);
  if (!v.is_number()) fail(key, fmt::format("expected a number, found {}", v.type_name()));
  const double x = v.get<double>();
  if (!std::isfinite(x)) fail(key, "number is not finite");
  return x;
}
double StrictObject::number(const std::string& key, double fallback) const { return has(key) ? number(key) : fallback; }
double StrictObject::positive(const std::string& key) const {
  const double x = number(key);
  if (!(x > 0)) fail(key, fmt::format("must be positive, is {}", x));
  return x;
}
int64_t StrictObject::integer(const std::string& key) const {
  const auto& v = value(key);
  if (!v.is_number_integer()) fail(key, fmt::format("expected an integer, found {}", v.type_name()));
  return v.get<int64_t>();
}
int64_t StrictObject::integer(const std::string& key, int64_t fallback) const {
  return has(key) ? integer(key) : fallback;
}
bool StrictObject::boolean(const std::string& key, bool fallback) const {
  if (!has(key)) return fallback;
  const auto& v = value(key);
  if (!v.is_boolean()) fail(key, fmt::format("expected true or false, found {}", v.type_name()));
  return v.get<bool>();
}
std::string StrictObject::string(const std::string& key) const {
  const auto& v = value(key);
  if (!v.is_string()) fail(key, fmt::format("expected a string, found {}", v.type_name()));
  return v.get<std::string>();
}
std::string StrictObject::string(const std::string& key, const std::string& fallback) const {
  return has(key) ? string(key) : fallback;
}
std::string StrictObject::choice(const std::string& key, const std::vector<std::string>& allowed) const {
  const std::string s = string(key);
  if (std::find(allowed.begin(), allowed.end(), s) == allowed.end()) {
    std::string list;
    for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
    fail(key, fmt::format("'{}' is not one of: {}", s, list));
  }
  return s;
}
std::string StrictObject::choice(const std::string& key, const std::vector<std::string>& allowed,
                                 const std::string& fallback) const {
  return has(key) ? choice(key, allowed) : fallback;
}
std::vector<double> StrictObject::numbers(const std::string& key) const {
  const auto& v = value(key);
  if (!v.is_array()) fail(key, fmt::format("expected an array of numbers, found {}", v.type_name()));
  std::vector<double> out;
  for (size_t i = 0; i < v.size(); ++i) {
    if (!v[i].is_number()) fail(key, fmt::format("element {} is {}, expected a number", i, v[i].type_name()));
    const double x = v[i].get<double>();
    if (!std::isfinite(x)) fail(key, fmt::format("element {} is not finite", i));
    out.push_back(x);
  }
  return out;
}
Vec2 StrictObject::vec2(const std::string& key) const {
  const auto n = numbers(key);
  if (n.size() != 2) fail(key, fmt::format("expected 2 numbers, found {}", n.size()));
  return {n[0], n[1]};
}
Vec3 StrictObject::vec3(const std::string& key) const {
  const auto n = numbers(key);
  if (n.size() != 3) fail(key, fmt::format("expected 3 numbers, found {}", n.size()));
  return {n[0], n[1], n[2]};
}
Vec3 StrictObject::vec3(const std::string& key, const Vec3& fallback) const { return has(key) ? vec3(key) : fallback; }
Vec3 StrictObject::rgb(const std::string& key, const Vec3& fallback) const {
  if (!has(key)) return fallback;
  if (value(key).is_number()) return Vec3(number(key));
  return vec3(key);
}
StrictObject StrictObject::object(const std::string& key) const {
  const auto& v = value(key);
  if (!v.is_object()) fail(key, fmt::format("expected an object, found {}", v.type_name()));
  return StrictObject(doc_, child(key));
}
std::optional<StrictObject> StrictObject::optional_object(const std::string& key) const {
  if (!has(key)) return std::nullopt;
  return object(key);
}
std::vector<StrictObject> StrictObject::objects(const std::string& key) const {
  std::vector<StrictObject> out;
  if (!has(key)) return out;
  const auto& v = value(key);
  if (!v.is_array()) fail(key, fmt::format("expected an array of objects, found {}", v.type_name()));
  for (size_t i = 0; i < v.size(); ++i) {
    if (!v[i].is_object()) fail(key, fmt::format("element {} is {}, expected an object", i, v[i].type_name()));
    out.emplace_back(doc_, child(key) + "/" + std::to_string(i));
  }
  return out;
}

void StrictObject::finish(const std::vector<std::string>& known_extra) const {
  for (const auto& [k, v] : obj_->items()) {
    if (used_.count(k)) continue;
    std::vector<std::string> known(used_.begin(), used_.end());
    known.insert(known.end(), known_extra.begin(), known_extra.end());
    std::string best;
    size_t best_d = 3;  // suggest only close matches
    for (const auto& c : known) {
      const size_t d = edit_distance(k, c);
      if (d < best_d) best_d = d, best = c;
    }
    fail(k, best.empty() ? fmt::format("unknown key '{}'", k)
                         : fmt::format("unknown key '{}' (did you mean '{}'?)", k, best));
  }
}

}  // namespace tb
