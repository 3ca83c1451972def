#include "methods/octahedral/octahedral_capture.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "methods/common/leaf_capture.h"
#include "methods/common/tree_rays.h"

namespace canopy {
namespace {

// One ray's view of the tree: linear colour and the normal towards the camera, or nothing.
struct RaySample {
  bool hit = false;
  float distance = 0.0f;  // along the ray from its origin
  glm::vec3 color{0.0f};
  glm::vec3 normal{0.0f};
};

glm::vec3 bilinearLinear(const ImageRgba8& image, glm::vec2 uv) {
  const float x = uv.x * image.width - 0.5f, y = uv.y * image.height - 0.5f;
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  const float fx = x - x0, fy = y - y0;
  auto at = [&](int px, int py) {
    // Wood textures repeat (uvs beyond [0, 1] wrap, as the reference samples them).
    px = ((px % image.width) + image.width) % image.width;
    py = ((py % image.height) + image.height) % image.height;
    const uint8_t* p = image.at(px, py);
    return glm::vec3(srgbToLinear(p[0] / 255.0f), srgbToLinear(p[1] / 255.0f),
                     srgbToLinear(p[2] / 255.0f));
  };
  return glm::mix(glm::mix(at(x0, y0), at(x0 + 1, y0), fx),
                  glm::mix(at(x0, y0 + 1), at(x0 + 1, y0 + 1), fx), fy);
}

class FrameTracer {
 public:
  FrameTracer(const Tree& tree, const OctahedralCaptureSettings& settings)
      : mTree(tree), mSettings(settings), mScene(tree), mSampler(tree) {}

  // The first surface along `direction` from `origin`; `sampleStep` is the world spacing of rays
  // (the leaf images' mip level follows it).
  RaySample trace(glm::vec3 origin, glm::vec3 direction, float tfar, float sampleStep) const {
    TreeRayContext context;
    rtcInitIntersectContext(&context.context);
    context.tree = &mTree;
    RTCRayHit rayHit{};
    rayHit.ray.org_x = origin.x;
    rayHit.ray.org_y = origin.y;
    rayHit.ray.org_z = origin.z;
    rayHit.ray.dir_x = direction.x;
    rayHit.ray.dir_y = direction.y;
    rayHit.ray.dir_z = direction.z;
    rayHit.ray.tnear = 0.0f;
    rayHit.ray.tfar = tfar;
    rayHit.ray.mask = 0xffffffffu;
    rayHit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(mScene.scene(), &context.context, &rayHit);
    RaySample sample;
    if (rayHit.hit.geomID == RTC_INVALID_GEOMETRY_ID) return sample;
    const unsigned primitive = rayHit.hit.primID;
    const float u = rayHit.hit.u, v = rayHit.hit.v;
    if (rayHit.hit.geomID == mScene.leafGeometry()) {
      const Leaf& leaf = mTree.leaves[primitive / 2];
      const float facing = glm::dot(direction, leaf.normal);
      const bool back = facing > 0.0f;
      const glm::vec2 uv =
          leaf.uvMin + leafUnitCoordinates(primitive, u, v) * (leaf.uvMax - leaf.uvMin);
      const glm::ivec2 size = mSampler.size(leaf.texture);
      const float footprint =
          sampleStep / std::max(std::abs(facing), 0.05f) *
          std::max(size.x * std::abs(leaf.uvMax.x - leaf.uvMin.x) / (2.0f * leaf.halfExtents.x),
                   size.y * std::abs(leaf.uvMax.y - leaf.uvMin.y) / (2.0f * leaf.halfExtents.y));
      sample.color = glm::vec3(mSampler.sample(leaf.texture, back, uv, footprint));
      sample.normal = back ? -leaf.normal : leaf.normal;
    } else {
      if (!mSettings.wood) return sample;
      const WoodMesh& wood = mTree.wood;
      const uint32_t* corners = &wood.indices[size_t(primitive) * 3];
      const float w0 = 1.0f - u - v;
      const glm::vec2 uv =
          wood.uvs[corners[0]] * w0 + wood.uvs[corners[1]] * u + wood.uvs[corners[2]] * v;
      glm::vec3 normal = wood.normals[corners[0]] * w0 + wood.normals[corners[1]] * u +
                         wood.normals[corners[2]] * v;
      const WoodMaterial& material = mTree.woodMaterials[wood.materialIds[primitive]];
      sample.color =
          glm::vec3(srgbToLinear(material.baseColor.r), srgbToLinear(material.baseColor.g),
                    srgbToLinear(material.baseColor.b));
      if (material.texture >= 0)
        sample.color *= bilinearLinear(mTree.woodTextures[size_t(material.texture)], uv);
      if (glm::dot(normal, direction) > 0.0f) normal = -normal;  // two-sided, as the reference
      const float length = glm::length(normal);
      sample.normal = length > 1e-8f ? normal / length : -direction;
    }
    sample.hit = true;
    sample.distance = rayHit.ray.tfar;
    return sample;
  }

