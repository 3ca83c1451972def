#include "common/gl/ledger.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "common/gl/api.h"
#include "common/gl/device.h"
#include "test_support.h"

namespace canopy::gl {
namespace {

TEST(Ledger, TotalsByOwnerAndCategory) {
  Ledger ledger;
  const auto a = ledger.record("m", MemoryCategory::kTexture, 1000, "t");
  ledger.record("m", MemoryCategory::kGeometry, 300, "g");
  ledger.record("other", MemoryCategory::kTexture, 7, "x");
  EXPECT_EQ(ledger.totals("m").texture, 1000u);
  EXPECT_EQ(ledger.totals("m").geometry, 300u);
  EXPECT_EQ(ledger.totals("m").total(), 1300u);
  EXPECT_EQ(ledger.totalsAll().total(), 1307u);
  ledger.release(a);
  EXPECT_EQ(ledger.totals("m").total(), 300u);
}

TEST(Ledger, TextureBytesIncludeMipsAndCompression) {
  EXPECT_EQ(textureLevelBytes(GL_RGBA8, 256, 256, 1), 262144u);
  EXPECT_EQ(textureLevelBytes(GL_RGBA16F, 10, 10, 2), 1600u);
  EXPECT_EQ(fullMipLevelCount(256, 256), 9);
  EXPECT_EQ(fullMipLevelCount(256, 64), 9);
  EXPECT_EQ(textureLevelBytes(0x83F1 /* DXT1 RGBA */, 256, 256, 1),
            32768u);                                              // 8 bytes per 4×4 block
  EXPECT_EQ(textureLevelBytes(0x83F3 /* DXT5 */, 6, 6, 1), 64u);  // 2×2 blocks of 16 bytes
}

TEST(Ledger, DeviceRecordsRealAllocationsAndReleasesThem) {
  auto context = test::makeTestContext();
  Ledger ledger;
  Device device(ledger);
  {
    Device::OwnerScope owner(device, "method");
    std::vector<float> data(250, 1.0f);
    Buffer buffer =
        device.createBuffer(MemoryCategory::kGeometry, GL_ARRAY_BUFFER, data, "vertices");
    Texture texture = device.createTexture(
        {GL_TEXTURE_2D, 64, 32, 1, GL_RGBA8, true, MemoryCategory::kTexture, "t"});
    Texture array = device.createTexture(
        {GL_TEXTURE_2D_ARRAY, 16, 16, 3, GL_R32F, false, MemoryCategory::kOther, "a"});
    // 64×32 RGBA8 with the full chain: 64·32 + 32·16 + 16·8 + 8·4 + 4·2 + 2·1 + 1·1 texels × 4
    // bytes.
    const uint64_t mipChain = (2048 + 512 + 128 + 32 + 8 + 2 + 1) * 4;
    EXPECT_EQ(texture.levels, 7);
    EXPECT_EQ(ledger.totals("method").geometry, 1000u);
    EXPECT_EQ(ledger.totals("method").texture, mipChain);
    EXPECT_EQ(ledger.totals("method").other, 16u * 16u * 3u * 4u);
    EXPECT_EQ(ledger.totals("nobody").total(), 0u);
    EXPECT_EQ(api().GetError(), static_cast<GLenum>(GL_NO_ERROR));
  }
  EXPECT_EQ(ledger.liveEntries(), 0u);
}

TEST(Shaders, CompileErrorsNameTheFileAndLine) {
  auto context = test::makeTestContext();
  Ledger ledger;
  Device device(ledger);
  const char* broken =
      "#version 430 core\nout vec4 c;\nvoid main() {\n  c = vec4(undefinedThing);\n}\n";
  try {
    device.createProgram({{"methods/x/broken.frag", broken}});
    FAIL() << "expected a compile error";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("methods/x/broken.frag:4"), std::string::npos)
        << error.what();
  }
}

TEST(Shaders, IncludesExpandAndErrorsNameTheRightFileAndLine) {
  auto context = test::makeTestContext();
  Ledger ledger;
  Device device(ledger);
  // After the include, the including file's own line numbers still hold.
  const char* broken =
      "#version 430 core\n#include \"methods/common/lighting.glsl\"\nout vec4 c;\n"
      "void main() {\n  c = vec4(lighting(vec3(0, 1, 0), 1.0) * undefinedThing);\n}\n";
  try {
    device.createProgram({{"methods/x/includes.frag", broken}});
    FAIL() << "expected a compile error";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("methods/x/includes.frag:5"), std::string::npos)
        << error.what();
  }
  // The included code itself compiles and links into a working program.
  const char* fine =
      "#version 430 core\n#include \"methods/common/lighting.glsl\"\nout vec4 c;\n"
      "void main() { c = vec4(lighting(vec3(0, 1, 0), 1.0)); }\n";
  const char* vertex =
      "#version 430 core\nout vec3 vWorldPosition;\n"
      "void main() { vWorldPosition = vec3(0); gl_Position = vec4(0, 0, 0, 1); }\n";
  EXPECT_NO_THROW(device.createProgram(
      {{"methods/x/includes.vert", vertex}, {"methods/x/includes_fine.frag", fine}}));
}

TEST(Shaders, EveryShaderFileIsEmbeddedVerbatim) {
  namespace fs = std::filesystem;
  int found = 0;
  for (const char* folder : {"common", "methods", "viewer"}) {
    for (const auto& entry :
         fs::recursive_directory_iterator(fs::path(CANOPY_SOURCE_DIR) / folder)) {
      const std::string extension = entry.path().extension().string();
      if (extension != ".vert" && extension != ".frag" && extension != ".glsl") continue;
      const std::string relative = fs::relative(entry.path(), CANOPY_SOURCE_DIR).string();
      std::ifstream in(entry.path(), std::ios::binary);
      const std::string text((std::istreambuf_iterator<char>(in)),
                             std::istreambuf_iterator<char>());
      EXPECT_EQ(embeddedShader(relative).text, text) << relative;
      ++found;
    }
  }
  EXPECT_GE(found, 4);
  EXPECT_THROW(embeddedShader("methods/none.frag"), std::logic_error);
}

}  // namespace
}  // namespace canopy::gl
