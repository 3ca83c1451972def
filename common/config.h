#pragma once

#include <optional>
#include <set>
#include <string>
#include <vector>

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

// Reads a JSON file; InputError naming the file when it is missing or not valid JSON.
nlohmann::json readJsonFile(const std::string& path);

// Typed parameter structs describe their fields once, through a visitor:
//   template <class V> void visit(V& v) { v("hash_resolution", hashResolution, 1, 4096); }
// ParamReader fills them from a config (range-checked, unknown keys rejected) and ParamWriter
// writes them back as the effective parameters, so reading and reporting cannot drift apart.
class ParamReader {
 public:
  ParamReader(ConfigObject& config, std::string owner)
      : mConfig(config), mOwner(std::move(owner)) {}

  template <typename T>
  void operator()(const char* key, T& field, T lo, T hi) {
    if (!mConfig.has(key)) return;
    const T value = mConfig.get<T>(key);
    if (!(value >= lo && value <= hi)) {
      throwInputError("{}: parameter '{}' = {} is out of range [{}, {}]", mOwner,
                      mConfig.keyPath(key), value, lo, hi);
    }
    field = value;
  }
  void operator()(const char* key, bool& field) {
    if (mConfig.has(key)) field = mConfig.get<bool>(key);
  }
  void operator()(const char* key, std::string& field, const std::vector<std::string>& allowed) {
    if (!mConfig.has(key)) return;
    const auto value = mConfig.get<std::string>(key);
    if (std::find(allowed.begin(), allowed.end(), value) == allowed.end()) {
      throwInputError("{}: parameter '{}' = '{}' is not one of {}", mOwner, mConfig.keyPath(key),
                      value, nlohmann::json(allowed).dump());
    }
    field = value;
  }

 private:
  ConfigObject& mConfig;
  std::string mOwner;
};

class ParamWriter {
 public:
  template <typename T>
  void operator()(const char* key, const T& field, T, T) {
    mJson[key] = field;
  }
  void operator()(const char* key, const bool& field) { mJson[key] = field; }
  void operator()(const char* key, const std::string& field, const std::vector<std::string>&) {
    mJson[key] = field;
  }
  nlohmann::json& json() { return mJson; }

 private:
  nlohmann::json mJson = nlohmann::json::object();
};

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

}  // namespace canopy
