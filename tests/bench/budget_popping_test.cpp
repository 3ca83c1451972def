// The equal-memory bisection on synthetic memory curves, and the temporal (popping) metric on a
// synthetic sequence with a known pop.
#include <gtest/gtest.h>

#include <cmath>

#include <glm/geometric.hpp>

#include "bench/budget.h"
#include "bench/popping.h"
#include "bench/report.h"

namespace canopy {
namespace {

TEST(Budget, BisectionHitsASyntheticMemoryCurveWithinFivePercent) {
  // Memory of a texture-resolution knob: 0.3 MB fixed + texels², like most methods here.
  const MemoryKnob knob{"texture_size", 8, 512, true, true};
  const auto memory = [](double size) { return 0.3 + size * size * 4.0 * 6.0 * 40.0 / 1e6; };
  for (double target : {1.0, 5.0, 20.0, 100.0}) {
    const KnobSearch s = bisectToTarget(knob, target, 0.05, memory, 16);
    EXPECT_TRUE(s.reached) << target;
    EXPECT_NEAR(memory(s.value), target, 0.05 * target) << target;
    EXPECT_EQ(s.value, std::round(s.value)) << "integer knob";
    EXPECT_LE(s.steps, 16);
    // The search grows from the cheap end: nothing far beyond the answer is ever baked.
    for (const auto& [value, measured] : s.trace) EXPECT_LE(value, 2.0 * s.value + 1.0) << target;
  }
  // Out of range: the nearer end, not reached.
  const KnobSearch tooSmall = bisectToTarget(knob, 0.01, 0.05, memory, 16);
  EXPECT_FALSE(tooSmall.reached);
  EXPECT_EQ(tooSmall.value, 8.0);
  const KnobSearch tooBig = bisectToTarget(knob, 1e6, 0.05, memory, 16);
  EXPECT_FALSE(tooBig.reached);
  EXPECT_EQ(tooBig.value, 512.0);
}

TEST(Budget, ShrinkingKnobsAndContinuousValuesBisectToo) {
  // A cell size: memory falls as the value grows.
  const MemoryKnob knob{"cell_size", 0.25, 8, false, false};
  const auto memory = [](double cell) { return 50.0 / (cell * cell); };
  const KnobSearch s = bisectToTarget(knob, 10.0, 0.05, memory, 20);
  EXPECT_TRUE(s.reached);
  EXPECT_NEAR(memory(s.value), 10.0, 0.5);
}

TEST(Budget, LeastMemoryReachingAPsnrTarget) {
  const MemoryKnob knob{"density", 2, 512, false, true};
  const auto psnr = [](double density) { return 10.0 + 3.0 * std::log2(density); };  // monotone
  const KnobSearch s = leastMemoryReaching(knob, 25.0, psnr, 30);
  ASSERT_TRUE(s.reached);
  EXPECT_GE(psnr(s.value), 25.0);
  EXPECT_LT(psnr(s.value * 0.99), 25.0 + 1e-3) << "close to the least density that reaches it";
  EXPECT_FALSE(leastMemoryReaching(knob, 99.0, psnr, 30).reached);
}

ImageRgba8 flat(int size, uint8_t value) {
  ImageRgba8 image(size, size);
  for (size_t i = 0; i < image.pixels.size(); i += 4) {
    image.pixels[i] = image.pixels[i + 1] = image.pixels[i + 2] = value;
    image.pixels[i + 3] = 255;
  }
  return image;
}

TEST(Popping, TemporalMetricFindsAKnownPopAndIgnoresTheReferencesOwnChange) {
  // The reference brightens smoothly by 2 per frame; the method follows it but jumps by 30 at
  // frame 5 (a level switch) and stays offset.
  std::vector<ImageRgba8> reference, method;
  std::vector<uint64_t> signatures;
  for (int i = 0; i < 10; ++i) {
    reference.push_back(flat(8, uint8_t(100 + 2 * i)));
    method.push_back(flat(8, uint8_t(100 + 2 * i + (i >= 5 ? 30 : 0))));
    signatures.push_back(i >= 5 ? 2 : 1);
  }
  const TemporalMetrics m = temporalMetrics(method, reference, signatures);
  EXPECT_NEAR(m.peakExcess, 30.0, 1e-9) << "|32 − 2| at the pop";
  EXPECT_NEAR(m.excess[5], 30.0, 1e-9);
  EXPECT_NEAR(m.excess[3], 0.0, 1e-9) << "smooth change explained by the reference";
  EXPECT_NEAR(m.meanExcess, 30.0 / 9.0, 1e-9);
  EXPECT_EQ(m.switches, 1);
  EXPECT_TRUE(m.lodSwitch[5]);
  EXPECT_FALSE(m.lodSwitch[4]);
  EXPECT_NEAR(m.psnr[0], 100.0, 1e-9) << "identical frames hit the cap";
  EXPECT_NEAR(m.psnr[6], 20.0 * std::log10(255.0 / 30.0), 1e-6);
  EXPECT_THROW(temporalMetrics(method, reference, {1, 2}), std::invalid_argument);
}

TEST(Popping, DollyPathGoesFromNearToFarAndOrbitStaysAtItsDistance) {
  Aabb bounds;
  bounds.min = glm::vec3(-1.0f);
  bounds.max = glm::vec3(1.0f);
  PoppingSettings settings;
  settings.frames = 5;
  settings.nearDistance = 2.0f;
  settings.farDistance = 32.0f;
  const auto dolly = dollyPath(bounds, settings, 40.0f);
  ASSERT_EQ(dolly.size(), 5u);
  EXPECT_FLOAT_EQ(dolly.front().distance, 2.0f);
  EXPECT_NEAR(dolly.back().distance, 32.0f, 1e-4f);
  EXPECT_NEAR(dolly[2].distance, 8.0f, 1e-4f) << "log-spaced";
  for (const auto& frame : orbitPath(bounds, settings, 40.0f))
    EXPECT_NEAR(glm::length(frame.camera.position), settings.orbitDistance * std::sqrt(3.0f),
                1e-3f);
}

TEST(Popping, CsvHasOneLinePerFrame) {
  SummaryRow row;
  row.tree = "t";
  row.variant = "m";
  PoppingRecord dolly;
  dolly.path = "dolly";
  dolly.distance = {1.5, 3.0};
  dolly.psnrFrame = {20.0, 21.0};
  dolly.change = {0.0, 4.0};
  dolly.referenceChange = {0.0, 1.0};
  dolly.temporalExcess = {0.0, 3.0};
  dolly.lodSwitch = {false, true};
  row.popping.push_back(dolly);
  const std::string csv = formatPoppingCsv({row});
  EXPECT_EQ(csv,
            "tree,variant,path,frame,distance,psnr,change,reference_change,temporal_excess,"
            "lod_switch\nt,m,dolly,0,1.5,20,0,0,0,0\nt,m,dolly,1,3,21,4,1,3,1\n");
  EXPECT_EQ(formatPoppingCsv({SummaryRow{}}), "");
}

}  // namespace
}  // namespace canopy
