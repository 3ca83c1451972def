#include "common/config.h"

#include <fstream>
#include <sstream>

namespace canopy {

ConfigObject::ConfigObject(const nlohmann::json& json, std::string path)
    : mJson(json), mPath(std::move(path)) {
  if (!mJson.is_object())
    throwInputError("config {}: expected a JSON object", mPath.empty() ? "(top)" : mPath);
}

std::string ConfigObject::keyPath(const std::string& key) const {
  return mPath.empty() ? key : mPath + "." + key;
}

const nlohmann::json& ConfigObject::require(const std::string& key) {
  if (!mJson.contains(key)) throwInputError("config {}: required key is missing", keyPath(key));
  mUsed.insert(key);
  return mJson.at(key);
}

const nlohmann::json* ConfigObject::find(const std::string& key) {
  if (!mJson.contains(key)) return nullptr;
  mUsed.insert(key);
  return &mJson.at(key);
}

ConfigObject ConfigObject::child(const std::string& key) {
  const nlohmann::json& value = require(key);
  if (!value.is_object()) throwInputError("config {}: expected an object", keyPath(key));
  return ConfigObject(value, keyPath(key));
}

std::vector<ConfigObject> ConfigObject::children(const std::string& key) {
  const nlohmann::json& value = require(key);
  if (!value.is_array()) throwInputError("config {}: expected a list", keyPath(key));
  std::vector<ConfigObject> result;
  for (size_t i = 0; i < value.size(); ++i) {
    const std::string path = keyPath(key) + "[" + std::to_string(i) + "]";
    if (!value[i].is_object()) throwInputError("config {}: expected an object", path);
    result.emplace_back(value[i], path);
  }
  return result;
}

void ConfigObject::finish(const std::string& owner) const {
  for (const auto& [key, value] : mJson.items()) {
    if (!mUsed.contains(key)) {
      if (owner.empty()) throwInputError("config {}: unknown key", keyPath(key));
      throwInputError("config {}: unknown key for {}", keyPath(key), owner);
    }
  }
}

void ParamReader::operator()(const char* key, std::string& field,
                             const std::vector<std::string>& allowed, const char*) {
  if (!mConfig.has(key)) return;
  const auto value = mConfig.get<std::string>(key);
  if (std::find(allowed.begin(), allowed.end(), value) == allowed.end()) {
    throwInputError("{}: parameter '{}' = '{}' is not one of {}", mOwner, mConfig.keyPath(key),
                    value, nlohmann::json(allowed).dump());
  }
  field = value;
}

void ParamReader::operator()(const char* key, glm::vec3& field, float lo, float hi, const char*) {
  if (!mConfig.has(key)) return;
  const std::vector<float> v = fixedList(key, 3, lo, hi, "three numbers");
  field = {v[0], v[1], v[2]};
}

void ParamReader::operator()(const char* key, Resolution field, int lo, int hi, const char*) {
  if (!mConfig.has(key)) return;
  const std::vector<int> v = fixedList(key, 2, lo, hi, "[width, height]");
  field.width = v[0];
  field.height = v[1];
}

std::string ParamDescriber::oneOf(const std::vector<std::string>& allowed) {
  std::string out = "one of ";
  for (size_t i = 0; i < allowed.size(); ++i)
    out += (i ? ", " : "") + nlohmann::json(allowed[i]).dump();
  return out;
}

nlohmann::json readJsonFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throwInputError("{}: cannot open file", path);
  std::stringstream buffer;
  buffer << in.rdbuf();
  try {
    return nlohmann::json::parse(buffer.str());
  } catch (const nlohmann::json::parse_error& error) {
    throwInputError("{}: not valid JSON ({})", path, error.what());
  }
}

}  // namespace canopy
