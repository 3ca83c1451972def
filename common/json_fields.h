#pragma once

// Structs that list their fields once, in a visit function,
//
//   template <class V> void visit(V& v) { v("hash_size", hashSize); v("levels", levels); }
//
// are written to JSON and read back by the two visitors here, so what is written and what is read
// cannot drift apart: the records of metrics.jsonl, baked-asset headers, camera paths. Reading is
// strict: a missing key, a value of the wrong type or (with finish()) a key no field names is an
// InputError naming the file (and line) and the key.
//
// Field types: bool, integers (the JSON value must be an integer in range), floating point (null
// reads as NaN: "not measured"; NaN is written as null), std::string, nlohmann::json (anything),
// std::vector / std::array of these, glm vectors (arrays of numbers), Aabb ([min xyz, max xyz]),
// nested structs with their own visit (objects, read as strictly), std::optional<T> (written as
// null when empty; the key is still required) and Absent<T> (the key may be missing).

#include <array>
#include <cmath>
#include <concepts>
#include <limits>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <nlohmann/json.hpp>

#include "common/error.h"
#include "common/tree.h"

namespace canopy {

// A field whose key may be missing (written only when it has a value).
template <typename T>
struct Absent {
  std::optional<T> value;
  bool has_value() const { return value.has_value(); }
  explicit operator bool() const { return value.has_value(); }
  const T& operator*() const { return *value; }
  T& operator*() { return *value; }
  const T* operator->() const { return &*value; }
  Absent& operator=(T v) {
    value = std::move(v);
    return *this;
  }
  bool operator==(const Absent&) const = default;
};

class JsonFieldWriter;
class JsonFieldReader;

template <typename T>
nlohmann::json writeFields(const T& value);
template <typename T>
void readFields(const nlohmann::json& json, const std::string& where, T& value);

template <typename T>
concept VisitsFields = requires(T& t, JsonFieldWriter& w) {
  t.visit(w);
};

namespace json_fields {

template <typename T>
struct IsVector : std::false_type {};
template <typename T>
struct IsVector<std::vector<T>> : std::true_type {};
template <typename T>
struct IsArray : std::false_type {};
template <typename T, size_t N>
struct IsArray<std::array<T, N>> : std::true_type {};
template <typename T>
struct IsOptional : std::false_type {};
template <typename T>
struct IsOptional<std::optional<T>> : std::true_type {};

template <typename T>
nlohmann::json toJson(const T& value);

template <typename Container>
nlohmann::json listToJson(const Container& values) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& v : values) out.push_back(toJson(v));
  return out;
}

template <typename T>
nlohmann::json toJson(const T& value) {
  if constexpr (VisitsFields<T>) {
    return writeFields(value);
  } else if constexpr (IsVector<T>::value || IsArray<T>::value) {
    return listToJson(value);
  } else if constexpr (IsOptional<T>::value) {
    return value ? toJson(*value) : nlohmann::json();
  } else if constexpr (std::is_same_v<T, glm::vec3>) {
    return {value.x, value.y, value.z};
  } else if constexpr (std::is_same_v<T, glm::ivec2>) {
    return {value.x, value.y};
  } else if constexpr (std::is_same_v<T, Aabb>) {
    return {value.min.x, value.min.y, value.min.z, value.max.x, value.max.y, value.max.z};
  } else if constexpr (std::is_floating_point_v<T>) {
    return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json();  // as dump() writes
  } else {
    return nlohmann::json(value);
  }
}

// Reads `json` as a T; `where` names the value ("results/x/metrics.jsonl:12: key 'psnr'").
template <typename T>
T fromJson(const nlohmann::json& json, const std::string& where);

[[noreturn]] inline void wrongType(const nlohmann::json& json, const std::string& where,
                                   const char* expected) {
  std::string shown = json.dump();
  if (shown.size() > 40) shown = shown.substr(0, 37) + "...";
  throwInputError("{}: expected {}, found {}", where, expected, shown);
}

template <typename T, size_t N>
std::array<float, N> numbers(const nlohmann::json& json, const std::string& where) {
  if (!json.is_array() || json.size() != N) wrongType(json, where, "an array of numbers");
  std::array<float, N> out{};
  for (size_t i = 0; i < N; ++i) out[i] = fromJson<float>(json[i], where);
  return out;
}

