#include "methods/method.h"

#include <fstream>

#include "common/atomic_file.h"
#include "common/config.h"

namespace canopy {

void AssetFolder::writeBlob(const std::string& name, const void* data, size_t bytes) {
  writeTextAtomically(mFolder / name, std::string_view(static_cast<const char*>(data), bytes));
}

void AssetFolder::writeImage(const std::string& name, const ImageRgba8& image) {
  writePng(mFolder / name, image);
}

void AssetFolder::writeHeader() {
  writeTextAtomically(mFolder / "asset.json", mHeader.dump(2));
}

void AssetFolder::readHeader() {
  mHeader = readJsonFile((mFolder / "asset.json").string());
}

void AssetFolder::describe(const std::string& method, const nlohmann::json& params,
                           const nlohmann::json& report) {
  mHeader["method"] = method;
  mHeader["params"] = params;
  mHeader["report"] = report;
}

void AssetFolder::readHeaderOf(const std::string& method) {
  readHeader();
  if (mHeader.value("method", "") != method) {
    throwInputError("{}: not a {} asset (asset.json names '{}')", mFolder.string(), method,
                    mHeader.value("method", ""));
  }
}

std::vector<uint8_t> AssetFolder::readBlob(const std::string& name) const {
  const auto path = mFolder / name;
  std::ifstream in(path, std::ios::binary);
  if (!in) throwInputError("{}: missing asset blob", path.string());
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

ImageRgba8 AssetFolder::readImage(const std::string& name) const {
  return canopy::readImage(mFolder / name);
}

uint64_t AssetFolder::sizeOnDisk() const {
  uint64_t total = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(mFolder)) {
    if (entry.is_regular_file()) total += entry.file_size();
  }
  return total;
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
