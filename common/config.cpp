#include "common/config.h"

#include <cctype>
#include <filesystem>
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

std::string shortened(const std::string& text) {
  return text.size() <= 60 ? text : text.substr(0, 57) + "...";
}

namespace {

// Tracks nesting and the keys seen in every open object while the parser runs.
class StrictJsonCallback {
 public:
  explicit StrictJsonCallback(const std::string& source) : mSource(source) {}

  bool operator()(int, nlohmann::json::parse_event_t event, nlohmann::json& parsed) {
    using Event = nlohmann::json::parse_event_t;
    switch (event) {
      case Event::object_start:
      case Event::array_start:
        if (++mDepth > kMaxJsonDepth)
          throwInputError("{}: not valid JSON (nested deeper than {} levels)", mSource,
                          kMaxJsonDepth);
        mKeys.emplace_back();
        break;
      case Event::object_end:
      case Event::array_end:
        --mDepth;
        mKeys.pop_back();
        break;
      case Event::key:
        if (!mKeys.back().insert(parsed.get<std::string>()).second)
          throwInputError("{}: not valid JSON (key \"{}\" appears twice in one object)", mSource,
                          shortened(parsed.get<std::string>()));
        break;
      case Event::value:
        break;
    }
    return true;
  }

 private:
  const std::string& mSource;
  int mDepth = 0;
  std::vector<std::set<std::string>> mKeys;  // per open object or array (arrays stay empty)
};

// nlohmann's what() starts with "[json.exception.parse_error.101] "; the reader wants the rest.
std::string withoutExceptionTag(const char* message) {
  std::string text = message;
  if (text.rfind("[json.exception.", 0) == 0) {
    const size_t end = text.find("] ");
    if (end != std::string::npos) text = text.substr(end + 2);
  }
  return text;
}

}  // namespace

nlohmann::json parseJson(const std::string& text, const std::string& source) {
  try {
    return nlohmann::json::parse(text, StrictJsonCallback(source));
  } catch (const nlohmann::json::exception& error) {
    throwInputError("{}: not valid JSON ({})", source, withoutExceptionTag(error.what()));
  }
}

std::string readTextFile(const std::string& path) {
  std::error_code ignored;  // a path too long to test is reported by the open below
  if (std::filesystem::is_directory(path, ignored))
    throwInputError("{}: is a folder, not a file", path);
  std::ifstream in(path, std::ios::binary);
  if (!in) throwInputError("{}: cannot open file", path);
  std::stringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) throwInputError("{}: cannot read file", path);
  return buffer.str();
}

nlohmann::json readJsonFile(const std::string& path) {
  return parseJson(readTextFile(path), path);
}

const std::string& checkPathComponent(const std::string& value, const std::string& what) {
  const bool allowed = std::all_of(value.begin(), value.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.' || c == '-';
  });
  if (!allowed || value.empty() || value.size() > 100 || value == "." || value == "..") {
    throwInputError(
        "{}: '{}' must be 1 to 100 letters, digits, '_', '.' or '-', and not '.' or '..'", what,
        shortened(value));
  }
  return value;
}

}  // namespace canopy
