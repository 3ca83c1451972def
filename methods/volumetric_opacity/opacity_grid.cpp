#include "methods/volumetric_opacity/opacity_grid.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <tuple>

#include <glm/geometric.hpp>

namespace canopy {

Aabb OpacityGrid::cellBox(size_t cell) const {
  Aabb box;
  box.min = root.min + glm::vec3(cells[cell]) * cellSize;
  box.max = box.min + glm::vec3(cellSize);
  return box;
}

void OpacityGrid::setLattice(const Aabb& cube, int subdivisions) {
  root = cube;
  level = subdivisions;
  side = 1;
  for (int l = 0; l < level; ++l) side *= 3;
  cellSize = root.extent().x / float(side);
}

void OpacityGrid::rebuildLattice() {
  lattice.assign(size_t(side) * side * side, -1);
  for (size_t i = 0; i < cells.size(); ++i) {
    const glm::ivec3 c = cells[i];
    lattice[(size_t(c.z) * side + size_t(c.y)) * side + size_t(c.x)] = int32_t(i);
  }
}

void OpacityGrid::removeTransparentCells(float threshold) {
  size_t kept = 0;
  for (size_t i = 0; i < cells.size(); ++i) {
    if (transparency[i] >= threshold) continue;
    cells[kept] = cells[i];
    transparency[kept] = transparency[i];
    ++kept;
  }
  cells.resize(kept);
  transparency.resize(kept);
  rebuildLattice();
}

std::vector<OpacityView> prepareViews(const std::vector<CapturedView>& views,
                                      float foregroundAlpha) {
  std::vector<OpacityView> prepared;
  prepared.reserve(views.size());
  for (const CapturedView& v : views) {
    prepared.push_back({PixelCamera(v.camera, v.image.width, v.image.height), &v.image,
                        AlphaIntegral(v.image, foregroundAlpha)});
  }
  return prepared;
}

Aabb enclosingCube(const Aabb& bounds) {
  const float half =
      0.5f * std::max({bounds.extent().x, bounds.extent().y, bounds.extent().z}) * 1.02f;
  Aabb cube;
  cube.min = bounds.center() - glm::vec3(half);
  cube.max = bounds.center() + glm::vec3(half);
  return cube;
}

OpacityGrid buildOpacityGrid(const Aabb& cube, int level, const std::vector<OpacityView>& views,
                             float foregroundAlpha) {
  OpacityGrid grid;
  grid.setLattice(cube, level);
  // Level by level: keep the cells no view carves, split the kept ones 3×3×3 (§7).
  std::vector<glm::ivec3> current{glm::ivec3(0)};
  int side = 1;
  for (int l = 0; l <= level; ++l) {
    const float size = cube.extent().x / float(side);
    std::vector<uint8_t> keep(current.size(), 0);
    tbb::parallel_for(size_t(0), current.size(), [&](size_t i) {
      Aabb box;
      box.min = cube.min + glm::vec3(current[i]) * size;
      box.max = box.min + glm::vec3(size);
      for (const OpacityView& v : views)
        if (viewCarvesBox(v.camera, v.alpha, box)) return;
      keep[i] = 1;
    });
    std::vector<glm::ivec3> kept;
    for (size_t i = 0; i < current.size(); ++i)
      if (keep[i]) kept.push_back(current[i]);
    grid.nonEmptyPerLevel.push_back(int(kept.size()));
    if (l == level) {
      current = std::move(kept);
      break;
    }
    std::vector<glm::ivec3> children;
    children.reserve(kept.size() * 27);
    for (const glm::ivec3& c : kept)
      for (int z = 0; z < 3; ++z)
        for (int y = 0; y < 3; ++y)
          for (int x = 0; x < 3; ++x) children.push_back(c * 3 + glm::ivec3(x, y, z));
    current = std::move(children);
    side *= 3;
  }
  // Lattice order (z, y, x) so the cell list, and everything derived from it, is deterministic.
  std::sort(current.begin(), current.end(), [](const glm::ivec3& a, const glm::ivec3& b) {
    return std::tie(a.z, a.y, a.x) < std::tie(b.z, b.y, b.x);
  });
  grid.cells = std::move(current);
  grid.rebuildLattice();
  // §5 initialisation: α_i = min over views of the average alpha in the cell's projection.
  grid.transparency.assign(grid.cells.size(), 1.0f);
  tbb::parallel_for(size_t(0), grid.cells.size(), [&](size_t i) {
    const Aabb box = grid.cellBox(i);
    double minAlpha = 1.0;
    for (const OpacityView& v : views) {
      PixelRect r;
      if (!projectBoxInside(v.camera, box, r)) continue;
      minAlpha = std::min(minAlpha, v.alpha.alphaSum(r.x0, r.y0, r.x1, r.y1) / double(r.area()));
    }
    grid.transparency[i] = float(1.0 - minAlpha);
  });
  return grid;
}

OpacityGrid coarsenGrid(const OpacityGrid& fine, float minTransparency) {
  if (fine.level < 1) throw std::logic_error("coarsenGrid: the grid has no coarser level");
  OpacityGrid coarse;
  coarse.root = fine.root;
  coarse.level = fine.level - 1;
  coarse.side = fine.side / 3;
  coarse.cellSize = fine.cellSize * 3.0f;
  coarse.nonEmptyPerLevel = fine.nonEmptyPerLevel;
  coarse.nonEmptyPerLevel.resize(
      std::min(coarse.nonEmptyPerLevel.size(), size_t(coarse.level) + 1));
  std::map<std::tuple<int, int, int>, double> depth;  // lattice order (z, y, x)
  for (size_t i = 0; i < fine.cells.size(); ++i) {
    const glm::ivec3 parent = fine.cells[i] / 3;
    depth[{parent.z, parent.y, parent.x}] -= std::log(double(fine.transparency[i])) / 9.0;
  }
  coarse.cells.reserve(depth.size());
  coarse.transparency.reserve(depth.size());
  for (const auto& [zyx, opticalDepth] : depth) {
    coarse.cells.emplace_back(std::get<2>(zyx), std::get<1>(zyx), std::get<0>(zyx));
    coarse.transparency.push_back(
        std::clamp(float(std::exp(-opticalDepth)), minTransparency, 1.0f - 1e-6f));
  }
  coarse.rebuildLattice();
  return coarse;
}

bool traceRay(const OpacityGrid& grid, const PixelCamera& camera, float px, float py,
              std::vector<RaySegment>& out) {
  out.clear();
  const glm::vec3 origin = camera.position();
  const glm::vec3 dir = camera.rayDirection({px, py});
  // Slab test against the root cube.
  float tEnter = 0.0f, tExit = std::numeric_limits<float>::max();
  for (int a = 0; a < 3; ++a) {
    if (std::abs(dir[a]) < 1e-12f) {
      if (origin[a] < grid.root.min[a] || origin[a] > grid.root.max[a]) return false;
      continue;
    }
    float t0 = (grid.root.min[a] - origin[a]) / dir[a],
          t1 = (grid.root.max[a] - origin[a]) / dir[a];
    if (t0 > t1) std::swap(t0, t1);
    tEnter = std::max(tEnter, t0);
    tExit = std::min(tExit, t1);
  }
  if (tEnter >= tExit) return false;
  // Appendix A with the pyramid integrated exactly: a pixel's cross-section at depth z is (z/f)²,
  // depth z = t·cosθ along the ray, so the pyramid between t0 and t1 holds
  // cos³θ (t1³ − t0³) / (3 f²).
  const float cosTheta = glm::dot(dir, camera.forward());
  const double scale = double(cosTheta) * cosTheta * cosTheta /
                       (3.0 * double(camera.focalPixels()) * camera.focalPixels() *
                        double(grid.cellSize) * grid.cellSize * grid.cellSize);
  // 3D-DDA (Amanatides & Woo) from the entry point.
  const glm::vec3 entry = origin + dir * tEnter;
  glm::ivec3 cell = glm::clamp(glm::ivec3(glm::floor((entry - grid.root.min) / grid.cellSize)),
                               glm::ivec3(0), glm::ivec3(grid.side - 1));
  glm::ivec3 step;
  glm::vec3 tMax, tDelta;
  for (int a = 0; a < 3; ++a) {
    if (dir[a] > 0.0f) {
      step[a] = 1;
      tMax[a] = (grid.root.min[a] + float(cell[a] + 1) * grid.cellSize - origin[a]) / dir[a];
      tDelta[a] = grid.cellSize / dir[a];
    } else if (dir[a] < 0.0f) {
      step[a] = -1;
      tMax[a] = (grid.root.min[a] + float(cell[a]) * grid.cellSize - origin[a]) / dir[a];
      tDelta[a] = -grid.cellSize / dir[a];
    } else {
      step[a] = 0;
      tMax[a] = std::numeric_limits<float>::max();
      tDelta[a] = std::numeric_limits<float>::max();
    }
  }
  float t = tEnter;
  while (t < tExit) {
    const int axis = tMax.x < tMax.y ? (tMax.x < tMax.z ? 0 : 2) : (tMax.y < tMax.z ? 1 : 2);
    const float tNext = std::min(tMax[axis], tExit);
    const int32_t index = grid.cellAt(cell);
    if (index >= 0 && tNext > t) {
      const double w = scale * (double(tNext) * tNext * tNext - double(t) * t * t);
      out.push_back({index, float(w), (tNext - t) / grid.cellSize});
    }
    t = tNext;
    cell[axis] += step[axis];
    if (cell[axis] < 0 || cell[axis] >= grid.side) break;
    tMax[axis] += tDelta[axis];
  }
  return true;
}

}  // namespace canopy
