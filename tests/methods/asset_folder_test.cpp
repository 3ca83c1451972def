// AssetFolder's blob helpers on the edge cases a corrupt or minimal asset produces.
#include <gtest/gtest.h>

#include "methods/method.h"
#include "test_support.h"

namespace canopy {
namespace {

TEST(AssetFolder, EmptyBlobsReadAsEmptyAndTruncatedOnesAreNamed) {
  test::TempDir dir;
  AssetFolder asset(dir.path());
  // Found by the asset_loader fuzz target: an empty blob made readBlobAs memcpy from null.
  asset.writeBlob("empty.bin", std::vector<uint32_t>{});
  EXPECT_TRUE(asset.readBlobAs<uint32_t>("empty.bin").empty());
  asset.writeBlob("values.bin", std::vector<uint32_t>{1, 2, 3});
  EXPECT_EQ(asset.readBlobAs<uint32_t>("values.bin"), (std::vector<uint32_t>{1, 2, 3}));
  test::writeText(dir / "cut.bin", "abc");
  try {
    asset.readBlobAs<uint32_t>("cut.bin");
    FAIL() << "a blob of 3 bytes read as uint32";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("cut.bin: truncated blob"), std::string::npos)
        << error.what();
  }
  try {
    asset.readBlobAs<uint32_t>("absent.bin");
    FAIL() << "a missing blob read";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("absent.bin"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace canopy