 private:
  const Tree& mTree;
  const OctahedralCaptureSettings& mSettings;
  TreeRayScene mScene;
  LeafImageSampler mSampler;
};

uint8_t unorm8(float value) {
  return static_cast<uint8_t>(std::lround(std::clamp(value, 0.0f, 1.0f) * 255.0f));
}

// The frame (i, j) into its cells of both atlases; returns the summed alpha of its inner square.
double captureFrame(const FrameTracer& tracer, const OctahedralCaptureSettings& settings,
                    glm::ivec2 frame, glm::vec3 center, float radius, OctahedralFrames& out) {
  const glm::vec3 toCamera = settings.grid.frameDirection(frame);
  const FrameAxes axes = frameAxes(toCamera);
  const int inner = settings.cellTexels - 2 * settings.padding, ss = settings.supersample;
  const float step = 2.0f * radius / float(inner * ss);
  const glm::ivec2 origin = frame * settings.cellTexels + settings.padding;
  double alphaSum = 0.0;
  for (int y = 0; y < inner; ++y) {
    for (int x = 0; x < inner; ++x) {
      glm::vec3 color(0.0f), normal(0.0f);
      float depth = 0.0f;
      int covered = 0;
      for (int sy = 0; sy < ss; ++sy) {
        for (int sx = 0; sx < ss; ++sx) {
          const float a = -radius + (float(x * ss + sx) + 0.5f) * step;
          const float b = -radius + (float(y * ss + sy) + 0.5f) * step;
          const glm::vec3 start =
              center + axes.right * a + axes.up * b + toCamera * (2.0f * radius);
          const RaySample sample = tracer.trace(start, -toCamera, 4.0f * radius, step);
          if (!sample.hit) continue;
          color += sample.color;
          normal += sample.normal;
          depth += sample.distance - 2.0f * radius;  // signed, from the centre plane
          ++covered;
        }
      }
      uint8_t* c = out.color.at(origin.x + x, origin.y + y);
      uint8_t* n = out.normalDepth.at(origin.x + x, origin.y + y);
      writeCoverageTexel(c, color, covered, ss * ss);
      alphaSum += c[3] / 255.0;
      if (covered == 0) continue;
      const float length = glm::length(normal);
      const glm::vec3 unit = length > 1e-8f ? normal / length : toCamera;
      for (int k = 0; k < 3; ++k) n[k] = unorm8(unit[k] * 0.5f + 0.5f);
      n[3] = unorm8(depth / float(covered) / radius * 0.5f + 0.5f);
    }
  }
  return alphaSum;
}

// Empty texels of the normal-depth atlas: the camera's direction and the centre plane, then
// (within `passes` texels of a covered one) their covered neighbours' values.
void fillEmptyNormalDepth(const OctahedralCaptureSettings& settings, OctahedralFrames& frames,
                          int passes) {
  const int n = settings.grid.frames, cell = settings.cellTexels;
  ImageRgba8 normals = frames.normalDepth, depths = frames.normalDepth;
  for (int y = 0; y < frames.color.height; ++y) {
    for (int x = 0; x < frames.color.width; ++x) {
      const bool covered = frames.color.at(x, y)[3] > 0;
      uint8_t* normal = normals.at(x, y);
      uint8_t* depth = depths.at(x, y);
      if (!covered) {
        const glm::ivec2 frame = glm::min(glm::ivec2(x, y) / cell, glm::ivec2(n - 1));
        const glm::vec3 toCamera = settings.grid.frameDirection(frame);
        for (int k = 0; k < 3; ++k) normal[k] = unorm8(toCamera[k] * 0.5f + 0.5f);
        depth[0] = depth[1] = depth[2] = 128;
      } else {
        depth[0] = depth[1] = depth[2] = frames.normalDepth.at(x, y)[3];
      }
      normal[3] = depth[3] = covered ? 255 : 0;
    }
  }
  dilateTransparentColors(normals, passes);
  dilateTransparentColors(depths, passes);
  for (int y = 0; y < frames.color.height; ++y) {
    for (int x = 0; x < frames.color.width; ++x) {
      uint8_t* out = frames.normalDepth.at(x, y);
      std::copy_n(normals.at(x, y), 3, out);
      out[3] = depths.at(x, y)[0];
    }
  }
}

}  // namespace

OctahedralFrames captureOctahedralFrames(const Tree& tree,
                                         const OctahedralCaptureSettings& settings) {
  const int n = settings.grid.frames, side = n * settings.cellTexels;
  OctahedralFrames frames;
  frames.center = tree.boundingSphereCenter();
  frames.radius = std::max(tree.boundingSphereRadius(), 1e-6f);
  frames.color = ImageRgba8(side, side);
  frames.normalDepth = ImageRgba8(side, side);
  const FrameTracer tracer(tree, settings);
  std::vector<double> alphaSums(size_t(n) * n, 0.0);
  tbb::parallel_for(0, n * n, [&](int index) {
    alphaSums[size_t(index)] = captureFrame(tracer, settings, {index % n, index / n}, frames.center,
                                            frames.radius, frames);
  });
  double alphaSum = 0.0;
  for (double sum : alphaSums) alphaSum += sum;
  const int inner = settings.cellTexels - 2 * settings.padding;
  frames.coveredFraction = alphaSum / (double(n) * n * inner * inner);
  fillEmptyNormalDepth(settings, frames, 2 * settings.padding);
  dilateTransparentColors(frames.color, 2 * settings.padding);
  return frames;
}

ImageRgba8 halveImage(const ImageRgba8& image) {
  const int width = std::max(1, image.width / 2), height = std::max(1, image.height / 2);
  ImageRgba8 half(width, height);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      for (int c = 0; c < 4; ++c) {
        int sum = 0;
        for (int dy = 0; dy < 2; ++dy)
          for (int dx = 0; dx < 2; ++dx)
            sum += image.at(std::min(image.width - 1, 2 * x + dx),
                            std::min(image.height - 1, 2 * y + dy))[c];
        half.at(x, y)[c] = static_cast<uint8_t>((sum + 2) / 4);
      }
    }
  }
  return half;
}

