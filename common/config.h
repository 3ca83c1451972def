#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <set>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <fmt/ranges.h>
#include <glm/vec3.hpp>
#include <nlohmann/json.hpp>

#include "common/error.h"

namespace canopy {

// A JSON object read key by key. Every read marks its key as used; finish() rejects any key that
// was never read, naming it with its full path ("methods[1].params.billboards"), so a typo in a
// config is an error and never a silently ignored setting.
class ConfigObject {
 public:
  ConfigObject(const nlohmann::json& json, std::string path);

  const std::string& path() const { return mPath; }
  std::string keyPath(const std::string& key) const;
  bool has(const std::string& key) const { return mJson.contains(key); }

  // The raw value of a key (marked used); throws InputError when the key is absent.
  const nlohmann::json& require(const std::string& key);
  // The raw value, or nullptr json when absent (marked used either way).
  const nlohmann::json* find(const std::string& key);

  template <typename T>
  T get(const std::string& key, const T& fallback) {
    const nlohmann::json* value = find(key);
    return value ? convert<T>(*value, key) : fallback;
  }
  template <typename T>
  T get(const std::string& key) {
    return convert<T>(require(key), key);
  }

  ConfigObject child(const std::string& key);
  std::vector<ConfigObject> children(const std::string& key);  // an array of objects

  // Throws InputError for the first key that was not read. `owner` says whose keys they are.
  void finish(const std::string& owner = "") const;

  template <typename T>
  T convert(const nlohmann::json& value, const std::string& key) const {
    try {
      if constexpr (std::is_same_v<T, bool>) {
        if (!value.is_boolean()) throw std::invalid_argument("expected true or false");
      } else if constexpr (std::is_arithmetic_v<T>) {
        if (!value.is_number()) throw std::invalid_argument("expected a number");
        if constexpr (std::is_integral_v<T>) {
          if (!value.is_number_integer()) throw std::invalid_argument("expected an integer");
          // In range of T, not wrapped into it (4294967297 is no int).
          const bool fits =
              value.is_number_unsigned()
                  ? value.get<uint64_t>() <= uint64_t(std::numeric_limits<T>::max())
                  : value.get<int64_t>() >= int64_t(std::numeric_limits<T>::min()) &&
                        (std::is_unsigned_v<T> ||
                         value.get<int64_t>() <= int64_t(std::numeric_limits<T>::max()));
          if (!fits) throw std::invalid_argument("integer out of range");
        } else if (!std::isfinite(value.get<double>())) {
          throw std::invalid_argument("not a finite number");
        }
      } else if constexpr (std::is_same_v<T, std::string>) {
        if (!value.is_string()) throw std::invalid_argument("expected a string");
      }
      return value.get<T>();
    } catch (const std::exception& error) {
      throwInputError("config {}: bad value {} ({})", keyPath(key), value.dump(), error.what());
    }
  }

 private:
  const nlohmann::json& mJson;
  std::string mPath;
  mutable std::set<std::string> mUsed;
};

// Every JSON text the project reads (configs, records, captures, camera paths, asset headers)
// goes through this parser: syntax errors, numbers out of double range (1e400), objects that
// name a key twice (JSON leaves the winner open) and nesting deeper than kMaxJsonDepth (which
// would otherwise exhaust the stack later) are InputErrors naming `source` and the position.
inline constexpr int kMaxJsonDepth = 64;
nlohmann::json parseJson(const std::string& text, const std::string& source);

// The whole of a file; InputError naming it when it is a folder or cannot be opened or read.
std::string readTextFile(const std::string& path);
// Reads a JSON file through parseJson; InputError naming the file when it is missing, unreadable
// or not valid JSON.
nlohmann::json readJsonFile(const std::string& path);

// A value used as one component of a path (an experiment or tree name): non-empty, at most 100
// characters from [A-Za-z0-9_.-], not "." or "..", so it can neither escape its folder nor
// collide with the folder itself. InputError naming `what` otherwise; returns the value.
const std::string& checkPathComponent(const std::string& value, const std::string& what);

// Typed parameter structs describe their fields once, through a visitor, each with its range and
// its documentation:
//   template <class V> void visit(V& v) {
//     v("hash_resolution", hashResolution, 1, 4096, "hash cells along a billboard's side");
//   }
// ParamReader fills them from a config (range-checked, unknown keys rejected), ParamWriter writes
// them back as the effective parameters and ParamDescriber lists them (key, type, default, range,
// doc) for --list-methods and docs/METHODS.md, so reading, reporting and documenting cannot drift
// apart. Field kinds: a number in [lo, hi]; bool; a free string; a string from a list; an enum
// named by strings; a non-empty list of numbers in [lo, hi]; a glm::vec3; a Resolution.

// Two integers configured as one [width, height] key.
struct Resolution {
  int& width;
  int& height;
};

template <typename E>
using EnumNames = std::vector<std::pair<std::string, E>>;

class ParamReader {
 public:
  ParamReader(ConfigObject& config, std::string owner)
      : mConfig(config), mOwner(std::move(owner)) {}

