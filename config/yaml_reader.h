#pragma once
// Checked reading of YAML mappings, for the scene loader (config/scene.cc).
//
// Every value is fetched by key with its type and range checked, so a schema reads top to
// bottom as a list of Get calls. Every failure throws hapsim::InputError naming the file, the
// 1-based line and the dotted key path ("body.probes[1].position_m"):
//   - an error about a value is reported on the line of its key;
//   - a missing required key is reported on the line of the key that holds the map it is missing
//     from (or of the map itself for the document root and for list items);
//   - a list item as a whole is reported on the line of the item.
// Numbers are parsed strictly: a double accepts plain decimals and exponents ("50000", "1e-6"),
// an int accepts only plain integers ("200", not "1.5" or "2e2"); quoted strings, NaN, infinities
// and overflows are errors.

#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <initializer_list>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace hapsim::config {

// The allowed range of a number: a lower and an upper bound, each open or closed.
struct Bounds {
  double lower = -std::numeric_limits<double>::infinity();
  double upper = std::numeric_limits<double>::infinity();
  bool lower_open = false;
  bool upper_open = false;

  bool Contains(double value) const;
  std::string Describe() const;  // e.g. "> 0", ">= 1", "in (-1, 0.5)"
};

inline Bounds Any() { return Bounds{}; }
inline Bounds Above(double lower) { return Bounds{lower, Any().upper, true, false}; }
inline Bounds AtLeast(double lower) { return Bounds{lower, Any().upper, false, false}; }
inline Bounds OpenInterval(double lower, double upper) { return Bounds{lower, upper, true, true}; }
inline Bounds ClosedInterval(double lower, double upper) {
  return Bounds{lower, upper, false, false};
}

// A YAML mapping together with where it sits: the file, its dotted key path and its line.
// Cheap to copy (YAML::Node is a handle).
class YamlMap {
 public:
  // Parses a whole document, which must be a mapping. Throws InputError on a YAML syntax error
  // (at the line yaml-cpp reports), an empty document, or a document that is not a mapping.
  static YamlMap Parse(const std::string& yaml_text, const std::string& file);

  const std::string& file() const { return file_; }
  const std::string& path() const { return path_; }  // empty for the document root
  int line() const { return line_; }

  bool Has(const std::string& key) const { return Find(key) != nullptr; }
  std::string KeyPath(const std::string& key) const;  // path() + "." + key
  int LineOf(const std::string& key) const;           // line of the key, or line() if it is absent

  // Throws on the first key not in `allowed`, naming it and listing the allowed keys.
  void CheckKeys(std::initializer_list<const char*> allowed) const;

  // Throw InputError about this map / about `key` of this map.
  [[noreturn]] void Fail(const std::string& message) const;
  [[noreturn]] void FailKey(const std::string& key, const std::string& message) const;

  // Required values: throw if the key is absent, of the wrong type or outside `bounds`.
  double GetDouble(const std::string& key, const Bounds& bounds = Any()) const;
  int GetInt(const std::string& key, const Bounds& bounds = Any()) const;
  std::string GetString(const std::string& key) const;  // any scalar, taken as written
  Eigen::Vector3d GetVector3(const std::string& key, const Bounds& bounds = Any()) const;
  Eigen::Vector3i GetVector3i(const std::string& key, const Bounds& bounds = Any()) const;
  YamlMap GetMap(const std::string& key) const;

  // Optional values: `default_value` (or nothing) when the key is absent, checked when present.
  std::string GetStringOr(const std::string& key, const std::string& default_value) const;
  Eigen::Vector3d GetVector3Or(const std::string& key, const Eigen::Vector3d& default_value,
                               const Bounds& bounds = Any()) const;
  Eigen::Vector2d GetVector2Or(const std::string& key, const Eigen::Vector2d& default_value,
                               const Bounds& bounds = Any()) const;
  double GetDoubleOr(const std::string& key, double default_value,
                     const Bounds& bounds = Any()) const;
  int GetIntOr(const std::string& key, int default_value, const Bounds& bounds = Any()) const;
  bool GetBoolOr(const std::string& key, bool default_value) const {  // true | false
    return GetEnumOr<bool>(key, {{"true", true}, {"false", false}}, default_value);
  }
  std::optional<YamlMap> FindMap(const std::string& key) const;
  // A list of mappings (empty when absent); item i has path "key[i]" and its own line.
  std::vector<YamlMap> GetMapList(const std::string& key) const;

  // A string that must be one of `choices`' names; the error lists them.
  template <typename Enum>
  Enum GetEnumOr(const std::string& key, const std::vector<std::pair<std::string, Enum>>& choices,
                 Enum default_value) const {
    if (!Has(key)) return default_value;
    std::vector<std::string> names;
    for (const auto& choice : choices) names.push_back(choice.first);
    return choices[GetChoiceIndex(key, names)].second;
  }

 private:
  struct Entry {
    std::string key;
    int line;  // 1-based line of the key
    YAML::Node value;
  };

  // `node` must be a mapping. Throws on a key that is not a plain scalar or appears twice.
  YamlMap(const YAML::Node& node, std::string file, std::string path, int line);

  const Entry* Find(const std::string& key) const;
  const Entry& Require(const std::string& key) const;  // throws "missing required key"
  double ReadNumber(const std::string& key, const YAML::Node& node, bool integer,
                    const Bounds& bounds, const std::string& element) const;
  Eigen::VectorXd ReadNumbers(const std::string& key, int count, bool integer,
                              const Bounds& bounds) const;
  Eigen::Vector3d ReadVector3(const std::string& key, bool integer, const Bounds& bounds) const;
  int GetChoiceIndex(const std::string& key, const std::vector<std::string>& names) const;

  std::string file_;
  std::string path_;
  int line_ = 0;
  std::vector<Entry> entries_;  // in file order; maps in a scene are small, so lookup is linear
};

}  // namespace hapsim::config
