// Parameters document themselves: --list-methods and docs/METHODS.md are generated from each
// method's visit(), and the docs fail this test when they drift (tools/update-method-docs.sh
// rewrites them).
#include <gtest/gtest.h>

#include "methods/method.h"
#include "test_support.h"

namespace canopy {
namespace {

TEST(ParameterDocs, EveryParameterHasATypeADefaultAndADoc) {
  for (const std::string& name : builtinMethods().names()) {
    const MethodInfo& info = builtinMethods().find(name);
    EXPECT_FALSE(info.description.empty()) << name;
    ASSERT_FALSE(info.parameters.empty()) << name;
    for (const ParamDoc& p : info.parameters) {
      EXPECT_FALSE(p.type.empty()) << name << "." << p.key;
      EXPECT_FALSE(p.defaultValue.empty()) << name << "." << p.key;
      EXPECT_GE(p.doc.size(), 10u) << name << "." << p.key << " needs a doc string";
    }
    // The documented defaults are the effective parameters of a default-made method.
    const nlohmann::json effective =
        info.create(nlohmann::json::object(), "test")->effectiveParams();
    EXPECT_EQ(effective.size(), info.parameters.size()) << name;
    for (const ParamDoc& p : info.parameters) EXPECT_TRUE(effective.contains(p.key)) << p.key;
  }
}

TEST(ParameterDocs, MethodsMdHoldsTheGeneratedTables) {
  const std::string docs =
      test::readText(std::filesystem::path(CANOPY_SOURCE_DIR) / "docs" / "METHODS.md");
  for (const std::string& name : builtinMethods().names()) {
    const std::string block = "<!-- parameters:" + name + " -->\n" +
                              parameterTableMarkdown(builtinMethods().find(name)) +
                              "<!-- /parameters -->";
    EXPECT_NE(docs.find(block), std::string::npos)
        << "docs/METHODS.md: the parameter table of " << name
        << " differs from the code; run tools/update-method-docs.sh. Expected:\n"
        << block;
  }
}

TEST(ParameterDocs, ListMethodsPrintsDescriptionsAndParameters) {
  const test::TempDir dir;
  const std::string out = (dir / "list.txt").string();
  ASSERT_EQ(std::system((std::string(CANOPY_BENCH_EXE) + " --list-methods > " + out).c_str()), 0);
  const std::string text = test::readText(out);
  for (const std::string& name : builtinMethods().names()) {
    const MethodInfo& info = builtinMethods().find(name);
    EXPECT_NE(text.find(name + ": " + info.description), std::string::npos) << name;
    for (const ParamDoc& p : info.parameters) EXPECT_NE(text.find(p.doc), std::string::npos);
  }
}

}  // namespace
}  // namespace canopy