  template <typename T>
  requires std::is_arithmetic_v<T>
  void operator()(const char* key, T& field, T lo, T hi, const char*) {
    if (mConfig.has(key)) field = checked(key, mConfig.get<T>(key), lo, hi);
  }
  void operator()(const char* key, bool& field, const char*) {
    if (mConfig.has(key)) field = mConfig.get<bool>(key);
  }
  void operator()(const char* key, std::string& field, const char*) {
    if (mConfig.has(key)) field = mConfig.get<std::string>(key);
  }
  void operator()(const char* key, std::string& field, const std::vector<std::string>& allowed,
                  const char*);
  template <typename E>
  void operator()(const char* key, E& field, const EnumNames<E>& names, const char*) {
    if (!mConfig.has(key)) return;
    std::vector<std::string> allowed;
    for (const auto& [name, value] : names) allowed.push_back(name);
    std::string name = allowed.front();
    (*this)(key, name, allowed, "");
    for (const auto& [n, value] : names)
      if (n == name) field = value;
  }
  template <typename T>
  void operator()(const char* key, std::vector<T>& field, T lo, T hi, const char*) {
    if (!mConfig.has(key)) return;
    const nlohmann::json& list = mConfig.require(key);
    if (!list.is_array() || list.empty())
      throwInputError("{}: parameter '{}' must be a non-empty list", mOwner, mConfig.keyPath(key));
    std::vector<T> values;
    for (const nlohmann::json& item : list)
      values.push_back(checked(key, mConfig.convert<T>(item, key), lo, hi));
    field = std::move(values);
  }
  void operator()(const char* key, glm::vec3& field, float lo, float hi, const char*);
  void operator()(const char* key, Resolution field, int lo, int hi, const char*);

 private:
  template <typename T>
  T checked(const char* key, T value, T lo, T hi) const {
    if (!(value >= lo && value <= hi)) {
      throwInputError("{}: parameter '{}' = {} is out of range [{}, {}]", mOwner,
                      mConfig.keyPath(key), value, lo, hi);
    }
    return value;
  }
  // Exactly `count` numbers in [lo, hi].
  template <typename T>
  std::vector<T> fixedList(const char* key, size_t count, T lo, T hi, const char* shape) {
    std::vector<T> values;
    (*this)(key, values, lo, hi, "");
    if (values.size() != count)
      throwInputError("{}: parameter '{}' must be {}", mOwner, mConfig.keyPath(key), shape);
    return values;
  }

  ConfigObject& mConfig;
  std::string mOwner;
};

class ParamWriter {
 public:
  template <typename T>
  requires std::is_arithmetic_v<T>
  void operator()(const char* key, const T& field, T, T, const char*) { mJson[key] = field; }
  void operator()(const char* key, const bool& field, const char*) { mJson[key] = field; }
  void operator()(const char* key, const std::string& field, const char*) { mJson[key] = field; }
  void operator()(const char* key, const std::string& field, const std::vector<std::string>&,
                  const char*) {
    mJson[key] = field;
  }
  template <typename E>
  void operator()(const char* key, const E& field, const EnumNames<E>& names, const char*) {
    for (const auto& [name, value] : names)
      if (value == field) mJson[key] = name;
  }
  template <typename T>
  void operator()(const char* key, const std::vector<T>& field, T, T, const char*) {
    mJson[key] = field;
  }
  void operator()(const char* key, const glm::vec3& field, float, float, const char*) {
    mJson[key] = {field.x, field.y, field.z};
  }
  void operator()(const char* key, Resolution field, int, int, const char*) {
    mJson[key] = {field.width, field.height};
  }
  nlohmann::json& json() { return mJson; }

