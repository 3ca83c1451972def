#pragma once

// The records of metrics.jsonl: one typed struct per kind, each listing its fields once in visit()
// (common/json_fields.h). The JSON keys are DESIGN.md's results schema, which scripts outside the
// code read: extend it, never rename a key. The runner writes these structs, and report, merge and
// resume read them back through the same lists, strictly: a record with a missing or unknown key
// is an InputError naming the file and line. A test reads every committed run, so a key renamed
// here fails the suite instead of silently emptying a table column.

#include <array>
#include <cstdint>
#include <string>
#include <variant>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/json_fields.h"

namespace canopy {

// {"texture", "geometry", "other", "total"}: bytes from the GPU ledger.
struct MemoryRecord {
  uint64_t texture = 0, geometry = 0, other = 0, total = 0;
  template <class V>
  void visit(V& v) {
    v("texture", texture);
    v("geometry", geometry);
    v("other", other);
    v("total", total);
  }
};

// What a frame drew: GL query counts and the share of leaves drawn as leaf polygons.
struct DrawnRecord {
  uint64_t primitives = 0;
  uint64_t fragments = 0;  // fragment-shader invocations (of the supersampled render for views)
  double leafGeometryFraction = 0.0;
  // Instances drawn at each level of detail, finest first (forests: over the scored frames);
  // absent for methods that do not report levels and in runs made before it existed.
  Absent<std::vector<uint64_t>> instancesPerLevel;
  // Likewise for the wood's levels (the full mesh first), for methods that simplify it.
  Absent<std::vector<uint64_t>> woodInstancesPerLevel;
  // Instances left after the harness's frustum culling (forests: mean over the scored frames);
  // absent in runs made before culling existed.
  Absent<double> instancesVisible;
  template <class V>
  void visit(V& v) {
    v("primitives", primitives);
    v("fragments", fragments);
    v("leaf_geometry_fraction", leafGeometryFraction);
    v("instances_per_level", instancesPerLevel);
    v("wood_instances_per_level", woodInstancesPerLevel);
    v("instances_visible", instancesVisible);
  }
};

// One bake of a budget search.
struct BudgetTrialRecord {
  nlohmann::json value;  // the knob's value (an integer or a number)
  double measured = 0.0;
  double memoryMb = 0.0;
  template <class V>
  void visit(V& v) {
    v("value", value);
    v("measured", measured);
    v("memory_mb", memoryMb);
  }
};

// The bake record's "budget": how the method's memory knob was set.
struct BudgetRecord {
  std::string mode;  // "memory_mb" or "psnr_db"
  double target = 0.0, tolerance = 0.0;
  std::string parameter;
  nlohmann::json value;  // the knob's value chosen
  double measured = 0.0, memoryMb = 0.0;
  bool reached = false;
  int steps = 0;
  std::vector<BudgetTrialRecord> trace;
  template <class V>
  void visit(V& v) {
    v("mode", mode);
    v("target", target);
    v("tolerance", tolerance);
    v("parameter", parameter);
    v("value", value);
    v("measured", measured);
    v("memory_mb", memoryMb);
    v("reached", reached);
    v("steps", steps);
    v("trace", trace);
  }
};

struct TreeRecord {
  static constexpr const char* kKind = "tree";
  std::string tree;
  nlohmann::json source;  // preset and seed, a file, or a capture folder
  uint64_t leaves = 0, woodTriangles = 0, branchNodes = 0;
  double boundingRadius = 0.0, loadSeconds = 0.0;
  std::string recordKey;
  template <class V>
  void visit(V& v) {
    v("tree", tree);
    v("source", source);
    v("leaves", leaves);
    v("wood_triangles", woodTriangles);
    v("branch_nodes", branchNodes);
    v("bounding_radius", boundingRadius);
    v("load_s", loadSeconds);
    v("record_key", recordKey);
  }
};

struct BakeRecord {
  static constexpr const char* kKind = "bake";
  std::string tree, method, variant;
  nlohmann::json params;  // effective
  nlohmann::json report;  // the method's facts about its bake
  double bakeSeconds = 0.0;
  uint64_t bakePeakRssBytes = 0;
  std::string bakePeakRssScope;  // "bake", or "process" where the kernel cannot reset the peak
  MemoryRecord memory;
  std::optional<uint64_t> diskBytes;  // null when the asset was not saved
  std::string glRenderer;
  Absent<BudgetRecord> budget;
  std::string recordKey;
  template <class V>
  void visit(V& v) {
    v("tree", tree);
    v("method", method);
    v("variant", variant);
    v("params", params);
    v("report", report);
    v("bake_s", bakeSeconds);
    v("bake_peak_rss_bytes", bakePeakRssBytes);
    v("bake_peak_rss_scope", bakePeakRssScope);
    v("memory_bytes", memory);
    v("disk_bytes", diskBytes);
    v("gl_renderer", glRenderer);
    v("budget", budget);
    v("record_key", recordKey);
  }
};

struct ViewRecord {
  static constexpr const char* kKind = "view";
  std::string tree, method, variant;
  nlohmann::json params;
  std::string ring;  // "orbit", "closeup" or "capture"
  double fovDegrees = 0.0;
  double distance = 0.0;              // bounding radii
  Absent<double> elevation, azimuth;  // orbit and close-up views
  Absent<std::string> captureView;    // capture views: the photograph's file
  double psnr = 0.0, psnrFrame = 0.0, ssim = 0.0, flip = 0.0, coverageError = 0.0;
  int64_t unionPixels = 0;
  std::array<int, 2> resolution{0, 0};
  int supersample = 1;
  DrawnRecord drawn;
  std::string shading;  // "unlit" or "lit"
  bool shadows = false;
  std::string recordKey;
  template <class V>
  void visit(V& v) {
    v("tree", tree);
    v("method", method);
    v("variant", variant);
    v("params", params);
    v("ring", ring);
    v("fov_deg", fovDegrees);
    v("distance", distance);
    v("elevation", elevation);
    v("azimuth", azimuth);
    v("capture_view", captureView);
    v("psnr", psnr);
    v("psnr_frame", psnrFrame);
    v("ssim", ssim);
    v("flip", flip);
    v("coverage_error", coverageError);
    v("union_pixels", unionPixels);
    v("resolution", resolution);
    v("supersample", supersample);
    v("drawn", drawn);
    v("shading", shading);
    v("shadows", shadows);
    v("record_key", recordKey);
  }
};

struct ForestRecord {
  static constexpr const char* kKind = "forest";
  std::string tree, method, variant;
  nlohmann::json params;
  int trees = 0, frames = 0, warmup = 0, blocks = 0;
  Absent<double> repeats;  // mean draws of a camera by each, the fastest timed (absent: 1)
  std::array<int, 2> resolution{0, 0};
  double frameMsMedian = 0.0, frameMsP95 = 0.0, frameMsMean = 0.0, fps = 0.0;
  // Against the reference (null for capture trees, which have no mesh to time against):
  double polygonalFrameMsMedian = 0.0;
  double speedupVsPolygonal = 0.0;                     // geometric mean of the per-frame ratios
  std::optional<std::array<double, 2>> speedupSpread;  // their [q25, q75]
  std::optional<std::vector<double>> blockSpeedups;    // per block, the median of its frames
  // Per camera of the path, in order: reference ms / method ms (each the fastest draw), so any
  // other statistic of the speedup can be computed from the record.
  Absent<std::vector<double>> frameSpeedups;           // absent in runs made before it existed
  double psnr = 0.0, flip = 0.0, coverageError = 0.0;  // forest frames vs the reference's
  double referenceCoverage = 0.0;                      // share of the frame the reference covers
  DrawnRecord drawn;
  std::string glRenderer;
  std::string recordKey;
  template <class V>
  void visit(V& v) {
    v("tree", tree);
    v("method", method);
    v("variant", variant);
    v("params", params);
    v("trees", trees);
    v("frames", frames);
    v("warmup", warmup);
    v("blocks", blocks);
    v("repeats", repeats);
    v("resolution", resolution);
    v("frame_ms_median", frameMsMedian);
    v("frame_ms_p95", frameMsP95);
    v("frame_ms_mean", frameMsMean);
    v("fps", fps);
    v("polygonal_frame_ms_median", polygonalFrameMsMedian);
    v("speedup_vs_polygonal", speedupVsPolygonal);
    v("speedup_spread", speedupSpread);
    v("block_speedups", blockSpeedups);
    v("frame_speedups", frameSpeedups);
    v("psnr", psnr);
    v("flip", flip);
    v("coverage_error", coverageError);
    v("reference_coverage", referenceCoverage);
    v("drawn", drawn);
    v("gl_renderer", glRenderer);
    v("record_key", recordKey);
  }
};

struct PoppingRecord {
  static constexpr const char* kKind = "popping";
  std::string tree, method, variant;
  nlohmann::json params;
  std::string path;  // "dolly" or "orbit"
  std::array<int, 2> resolution{0, 0};
  // Per frame:
  std::vector<double> distance, psnrFrame, change, referenceChange, temporalExcess;
  std::vector<bool> lodSwitch;
  double peakExcess = 0.0, meanExcess = 0.0;
  int switches = 0;
  std::string recordKey;
  template <class V>
  void visit(V& v) {
    v("tree", tree);
    v("method", method);
    v("variant", variant);
    v("params", params);
    v("path", path);
    v("resolution", resolution);
    v("distance", distance);
    v("psnr_frame", psnrFrame);
    v("change", change);
    v("reference_change", referenceChange);
    v("temporal_excess", temporalExcess);
    v("lod_switch", lodSwitch);
    v("peak_excess", peakExcess);
    v("mean_excess", meanExcess);
    v("switches", switches);
    v("record_key", recordKey);
  }
};

// A method that could not run on a tree (one that needs a mesh, on a capture folder).
struct SkipRecord {
  static constexpr const char* kKind = "skip";
  std::string tree, method, variant, reason;
  std::string recordKey;
  template <class V>
  void visit(V& v) {
    v("tree", tree);
    v("method", method);
    v("variant", variant);
    v("reason", reason);
    v("record_key", recordKey);
  }
};

using Record =
    std::variant<TreeRecord, BakeRecord, ViewRecord, ForestRecord, PoppingRecord, SkipRecord>;

// The record as one JSON object, "kind" included.
nlohmann::json recordToJson(const Record& record);
// Reads a record of any kind, strictly; `where` names it in errors ("metrics.jsonl:12").
Record recordFromJson(const nlohmann::json& json, const std::string& where);

const char* kindOf(const Record& record);
const std::string& recordKeyOf(const Record& record);
std::string& recordKeyOf(Record& record);

// The record of `kind` T, or nullptr.
template <typename T>
const T* recordAs(const Record& record) {
  return std::get_if<T>(&record);
}

// The fields of a record that depend on the method variant, not the record's kind.
struct VariantFields {
  std::string tree, method, variant;
};
inline VariantFields variantOf(const Record& record) {
  return std::visit(
      [](const auto& r) -> VariantFields {
        if constexpr (requires { r.variant; })
          return {r.tree, r.method, r.variant};
        else
          return {r.tree, "", ""};
      },
      record);
}

}  // namespace canopy
