// Strict reading of JSON settings (scenes, experiment configurations): every value is
// looked up through a StrictObject that remembers which keys were used, so an unknown or
// unused key is an error that names the key, its JSON pointer, the file and the line
// (after pbrt's ReportUnused). Wrong types, missing fields and non-finite numbers are errors
// in the same form. Errors are exceptions (JsonError), never aborts.
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "lib/core/math.h"

namespace tb {

class JsonError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A parsed document with the line of every key, object, array element and value, by JSON pointer.
struct JsonDocument {
  nlohmann::json root;
  std::string file;                     // shown in messages ("<string>" when parsed from text)
  std::map<std::string, int> lines;     // JSON pointer -> 1-based line

  // Parses text; a syntax error becomes a JsonError "file:line:col: ...".
  static std::shared_ptr<const JsonDocument> parse(const std::string& text, const std::string& file = "<string>");
  static std::shared_ptr<const JsonDocument> load(const std::string& path);
  // "file:line" for the pointer, or for its nearest located ancestor.
  std::string where(const std::string& pointer) const;
};

class StrictObject {
 public:
  StrictObject(std::shared_ptr<const JsonDocument> doc, std::string pointer);
  // The root object of a document.
  static StrictObject root(std::shared_ptr<const JsonDocument> doc) { return StrictObject(std::move(doc), ""); }

  bool has(const std::string& key) const;
  // The keys present, in document order of nlohmann's map (sorted).
  std::vector<std::string> keys() const;
  const std::string& pointer() const { return pointer_; }
  [[noreturn]] void fail(const std::string& key, const std::string& what) const;

  double number(const std::string& key) const;                  // finite
  double number(const std::string& key, double fallback) const;
  double positive(const std::string& key) const;                // finite, > 0
  int64_t integer(const std::string& key) const;
  int64_t integer(const std::string& key, int64_t fallback) const;
  bool boolean(const std::string& key, bool fallback) const;
  std::string string(const std::string& key) const;
  std::string string(const std::string& key, const std::string& fallback) const;
  // One of the allowed strings, else an error listing them.
  std::string choice(const std::string& key, const std::vector<std::string>& allowed) const;
  std::string choice(const std::string& key, const std::vector<std::string>& allowed, const std::string& fallback) const;
  Vec2 vec2(const std::string& key) const;
  Vec3 vec3(const std::string& key) const;
  Vec3 vec3(const std::string& key, const Vec3& fallback) const;
  // A number broadcast to three components or an array of three.
  Vec3 rgb(const std::string& key, const Vec3& fallback) const;
  std::vector<double> numbers(const std::string& key) const;
  StrictObject object(const std::string& key) const;
  std::optional<StrictObject> optional_object(const std::string& key) const;
  std::vector<StrictObject> objects(const std::string& key) const;  // an array of objects (may be absent: empty)
  const nlohmann::json& raw(const std::string& key) const;          // marks used; no checks

  // Throws if any key of this object was never read, suggesting the closest known key.
  void finish(const std::vector<std::string>& known_extra = {}) const;

 private:
  const nlohmann::json& value(const std::string& key) const;  // marks used; throws if missing
  std::string child(const std::string& key) const;

  std::shared_ptr<const JsonDocument> doc_;
  std::string pointer_;
  const nlohmann::json* obj_;
  mutable std::set<std::string> used_;
};

// Levenshtein distance, for "did you mean" suggestions.
size_t edit_distance(const std::string& a, const std::string& b);

}  // namespace tb