 private:
  nlohmann::json mJson = nlohmann::json::object();
};

// One parameter as a reader sees it: the config key, its type, its default, its range, its doc.
struct ParamDoc {
  std::string key, type, defaultValue, range, doc;
};

// Lists the fields of a parameter struct (visited on its default-constructed value).
class ParamDescriber {
 public:
  template <typename T>
  requires std::is_arithmetic_v<T>
  void operator()(const char* key, const T& field, T lo, T hi, const char* doc) {
    add(key, std::is_integral_v<T> ? "int" : "float", fmt::format("{}", field),
        fmt::format("[{}, {}]", lo, hi), doc);
  }
  void operator()(const char* key, const bool& field, const char* doc) {
    add(key, "bool", field ? "true" : "false", "", doc);
  }
  void operator()(const char* key, const std::string& field, const char* doc) {
    add(key, "string", nlohmann::json(field).dump(), "", doc);
  }
  void operator()(const char* key, const std::string& field,
                  const std::vector<std::string>& allowed, const char* doc) {
    add(key, "string", nlohmann::json(field).dump(), oneOf(allowed), doc);
  }
  template <typename E>
  void operator()(const char* key, const E& field, const EnumNames<E>& names, const char* doc) {
    std::vector<std::string> allowed;
    std::string current;
    for (const auto& [name, value] : names) {
      allowed.push_back(name);
      if (value == field) current = nlohmann::json(name).dump();
    }
    add(key, "string", current, oneOf(allowed), doc);
  }
  template <typename T>
  void operator()(const char* key, const std::vector<T>& field, T lo, T hi, const char* doc) {
    add(key, std::is_integral_v<T> ? "list of int" : "list of float",
        fmt::format("[{}]", fmt::join(field, ", ")), fmt::format("each in [{}, {}]", lo, hi), doc);
  }
  void operator()(const char* key, const glm::vec3& field, float lo, float hi, const char* doc) {
    add(key, "3 floats", fmt::format("[{}, {}, {}]", field.x, field.y, field.z),
        fmt::format("each in [{}, {}]", lo, hi), doc);
  }
  void operator()(const char* key, Resolution field, int lo, int hi, const char* doc) {
    add(key, "[width, height]", fmt::format("[{}, {}]", field.width, field.height),
        fmt::format("each in [{}, {}]", lo, hi), doc);
  }
  const std::vector<ParamDoc>& parameters() const { return mParameters; }

 private:
  static std::string oneOf(const std::vector<std::string>& allowed);
  void add(std::string key, std::string type, std::string value, std::string range,
           const char* doc) {
    mParameters.push_back(
        {std::move(key), std::move(type), std::move(value), std::move(range), doc ? doc : ""});
  }
  std::vector<ParamDoc> mParameters;
};

// Every parameter of `Params`, with the defaults of a default-constructed one.
template <typename Params>
std::vector<ParamDoc> describeParams() {
  Params params;
  ParamDescriber describer;
  params.visit(describer);
  return describer.parameters();
}

// Fills `params` from `config` (an object of parameters; may be null for all defaults) and
// rejects unknown keys, naming `owner`.
template <typename Params>
Params readParams(const nlohmann::json& config, const std::string& path, const std::string& owner) {
  Params params;
  static const nlohmann::json kEmpty = nlohmann::json::object();
  const nlohmann::json& object = config.is_null() ? kEmpty : config;
  if (!object.is_object()) throwInputError("config {}: expected an object of parameters", path);
  ConfigObject reader(object, path);
  ParamReader visitor(reader, owner);
  params.visit(visitor);
  reader.finish(owner);
  return params;
}

template <typename Params>
nlohmann::json writeParams(const Params& params) {
  ParamWriter writer;
  const_cast<Params&>(params).visit(writer);
  return writer.json();
}

// A user's value as a message shows it: at most 60 characters (a 30k-character name stays a line).
std::string shortened(const std::string& text);

}  // namespace canopy
