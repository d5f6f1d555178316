#include "config/yaml_reader.h"

#include <charconv>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <system_error>

#include "core/error.h"

namespace hapsim::config {
namespace {

// yaml-cpp marks are 0-based; a null mark (a node the parser did not place) gets `fallback`.
int LineOfMark(const YAML::Mark& mark, int fallback) {
  return mark.is_null() ? fallback : mark.line + 1;
}

// What a node holds, for "must be X, got Y" messages.
std::string DescribeNode(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Null:
    case YAML::NodeType::Undefined:
      return "nothing";
    case YAML::NodeType::Sequence:
      return "a list of " + std::to_string(node.size());
    case YAML::NodeType::Map:
      return "a map";
    case YAML::NodeType::Scalar:
      break;
  }
  if (node.Tag() == "?") return "'" + node.Scalar() + "'";  // plain (unquoted) scalar
  return "the string \"" + node.Scalar() + "\"";
}

std::string FormatNumber(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

// Parses a plain scalar strictly as a number (an int when `integer`). Returns an error message,
// empty on success. std::from_chars is locale-independent: "0.45" reads the same in a program
// whose locale uses a decimal comma.
std::string ParseNumber(const YAML::Node& node, bool integer, double* value) {
  const std::string expected = integer ? "an integer" : "a number";
  if (!node.IsScalar() || node.Tag() != "?") {
    return "must be " + expected + ", got " + DescribeNode(node);
  }
  const std::string& text = node.Scalar();
  const char* allowed = integer ? "+-0123456789" : "+-0123456789.eE";
  const bool has_plus = text.size() > 1 && text[0] == '+' && text[1] != '-';  // from_chars: no '+'
  const char* first = text.data() + (has_plus ? 1 : 0);
  const char* last = text.data() + text.size();
  std::from_chars_result result{first, std::errc::invalid_argument};
  if (!text.empty() && text.find_first_not_of(allowed) == std::string::npos) {
    long long as_integer = 0;
    result = integer ? std::from_chars(first, last, as_integer)
                     : std::from_chars(first, last, *value, std::chars_format::general);
    if (integer) *value = static_cast<double>(as_integer);
  }
  if (result.ec == std::errc::invalid_argument || result.ptr != last) {
    double special = 0.0;  // yaml-cpp's own reading knows .nan and .inf
    if (YAML::convert<double>::decode(node, special) && !std::isfinite(special)) {
      return "must be finite, got '" + text + "'";
    }
    return "must be " + expected + ", got '" + text + "'";
  }
  if (integer && (result.ec != std::errc() || std::abs(*value) > INT_MAX)) {
    return "must be an integer within ±" + std::to_string(INT_MAX) + ", got '" + text + "'";
  }
  if (result.ec != std::errc())
    return "must be finite and within the range of a double, got '" + text + "'";
  return "";
}

}  // namespace

bool Bounds::Contains(double value) const {
  const bool above = lower_open ? value > lower : value >= lower;
  const bool below = upper_open ? value < upper : value <= upper;
  return above && below;
}

std::string Bounds::Describe() const {
  const bool has_lower = std::isfinite(lower);
  const bool has_upper = std::isfinite(upper);
  if (has_lower && has_upper) {
    return std::string("in ") + (lower_open ? "(" : "[") + FormatNumber(lower) + ", " +
           FormatNumber(upper) + (upper_open ? ")" : "]");
  }
  if (has_lower) return (lower_open ? "> " : ">= ") + FormatNumber(lower);
  if (has_upper) return (upper_open ? "< " : "<= ") + FormatNumber(upper);
  return "any number";
}

YamlMap YamlMap::Parse(const std::string& yaml_text, const std::string& file) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {  // ParserException and its kin carry the mark
    throw InputError(file, LineOfMark(e.mark, 0), "", "YAML syntax error: " + e.msg);
  }
  if (root.IsNull()) throw InputError(file, 0, "", "the document is empty");
  const int line = LineOfMark(root.Mark(), 1);
  if (!root.IsMap()) {
    throw InputError(file, line, "",
                     "the document must be a map of keys, got " + DescribeNode(root));
  }
  return YamlMap(root, file, "", line);
}

YamlMap::YamlMap(const YAML::Node& node, std::string file, std::string path, int line)
    : file_(std::move(file)), path_(std::move(path)), line_(line) {
  for (const auto& item : node) {
    const int key_line = LineOfMark(item.first.Mark(), line_);
    if (!item.first.IsScalar()) {
      throw InputError(file_, key_line, path_,
                       "keys must be plain names, got " + DescribeNode(item.first));
    }
    const std::string& key = item.first.Scalar();
    if (const Entry* first = Find(key)) {
      throw InputError(file_, key_line, KeyPath(key),
                       "duplicate key (first given on line " + std::to_string(first->line) + ")");
    }
    entries_.push_back(Entry{key, key_line, item.second});
  }
}

std::string YamlMap::KeyPath(const std::string& key) const {
  return path_.empty() ? key : path_ + "." + key;
}

int YamlMap::LineOf(const std::string& key) const {
  const Entry* entry = Find(key);
  return entry != nullptr ? entry->line : line_;
}

void YamlMap::CheckKeys(std::initializer_list<const char*> allowed) const {
  for (const Entry& entry : entries_) {
    bool known = false;
    std::string list;
    for (const char* name : allowed) {
      known = known || entry.key == name;
      list += (list.empty() ? "" : ", ") + std::string(name);
    }
    if (!known) FailKey(entry.key, "unknown key '" + entry.key + "'; allowed keys here: " + list);
  }
}

