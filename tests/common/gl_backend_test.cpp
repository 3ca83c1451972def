// Every headless backend renders a known triangle in the same binary (the libGL/libOSMesa trap
// makes draws silent no-ops in a badly linked binary, so pixels are checked, not return codes).
#include <gtest/gtest.h>

#include <vector>

#include "common/error.h"
#include "common/gl/api.h"
#include "common/gl/context.h"
#include "common/gl/device.h"

namespace canopy::gl {
namespace {

constexpr const char* kVertex = R"(#version 430 core
const vec2 kCorners[3] = vec2[](vec2(-0.5, -0.5), vec2(0.5, -0.5), vec2(0.0, 0.5));
void main() { gl_Position = vec4(kCorners[gl_VertexID], 0.0, 1.0); }
)";
constexpr const char* kFragment = R"(#version 430 core
out vec4 color;
void main() { color = vec4(1.0, 0.0, 0.0, 1.0); }
)";

// Renders the triangle into a 64x64 RGBA8 target and returns the pixels (bottom-up rows).
std::vector<uint8_t> renderTriangle(Context& context) {
  context.makeCurrent();
  Ledger ledger;
  Device device(ledger);
  const Api& g = api();
  RenderTarget target = device.createRenderTarget(64, 64, GL_RGBA8);
  Program program = device.createProgram({{"test.vert", kVertex}, {"test.frag", kFragment}});
  GLuint vao = 0;
  g.GenVertexArrays(1, &vao);
  g.BindFramebuffer(GL_FRAMEBUFFER, target.framebuffer.id());
  g.Viewport(0, 0, 64, 64);
  g.ClearColor(0.0f, 0.0f, 1.0f, 1.0f);
  g.Clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  program.use();
  g.BindVertexArray(vao);
  g.DrawArrays(GL_TRIANGLES, 0, 3);
  std::vector<uint8_t> pixels(64 * 64 * 4);
  g.ReadPixels(0, 0, 64, 64, GL_RGBA, GL_UNSIGNED_BYTE, pixels.data());
  g.BindFramebuffer(GL_FRAMEBUFFER, 0);
  g.DeleteVertexArrays(1, &vao);
  EXPECT_EQ(g.GetError(), static_cast<GLenum>(GL_NO_ERROR));
  return pixels;
}

void expectTriangle(const std::vector<uint8_t>& pixels) {
  auto pixel = [&](int x, int y) { return &pixels[(y * 64 + x) * 4]; };
  // Centre of the triangle (y grows upwards in GL read-back): red.
  EXPECT_EQ(pixel(32, 28)[0], 255);
  EXPECT_EQ(pixel(32, 28)[2], 0);
  // Corners of the target are outside the triangle: the blue clear colour.
  for (auto [x, y] : {std::pair{2, 2}, std::pair{61, 61}, std::pair{2, 61}, std::pair{61, 2}}) {
    EXPECT_EQ(pixel(x, y)[0], 0) << x << "," << y;
    EXPECT_EQ(pixel(x, y)[2], 255) << x << "," << y;
  }
  // Area: the triangle covers 1/8 of the target (base 32 px, height 32 px): 512 pixels ± edge.
  int red = 0;
  for (int i = 0; i < 64 * 64; ++i) red += pixels[i * 4] == 255 ? 1 : 0;
  EXPECT_NEAR(red, 512, 40);
}

TEST(GlBackend, OsMesaRendersKnownTriangle) {
  auto context = createContext({Backend::kOsMesa});
  EXPECT_FALSE(context->renderer().empty());
  expectTriangle(renderTriangle(*context));
}

TEST(GlBackend, EglRendersKnownTriangle) {
  auto context = createContext({Backend::kEgl});
  EXPECT_FALSE(context->renderer().empty());
  expectTriangle(renderTriangle(*context));
}

TEST(GlBackend, OsMesaAndEglCoexistInOneProcess) {
  auto osmesa = createContext({Backend::kOsMesa});
  auto egl = createContext({Backend::kEgl});
  expectTriangle(renderTriangle(*osmesa));
  expectTriangle(renderTriangle(*egl));
  expectTriangle(renderTriangle(*osmesa));
}

// Runs where a display exists; ctest runs it under xvfb-run (tests/CMakeLists.txt).
TEST(GlBackend, GlfwRendersKnownTriangle) {
  const char* display = std::getenv("DISPLAY");
  if (display == nullptr || *display == '\0')
    GTEST_SKIP() << "no display (ctest runs this under xvfb-run)";
  auto context = createContext({Backend::kGlfw});
  EXPECT_FALSE(context->renderer().empty());
  expectTriangle(renderTriangle(*context));
}

TEST(GlBackend, GlfwWithoutDisplayIsAClearInputError) {
  const char* display = std::getenv("DISPLAY");
  if (display != nullptr && *display != '\0') GTEST_SKIP() << "a display is present";
  EXPECT_THROW(createContext({Backend::kGlfw}), InputError);
}

TEST(GlBackend, UnknownBackendNameIsAnInputError) {
  EXPECT_THROW(parseBackend("vulkan"), InputError);
  EXPECT_EQ(parseBackend("egl"), Backend::kEgl);
}

}  // namespace
}  // namespace canopy::gl
