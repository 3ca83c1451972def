#include "methods/method.h"

#include <algorithm>
#include <fstream>

#include <fmt/format.h>

#include "common/atomic_file.h"
#include "common/config.h"

namespace canopy {

namespace {

// The part of the header every asset has.
struct AssetDescription {
  std::string method;
  nlohmann::json params, report;
  template <class V>
  void visit(V& v) {
    v("method", method);
    v("params", params);
    v("report", report);
  }
};

// The report without its timings (keys "seconds" or ending in "_s", at any depth): how long a
// bake took is a
// fact of that process, not of the asset, and the same config must write byte-identical assets
// (their size is the bake record's disk_bytes).
nlohmann::json withoutTimings(const nlohmann::json& value) {
  if (value.is_array()) {
    nlohmann::json out = nlohmann::json::array();
    for (const auto& item : value) out.push_back(withoutTimings(item));
    return out;
  }
  if (!value.is_object()) return value;
  nlohmann::json out = nlohmann::json::object();
  for (const auto& [key, item] : value.items()) {
    if (key == "seconds" || (key.size() > 2 && key.ends_with("_s"))) continue;
    out[key] = withoutTimings(item);
  }
  return out;
}

}  // namespace

void AssetFolder::describe(const std::string& method, const nlohmann::json& params,
                           const nlohmann::json& report) {
  writeFields(AssetDescription{method, params, withoutTimings(report)});
}

void AssetFolder::writeHeader() {
  writeTextAtomically(mFolder / "asset.json", mHeader.dump(2));
}

nlohmann::json AssetFolder::readHeaderOf(const std::string& method) {
  mHeader = readJsonFile(headerPath());
  mReadKeys.clear();
  if (!mHeader.is_object()) throwInputError("{}: not an asset header (an object)", headerPath());
  const std::string named =
      mHeader.contains("method") && mHeader["method"].is_string() ? mHeader["method"] : "";
  if (named != method) {
    throwInputError("{}: not a {} asset (asset.json names '{}')", mFolder.string(), method, named);
  }
  AssetDescription description;
  readFields(description);
  return description.report;
}

void AssetFolder::finishReading() const {
  for (const auto& [key, value] : mHeader.items())
    if (!mReadKeys.contains(key)) throwInputError("{}: unknown key '{}'", headerPath(), key);
}

void AssetFolder::writeBlob(const std::string& name, const void* data, size_t bytes) {
  writeTextAtomically(mFolder / name, std::string_view(static_cast<const char*>(data), bytes));
}

std::vector<uint8_t> AssetFolder::readBlob(const std::string& name) const {
  const auto path = mFolder / name;
  std::ifstream in(path, std::ios::binary);
  if (!in) throwInputError("{}: missing asset blob", path.string());
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void AssetFolder::writeImage(const std::string& name, const ImageRgba8& image) {
  writePng(mFolder / name, image);
}

ImageRgba8 AssetFolder::readImage(const std::string& name) const {
  return canopy::readImage(mFolder / name);
}

void AssetFolder::writeImages(const std::string& pattern, const std::vector<ImageRgba8>& images) {
  for (size_t i = 0; i < images.size(); ++i)
    writeImage(fmt::format(fmt::runtime(pattern), i), images[i]);
}

std::vector<ImageRgba8> AssetFolder::readImages(const std::string& pattern, size_t count) const {
  std::vector<ImageRgba8> images;
  for (size_t i = 0; i < count; ++i)
    images.push_back(readImage(fmt::format(fmt::runtime(pattern), i)));
  return images;
}

uint64_t AssetFolder::sizeOnDisk() const {
  uint64_t total = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(mFolder)) {
    if (entry.is_regular_file()) total += entry.file_size();
  }
  return total;
}

std::string parameterTableMarkdown(const MethodInfo& info) {
  std::string out = "| key | type | default | range | what |\n|---|---|---|---|---|\n";
  for (const ParamDoc& p : info.parameters)
    out += fmt::format("| `{}` | {} | `{}` | {} | {} |\n", p.key, p.type, p.defaultValue, p.range,
                       p.doc);
  return out;
}

std::string parameterTableText(const MethodInfo& info) {
  size_t keyWidth = 3, typeWidth = 4, defaultWidth = 7, rangeWidth = 5;
  for (const ParamDoc& p : info.parameters) {
    keyWidth = std::max(keyWidth, p.key.size());
    typeWidth = std::max(typeWidth, p.type.size());
    defaultWidth = std::max(defaultWidth, p.defaultValue.size());
    rangeWidth = std::max(rangeWidth, p.range.size());
  }
  const auto line = [&](const std::string& key, const std::string& type, const std::string& value,
                        const std::string& range, const std::string& doc) {
    return fmt::format("  {:<{}}  {:<{}}  {:<{}}  {:<{}}  {}\n", key, keyWidth, type, typeWidth,
                       value, defaultWidth, range, rangeWidth, doc);
  };
  std::string out = line("key", "type", "default", "range", "what");
  for (const ParamDoc& p : info.parameters)
    out += line(p.key, p.type, p.defaultValue, p.range, p.doc);
  return out;
}

void bindInstanceMatrices(GLuint instanceBuffer, GLuint location, GLint firstInstance) {
  const gl::Api& g = gl::api();
  g.BindBuffer(GL_ARRAY_BUFFER, instanceBuffer);
  for (GLuint column = 0; column < 4; ++column) {
    g.EnableVertexAttribArray(location + column);
    g.VertexAttribPointer(
        location + column, 4, GL_FLOAT, GL_FALSE, sizeof(float) * 16,
        reinterpret_cast<const void*>(sizeof(float) * (16 * size_t(firstInstance) + 4 * column)));
    g.VertexAttribDivisor(location + column, 1);
  }
  g.BindBuffer(GL_ARRAY_BUFFER, 0);
}

}  // namespace canopy
