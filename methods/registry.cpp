#include <algorithm>

#include "methods/bbox_hierarchy/bbox_hierarchy.h"
#include "methods/billboard_cloud/billboard_cloud.h"
#include "methods/method.h"
#include "methods/multilayer_indirect/multilayer_indirect.h"
#include "methods/octahedral/octahedral.h"
#include "methods/polygonal/polygonal.h"
#include "methods/single_leaf_indirect/single_leaf_indirect.h"
#include "methods/volumetric_opacity/volumetric_opacity.h"

namespace canopy {

void MethodRegistry::add(MethodInfo info) {
  for (const MethodInfo& existing : mMethods) {
    if (existing.name == info.name) throw std::logic_error("method registered twice: " + info.name);
  }
  mMethods.push_back(std::move(info));
}

const MethodInfo& MethodRegistry::find(const std::string& name) const {
  for (const MethodInfo& info : mMethods) {
    if (info.name == name) return info;
  }
  std::string known;
  for (const MethodInfo& info : mMethods) known += (known.empty() ? "" : ", ") + info.name;
  throwInputError("unknown method '{}' (registered: {})", name, known);
}

std::vector<std::string> MethodRegistry::names() const {
  std::vector<std::string> names;
  for (const MethodInfo& info : mMethods) names.push_back(info.name);
  return names;
}

const MethodRegistry& builtinMethods() {
  static const MethodRegistry registry = [] {
    MethodRegistry r;
    // One explicit registration per method, in the order reports list them.
    registerPolygonal(r);
    registerBillboardCloud(r);
    registerSingleLeafIndirect(r);
    registerMultilayerIndirect(r);
    registerBboxHierarchy(r);
    registerVolumetricOpacity(r);
    registerOctahedral(r);
    return r;
  }();
  return registry;
}

}  // namespace canopy