std::vector<glm::vec4> frameCoverageRects(const ImageRgba8& color, int frames, int cellTexels,
                                          int padding, int marginTexels) {
  const int inner = cellTexels - 2 * padding;
  std::vector<glm::vec4> rects(size_t(frames) * frames, glm::vec4(1.0f, 1.0f, -1.0f, -1.0f));
  for (int j = 0; j < frames; ++j) {
    for (int i = 0; i < frames; ++i) {
      glm::ivec4 box(inner, inner, -1, -1);  // covered texels: x0, y0, x1, y1 (inclusive)
      for (int y = 0; y < inner; ++y) {
        const uint8_t* row = &color.pixels[(size_t(j * cellTexels + padding + y) * color.width +
                                            size_t(i * cellTexels + padding)) *
                                           4];
        for (int x = 0; x < inner; ++x) {
          if (row[4 * x + 3] == 0) continue;
          box = {std::min(box.x, x), std::min(box.y, y), std::max(box.z, x), std::max(box.w, y)};
        }
      }
      if (box.z < 0) continue;
      // Texel t spans [t, t + 1] / inner · 2 − 1.
      const auto edge = [&](int texel) {
        return std::clamp(float(texel) / float(inner) * 2.0f - 1.0f, -1.0f, 1.0f);
      };
      rects[size_t(j) * frames + i] = {edge(box.x - marginTexels), edge(box.y - marginTexels),
                                       edge(box.z + 1 + marginTexels),
                                       edge(box.w + 1 + marginTexels)};
    }
  }
  return rects;
}

}  // namespace canopy