template <typename T>
T fromJson(const nlohmann::json& json, const std::string& where) {
  if constexpr (VisitsFields<T>) {
    T value{};
    readFields(json, where, value);
    return value;
  } else if constexpr (std::is_same_v<T, bool>) {
    if (!json.is_boolean()) wrongType(json, where, "true or false");
    return json.get<bool>();
  } else if constexpr (std::is_integral_v<T>) {
    if (!json.is_number_integer()) wrongType(json, where, "an integer");
    if constexpr (std::is_unsigned_v<T>) {
      if (json.is_number_unsigned() ? json.get<uint64_t>() > std::numeric_limits<T>::max()
                                    : json.get<int64_t>() < 0)
        wrongType(json, where, "a non-negative integer in range");
    } else {
      const int64_t v = json.is_number_unsigned() && json.get<uint64_t>() > uint64_t(INT64_MAX)
                            ? INT64_MAX
                            : json.get<int64_t>();
      if (v < int64_t(std::numeric_limits<T>::min()) || v > int64_t(std::numeric_limits<T>::max()))
        wrongType(json, where, "an integer in range");
    }
    return json.get<T>();
  } else if constexpr (std::is_floating_point_v<T>) {
    if (json.is_null()) return std::numeric_limits<T>::quiet_NaN();
    if (!json.is_number()) wrongType(json, where, "a number");
    return json.get<T>();
  } else if constexpr (std::is_same_v<T, std::string>) {
    if (!json.is_string()) wrongType(json, where, "a string");
    return json.get<std::string>();
  } else if constexpr (std::is_same_v<T, nlohmann::json>) {
    return json;
  } else if constexpr (IsOptional<T>::value) {
    if (json.is_null()) return std::nullopt;
    return fromJson<typename T::value_type>(json, where);
  } else if constexpr (IsVector<T>::value) {
    if (!json.is_array()) wrongType(json, where, "an array");
    T out;
    out.reserve(json.size());
    for (size_t i = 0; i < json.size(); ++i)
      out.push_back(
          fromJson<typename T::value_type>(json[i], where + "[" + std::to_string(i) + "]"));
    return out;
  } else if constexpr (IsArray<T>::value) {
    T out{};
    if (!json.is_array() || json.size() != out.size())
      wrongType(json, where, ("an array of " + std::to_string(out.size())).c_str());
    for (size_t i = 0; i < out.size(); ++i)
      out[i] = fromJson<typename T::value_type>(json[i], where + "[" + std::to_string(i) + "]");
    return out;
  } else if constexpr (std::is_same_v<T, glm::vec3>) {
    const auto v = numbers<float, 3>(json, where);
    return {v[0], v[1], v[2]};
  } else if constexpr (std::is_same_v<T, glm::ivec2>) {
    if (!json.is_array() || json.size() != 2) wrongType(json, where, "two integers");
    return {fromJson<int>(json[0], where), fromJson<int>(json[1], where)};
  } else if constexpr (std::is_same_v<T, Aabb>) {
    const auto v = numbers<float, 6>(json, where);
    Aabb box;
    box.min = {v[0], v[1], v[2]};
    box.max = {v[3], v[4], v[5]};
    return box;
  } else {
    static_assert(sizeof(T) == 0, "no JSON field reader for this type");
  }
}

}  // namespace json_fields

class JsonFieldWriter {
 public:
  template <typename T>
  void operator()(const char* key, const T& value) {
    mJson[key] = json_fields::toJson(value);
  }
  template <typename T>
  void operator()(const char* key, const Absent<T>& value) {
    if (value) mJson[key] = json_fields::toJson(*value);
  }
  nlohmann::json& json() { return mJson; }

 private:
  nlohmann::json mJson = nlohmann::json::object();
};

class JsonFieldReader {
 public:
  // `where` names the object in errors (a file, "file:line", a key path).
  JsonFieldReader(const nlohmann::json& json, std::string where)
      : mJson(json), mWhere(std::move(where)) {
    if (!mJson.is_object()) json_fields::wrongType(mJson, mWhere, "an object");
  }
  template <typename T>
  void operator()(const char* key, T& value) {
    if (!mJson.contains(key)) throwInputError("{}: key '{}' is missing", mWhere, key);
    mUsed.insert(key);
    value = json_fields::fromJson<T>(mJson[key], fmt::format("{}: key '{}'", mWhere, key));
  }
  template <typename T>
  void operator()(const char* key, Absent<T>& value) {
    if (!mJson.contains(key)) return;
    mUsed.insert(key);
    value = json_fields::fromJson<T>(mJson[key], fmt::format("{}: key '{}'", mWhere, key));
  }
  // Marks a key as read without a field (e.g. the "kind" a caller dispatched on).
  void skip(const char* key) { mUsed.insert(key); }
  const std::set<std::string>& used() const { return mUsed; }
  // InputError naming the first key no field read.
  void finish() const {
    for (const auto& [key, value] : mJson.items())
      if (!mUsed.contains(key)) throwInputError("{}: unknown key '{}'", mWhere, key);
  }

 private:
  const nlohmann::json& mJson;
  std::string mWhere;
  std::set<std::string> mUsed;
};

// Every field of `value` as a JSON object.
template <typename T>
nlohmann::json writeFields(const T& value) {
  JsonFieldWriter writer;
  const_cast<T&>(value).visit(writer);
  return writer.json();
}

// Fills `value` from `json`, strictly (unknown keys too are errors).
template <typename T>
void readFields(const nlohmann::json& json, const std::string& where, T& value) {
  JsonFieldReader reader(json, where);
  value.visit(reader);
  reader.finish();
}

}  // namespace canopy