void YamlMap::Fail(const std::string& message) const {
  throw InputError(file_, line_, path_, message);
}

void YamlMap::FailKey(const std::string& key, const std::string& message) const {
  throw InputError(file_, LineOf(key), KeyPath(key), message);
}

const YamlMap::Entry* YamlMap::Find(const std::string& key) const {
  for (const Entry& entry : entries_) {
    if (entry.key == key) return &entry;
  }
  return nullptr;
}

const YamlMap::Entry& YamlMap::Require(const std::string& key) const {
  const Entry* entry = Find(key);
  if (entry == nullptr) FailKey(key, "missing required key");
  return *entry;
}

double YamlMap::ReadNumber(const std::string& key, const YAML::Node& node, bool integer,
                           const Bounds& bounds, const std::string& element) const {
  double value = 0.0;
  const std::string error = ParseNumber(node, integer, &value);
  if (!error.empty()) FailKey(key, element + error);
  if (!bounds.Contains(value)) {
    FailKey(key, element + "must be " + bounds.Describe() + ", got '" + node.Scalar() + "'");
  }
  return value;
}

double YamlMap::GetDouble(const std::string& key, const Bounds& bounds) const {
  return ReadNumber(key, Require(key).value, /*integer=*/false, bounds, "");
}

int YamlMap::GetInt(const std::string& key, const Bounds& bounds) const {
  return static_cast<int>(ReadNumber(key, Require(key).value, /*integer=*/true, bounds, ""));
}

std::string YamlMap::GetString(const std::string& key) const {
  const YAML::Node& value = Require(key).value;
  if (!value.IsScalar()) FailKey(key, "must be a string, got " + DescribeNode(value));
  return value.Scalar();
}

Eigen::VectorXd YamlMap::ReadNumbers(const std::string& key, int count, bool integer,
                                     const Bounds& bounds) const {
  const YAML::Node& value = Require(key).value;
  const std::string expected = "a list of " + std::to_string(count) +
                               (integer ? " integers" : " numbers");
  if (!value.IsSequence() || value.size() != static_cast<std::size_t>(count)) {
    FailKey(key, "must be " + expected + ", got " + DescribeNode(value));
  }
  Eigen::VectorXd vector(count);
  for (int i = 0; i < count; ++i) {
    vector[i] =
        ReadNumber(key, value[i], integer, bounds, "element " + std::to_string(i + 1) + " ");
  }
  return vector;
}

Eigen::Vector3d YamlMap::ReadVector3(const std::string& key, bool integer,
                                     const Bounds& bounds) const {
  return ReadNumbers(key, 3, integer, bounds);
}

Eigen::Vector2d YamlMap::GetVector2Or(const std::string& key, const Eigen::Vector2d& default_value,
                                      const Bounds& bounds) const {
  return Has(key) ? Eigen::Vector2d(ReadNumbers(key, 2, /*integer=*/false, bounds)) : default_value;
}

Eigen::Vector3d YamlMap::GetVector3(const std::string& key, const Bounds& bounds) const {
  return ReadVector3(key, /*integer=*/false, bounds);
}

Eigen::Vector3i YamlMap::GetVector3i(const std::string& key, const Bounds& bounds) const {
  return ReadVector3(key, /*integer=*/true, bounds).cast<int>();
}

YamlMap YamlMap::GetMap(const std::string& key) const {
  const Entry& entry = Require(key);
  if (!entry.value.IsMap()) FailKey(key, "must be a map, got " + DescribeNode(entry.value));
  return YamlMap(entry.value, file_, KeyPath(key), entry.line);
}

std::string YamlMap::GetStringOr(const std::string& key, const std::string& default_value) const {
  return Has(key) ? GetString(key) : default_value;
}

Eigen::Vector3d YamlMap::GetVector3Or(const std::string& key, const Eigen::Vector3d& default_value,
                                      const Bounds& bounds) const {
  return Has(key) ? GetVector3(key, bounds) : default_value;
}

double YamlMap::GetDoubleOr(const std::string& key, double default_value,
                            const Bounds& bounds) const {
  return Has(key) ? GetDouble(key, bounds) : default_value;
}

int YamlMap::GetIntOr(const std::string& key, int default_value, const Bounds& bounds) const {
  return Has(key) ? GetInt(key, bounds) : default_value;
}

std::optional<YamlMap> YamlMap::FindMap(const std::string& key) const {
  if (!Has(key)) return std::nullopt;
  return GetMap(key);
}

std::vector<YamlMap> YamlMap::GetMapList(const std::string& key) const {
  const Entry* entry = Find(key);
  if (entry == nullptr) return {};
  if (!entry->value.IsSequence()) FailKey(key, "must be a list, got " + DescribeNode(entry->value));
  std::vector<YamlMap> items;
  for (std::size_t i = 0; i < entry->value.size(); ++i) {
    const YAML::Node& item = entry->value[i];
    const std::string item_path = KeyPath(key) + "[" + std::to_string(i) + "]";
    const int item_line = LineOfMark(item.Mark(), entry->line);
    if (!item.IsMap()) {
      throw InputError(file_, item_line, item_path, "must be a map, got " + DescribeNode(item));
    }
    items.push_back(YamlMap(item, file_, item_path, item_line));
  }
  return items;
}

int YamlMap::GetChoiceIndex(const std::string& key, const std::vector<std::string>& names) const {
  const std::string value = GetString(key);
  std::string list;
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (value == names[i]) return static_cast<int>(i);
    list += (i == 0 ? "" : ", ") + names[i];
  }
  FailKey(key, "must be one of: " + list + "; got '" + value + "'");
}

}  // namespace hapsim::config
