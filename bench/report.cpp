#include "bench/report.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include <fmt/format.h>

#include "common/atomic_file.h"

namespace canopy {
namespace {

struct Mean {
  double sum = 0;
  int count = 0;
  void add(double v) {
    if (std::isfinite(v)) {
      sum += v;
      ++count;
    }
  }
  double value() const { return count ? sum / count : std::nan(""); }
};

std::string csvField(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

std::string number(double value, int decimals) {
  return std::isfinite(value) ? fmt::format("{:.{}f}", value, decimals) : "";
}

double mb(const nlohmann::json& bytes) {
  return bytes.is_number() ? bytes.get<double>() / 1e6 : std::nan("");
}

template <typename Rows, typename Get>
std::vector<double> collectKeys(const Rows& rows, Get get) {
  std::set<double> keys;
  for (const auto& row : rows)
    for (const auto& [key, value] : get(row)) keys.insert(key);
  return {keys.begin(), keys.end()};
}

double lookup(const std::vector<std::pair<double, double>>& pairs, double key) {
  for (const auto& [k, v] : pairs)
    if (k == key) return v;
  return std::nan("");
}

const nlohmann::json* forestOfSize(const SummaryRow& row, int size) {
  for (const nlohmann::json& f : row.forests)
    if (f.value("trees", 0) == size) return &f;
  return nullptr;
}

std::vector<int> forestSizes(const std::vector<SummaryRow>& rows) {
  std::set<int> sizes;
  for (const SummaryRow& row : rows)
    for (const auto& f : row.forests) sizes.insert(f.value("trees", 0));
  return {sizes.begin(), sizes.end()};
}

double jsonNumber(const nlohmann::json* record, const char* key) {
  if (!record || !record->contains(key) || !(*record)[key].is_number()) return std::nan("");
  return (*record)[key].get<double>();
}

// A forest record's fragment-shader invocations per pixel of its frame.
double forestFragmentsPerPixel(const nlohmann::json* forest) {
  if (!forest || !forest->contains("drawn") || !forest->contains("resolution")) return std::nan("");
  const double w = (*forest)["resolution"][0], h = (*forest)["resolution"][1];
  return jsonNumber(&(*forest)["drawn"], "fragments") / (w * h);
}

double forestLeafFraction(const nlohmann::json* forest) {
  return forest && forest->contains("drawn")
             ? jsonNumber(&(*forest)["drawn"], "leaf_geometry_fraction")
             : std::nan("");
}

// The interquartile range of a forest's per-block speedups: (q25, q75).
std::pair<double, double> speedupSpread(const nlohmann::json* forest) {
  if (!forest || !forest->contains("speedup_spread") || !(*forest)["speedup_spread"].is_array())
    return {std::nan(""), std::nan("")};
  const nlohmann::json& spread = (*forest)["speedup_spread"];
  return {spread[0].get<double>(), spread[1].get<double>()};
}

// "2.95× [2.80–3.10]": a speedup with its interquartile range, "–" without one.
std::string speedupText(const nlohmann::json* forest) {
  const double speedup = jsonNumber(forest, "speedup_vs_polygonal");
  if (!std::isfinite(speedup)) return "–";
  const auto [q25, q75] = speedupSpread(forest);
  std::string text = number(speedup, 2) + "×";
  if (std::isfinite(q25)) text += " [" + number(q25, 2) + "–" + number(q75, 2) + "]";
  return text;
}

// "| a | b | c1 | c2 |\n|---|---|--:|--:|\n": text columns, then right-aligned numbers.
std::string markdownHeader(const std::vector<std::string>& textColumns,
                           const std::vector<std::string>& numberColumns) {
  std::string header = "|", rule = "|";
  for (const std::string& c : textColumns) header += " " + c + " |", rule += "---|";
  for (const std::string& c : numberColumns) header += " " + c + " |", rule += "--:|";
  return header + "\n" + rule + "\n";
}

template <typename T>
std::vector<std::string> labels(const std::vector<T>& keys, const char* format) {
  std::vector<std::string> result;
  for (const T& key : keys) result.push_back(fmt::format(fmt::runtime(format), key));
  return result;
}

}  // namespace

std::vector<SummaryRow> summarize(const std::vector<nlohmann::json>& records) {
  std::vector<SummaryRow> rows;
  std::map<std::pair<std::string, std::string>, size_t> index;
  struct Accumulator {
    Mean psnr, psnrFrame, ssim, coverage, flip, psnrCloseup, flipCloseup, ssimCloseup;
    Mean primitives, fragmentsPerPixel, leafFraction;
    std::map<double, Mean> byDistance, byElevation;
  };
  std::vector<Accumulator> accumulators;
  for (const nlohmann::json& record : records) {
    const std::string kind = record.value("kind", "");
    if (kind == "tree") continue;
    const std::string tree = record.value("tree", ""),
                      variant = record.value("variant", record.value("method", ""));
    auto [it, inserted] = index.try_emplace({tree, variant}, rows.size());
    if (inserted) {
      SummaryRow row;
      row.tree = tree;
      row.method = record.value("method", "");
      row.variant = variant;
      row.params = record.value("params", nlohmann::json::object());
      rows.push_back(std::move(row));
      accumulators.emplace_back();
    }
    SummaryRow& row = rows[it->second];
    Accumulator& acc = accumulators[it->second];
    if (kind == "bake") {
      row.bake = record;
      row.params = record.value("params", row.params);
    } else if (kind == "view") {
      const double psnr = record.value("psnr", std::nan(""));
      if (record.value("ring", "orbit") == "closeup") {
        acc.psnrCloseup.add(psnr);
        acc.flipCloseup.add(jsonNumber(&record, "flip"));
        acc.ssimCloseup.add(jsonNumber(&record, "ssim"));
        ++row.closeupViews;
        continue;
      }
      acc.psnr.add(psnr);
      acc.psnrFrame.add(record.value("psnr_frame", std::nan("")));
      acc.ssim.add(record.value("ssim", std::nan("")));
      acc.coverage.add(record.value("coverage_error", std::nan("")));
      acc.flip.add(jsonNumber(&record, "flip"));
      if (record.contains("drawn") && record.contains("resolution")) {
        const nlohmann::json& drawn = record["drawn"];
        const double s = record.value("supersample", 1.0), w = record["resolution"][0],
                     h = record["resolution"][1];
        acc.primitives.add(jsonNumber(&drawn, "primitives"));
        acc.fragmentsPerPixel.add(jsonNumber(&drawn, "fragments") / (s * s * w * h));
        acc.leafFraction.add(jsonNumber(&drawn, "leaf_geometry_fraction"));
      }
      acc.byDistance[record.value("distance", 0.0)].add(psnr);
      // Capture views have no elevation (the capture's up axis is its own).
      if (record.contains("elevation"))
        acc.byElevation[record["elevation"].get<double>()].add(psnr);
      ++row.views;
    } else if (kind == "forest") {
      row.forests.push_back(record);
    } else if (kind == "popping") {
      row.popping.push_back(record);
    } else if (kind == "skip") {
      row.skipped = record.value("reason", "skipped");
    }
  }
  for (size_t i = 0; i < rows.size(); ++i) {
    const Accumulator& acc = accumulators[i];
    rows[i].psnr = acc.psnr.value();
    rows[i].psnrFrame = acc.psnrFrame.value();
    rows[i].ssim = acc.ssim.value();
    rows[i].coverageError = acc.coverage.value();
    rows[i].flip = acc.flip.value();
    rows[i].psnrCloseup = acc.psnrCloseup.value();
    rows[i].flipCloseup = acc.flipCloseup.value();
    rows[i].ssimCloseup = acc.ssimCloseup.value();
    rows[i].primitives = acc.primitives.value();
    rows[i].fragmentsPerPixel = acc.fragmentsPerPixel.value();
    rows[i].leafGeometryFraction = acc.leafFraction.value();
    for (const auto& [d, m] : acc.byDistance) rows[i].psnrByDistance.emplace_back(d, m.value());
    for (const auto& [e, m] : acc.byElevation) rows[i].psnrByElevation.emplace_back(e, m.value());
    std::sort(rows[i].forests.begin(), rows[i].forests.end(), [](const auto& a, const auto& b) {
      return a.value("trees", 0) < b.value("trees", 0);
    });
  }
  return rows;
}

namespace {

const nlohmann::json* poppingOf(const SummaryRow& row, const std::string& path) {
  for (const nlohmann::json& p : row.popping)
    if (p.value("path", "") == path) return &p;
  return nullptr;
}

std::vector<std::string> poppingPaths(const std::vector<SummaryRow>& rows) {
  std::set<std::string> paths;
  for (const SummaryRow& row : rows)
    for (const auto& p : row.popping) paths.insert(p.value("path", ""));
  return {paths.begin(), paths.end()};
}

const nlohmann::json* budgetOf(const SummaryRow& row) {
  return row.bake.is_object() && row.bake.contains("budget") ? &row.bake["budget"] : nullptr;
}

}  // namespace

std::string formatPoppingCsv(const std::vector<SummaryRow>& rows) {
  std::string out;
  for (const SummaryRow& row : rows) {
    for (const nlohmann::json& p : row.popping) {
      const auto& distance = p.at("distance");
      for (size_t i = 0; i < distance.size(); ++i) {
        out += fmt::format(
            "{},{},{},{},{},{},{},{},{},{}\n", csvField(row.tree), csvField(row.variant),
            p.value("path", ""), i, distance[i].get<double>(), p.at("psnr_frame")[i].get<double>(),
            p.at("change")[i].get<double>(), p.at("reference_change")[i].get<double>(),
            p.at("temporal_excess")[i].get<double>(), p.at("lod_switch")[i].get<bool>() ? 1 : 0);
      }
    }
  }
  if (out.empty()) return out;
  return "tree,variant,path,frame,distance,psnr,change,reference_change,temporal_excess,"
         "lod_switch\n" +
         out;
}

std::string formatSummaryCsv(const std::vector<SummaryRow>& rows) {
  const auto distances = collectKeys(rows, [](const SummaryRow& r) { return r.psnrByDistance; });
  const auto elevations = collectKeys(rows, [](const SummaryRow& r) { return r.psnrByElevation; });
  const auto sizes = forestSizes(rows);
  std::string out =
      "tree,method,variant,params,bake_s,bake_peak_rss_mb,memory_texture_mb,memory_geometry_mb,"
      "memory_other_mb,memory_total_mb,disk_mb,views,psnr,psnr_frame,ssim,coverage_error,flip,"
      "closeup_views,psnr_closeup,flip_closeup,ssim_closeup,primitives,fragments_per_pixel,"
      "leaf_geometry_fraction";
  for (double d : distances) out += fmt::format(",psnr_d{:g}", d);
  for (double e : elevations) out += fmt::format(",psnr_e{:g}", e);
  for (int n : sizes)
    out += fmt::format(
        ",frame_ms_median_n{0},frame_ms_p95_n{0},fps_n{0},speedup_vs_polygonal_n{0},"
        "speedup_q25_n{0},speedup_q75_n{0},forest_psnr_n{0},forest_flip_n{0},"
        "forest_coverage_error_n{0},forest_fragments_per_pixel_n{0},"
        "forest_leaf_geometry_fraction_n{0}",
        n);
  const auto paths = poppingPaths(rows);
  for (const std::string& path : paths)
    out += fmt::format(",popping_{0}_peak,popping_{0}_mean,popping_{0}_switches", path);
  out += ",budget_parameter,budget_value,budget_reached,skipped\n";
  for (const SummaryRow& row : rows) {
    const nlohmann::json& bake = row.bake;
    const nlohmann::json memory =
        bake.is_object() ? bake.value("memory_bytes", nlohmann::json()) : nlohmann::json();
    const auto memoryField = [&](const char* key) {
      return memory.is_object() ? mb(memory[key]) : std::nan("");
    };
    out += csvField(row.tree) + "," + csvField(row.method) + "," + csvField(row.variant) + "," +
           csvField(row.params.dump());
    out += "," + number(jsonNumber(bake.is_object() ? &bake : nullptr, "bake_s"), 4);
    out += "," + number(bake.is_object() ? mb(bake.value("bake_peak_rss_bytes", nlohmann::json()))
                                         : std::nan(""),
                        2);
    for (const char* key : {"texture", "geometry", "other", "total"})
      out += "," + number(memoryField(key), 4);
    out +=
        "," +
        number(bake.is_object() ? mb(bake.value("disk_bytes", nlohmann::json())) : std::nan(""), 4);
    out += fmt::format(",{}", row.views);
    out += "," + number(row.psnr, 3) + "," + number(row.psnrFrame, 3) + "," + number(row.ssim, 4) +
           "," + number(row.coverageError, 5) + "," + number(row.flip, 4);
    out += fmt::format(",{}", row.closeupViews) + "," + number(row.psnrCloseup, 3) + "," +
           number(row.flipCloseup, 4) + "," + number(row.ssimCloseup, 4);
    out += "," + number(row.primitives, 0) + "," + number(row.fragmentsPerPixel, 4) + "," +
           number(row.leafGeometryFraction, 4);
    for (double d : distances) out += "," + number(lookup(row.psnrByDistance, d), 3);
    for (double e : elevations) out += "," + number(lookup(row.psnrByElevation, e), 3);
    for (int n : sizes) {
      const nlohmann::json* f = forestOfSize(row, n);
      const auto [q25, q75] = speedupSpread(f);
      out += "," + number(jsonNumber(f, "frame_ms_median"), 3) + "," +
             number(jsonNumber(f, "frame_ms_p95"), 3) + "," + number(jsonNumber(f, "fps"), 3) +
             "," + number(jsonNumber(f, "speedup_vs_polygonal"), 3) + "," + number(q25, 3) + "," +
             number(q75, 3) + "," + number(jsonNumber(f, "psnr"), 3) + "," +
             number(jsonNumber(f, "flip"), 4) + "," + number(jsonNumber(f, "coverage_error"), 5) +
             "," + number(forestFragmentsPerPixel(f), 4) + "," + number(forestLeafFraction(f), 4);
    }
    for (const std::string& path : paths) {
      const nlohmann::json* p = poppingOf(row, path);
      out += "," + number(jsonNumber(p, "peak_excess"), 3) + "," +
             number(jsonNumber(p, "mean_excess"), 3) + "," + number(jsonNumber(p, "switches"), 0);
    }
    const nlohmann::json* budget = budgetOf(row);
    out += budget ? fmt::format(",{},{},{}", budget->value("parameter", ""),
                                (*budget)["value"].dump(), budget->value("reached", false) ? 1 : 0)
                  : ",,,";
    out += "," + csvField(row.skipped) + "\n";
  }
  return out;
}

std::string formatSummaryMarkdown(const std::vector<SummaryRow>& rows, const std::string& title,
                                  const std::string& renderer) {
  const auto distances = collectKeys(rows, [](const SummaryRow& r) { return r.psnrByDistance; });
  const auto elevations = collectKeys(rows, [](const SummaryRow& r) { return r.psnrByElevation; });
  std::string out = fmt::format(
      "# {}\n\nRenderer: `{}`. PSNR in dB over the union of coverage masks "
      "(capped at 100 dB for identical images); memory from the GPU ledger.\n\n",
      title, renderer);
  bool anyCloseup = false;
  for (const SummaryRow& row : rows) anyCloseup = anyCloseup || row.closeupViews > 0;
  std::vector<std::string> quality = {"bake s", "memory MB", "disk MB",     "PSNR",
                                      "FLIP",   "SSIM",      "coverage err"};
  for (const std::string& label : labels(distances, "PSNR @{:g}r")) quality.push_back(label);
  if (anyCloseup) {
    quality.push_back("PSNR close-up");
    quality.push_back("FLIP close-up");
  }
  out +=
      "## Quality, memory and bake\n\nPSNR, FLIP, SSIM and coverage error are means over the "
      "orbit rings' views; the close-up ring (a narrow field of view, leaves tens of pixels "
      "wide) has its own columns.\n\n" +
      markdownHeader({"tree", "method"}, quality);
  for (const SummaryRow& row : rows) {
    const nlohmann::json* bake = row.bake.is_object() ? &row.bake : nullptr;
    const double memory =
        bake ? mb((*bake)["memory_bytes"].value("total", nlohmann::json())) : std::nan("");
    out +=
        fmt::format("| {} | {} | {} | {} | {} | {} | {} | {} | {} |", row.tree, row.variant,
                    number(jsonNumber(bake, "bake_s"), 2), number(memory, 2),
                    number(bake ? mb((*bake)["disk_bytes"]) : std::nan(""), 2), number(row.psnr, 2),
                    number(row.flip, 3), number(row.ssim, 3), number(row.coverageError, 4));
    for (double d : distances) out += " " + number(lookup(row.psnrByDistance, d), 2) + " |";
    if (anyCloseup)
      out += " " + number(row.psnrCloseup, 2) + " | " + number(row.flipCloseup, 3) + " |";
    out += "\n";
  }
  const auto sizes = forestSizes(rows);
  std::vector<std::string> drawnColumns = {"primitives / view", "fragments / px",
                                           "leaf polygons %"};
  for (int n : sizes) {
    drawnColumns.push_back(fmt::format("fragments / px, {} trees", n));
    drawnColumns.push_back(fmt::format("leaf polygons %, {} trees", n));
  }
  out +=
      "\n## What was drawn\n\nGL query counts of the orbit views (fragment-shader "
      "invocations per output pixel, supersampling divided out) and of the forests' scored "
      "frames; leaf polygons: the share of the tree's leaves drawn as leaf polygons (100 % for "
      "the reference, 0 % for a pure impostor).\n\n" +
      markdownHeader({"tree", "method"}, drawnColumns);
  for (const SummaryRow& row : rows) {
    out +=
        fmt::format("| {} | {} | {} | {} | {} |", row.tree, row.variant, number(row.primitives, 0),
                    number(row.fragmentsPerPixel, 2), number(100.0 * row.leafGeometryFraction, 1));
    for (int n : sizes) {
      const nlohmann::json* f = forestOfSize(row, n);
      out += " " + number(forestFragmentsPerPixel(f), 2) + " | " +
             number(100.0 * forestLeafFraction(f), 1) + " |";
    }
    out += "\n";
  }
  const auto paths = poppingPaths(rows);
  if (!paths.empty()) {
    std::vector<std::string> columns;
    for (const std::string& path : paths) {
      columns.push_back(path + " peak");
      columns.push_back(path + " mean");
      columns.push_back(path + " LoD switches");
    }
    out += "\n## Popping (temporal error in excess of the reference's, 8-bit RMS)\n\n" +
           markdownHeader({"tree", "method"}, columns);
    for (const SummaryRow& row : rows) {
      if (row.popping.empty()) continue;
      out += fmt::format("| {} | {} |", row.tree, row.variant);
      for (const std::string& path : paths) {
        const nlohmann::json* p = poppingOf(row, path);
        out += " " + number(jsonNumber(p, "peak_excess"), 2) + " | " +
               number(jsonNumber(p, "mean_excess"), 2) + " | " +
               number(jsonNumber(p, "switches"), 0) + " |";
      }
      out += "\n";
    }
  }
  bool anyBudget = false;
  for (const SummaryRow& row : rows) anyBudget = anyBudget || budgetOf(row);
  if (anyBudget) {
    out += "\n## Budget (each method's memory knob set by bisection)\n\n" +
           markdownHeader({"tree", "method", "parameter", "reached"},
                          {"value", "target", "memory MB", "PSNR", "bakes"});
    for (const SummaryRow& row : rows) {
      const nlohmann::json* b = budgetOf(row);
      if (!b) continue;
      const double memory = mb(row.bake["memory_bytes"].value("total", nlohmann::json()));
      out +=
          fmt::format("| {} | {} | {} | {} | {} | {} {} | {} | {} | {} |\n", row.tree, row.variant,
                      b->value("parameter", ""), b->value("reached", false) ? "yes" : "no",
                      (*b)["value"].dump(), number(jsonNumber(b, "target"), 2),
                      b->value("mode", "") == "memory_mb" ? "MB" : "dB", number(memory, 2),
                      number(row.psnr, 2), number(jsonNumber(b, "steps"), 0));
    }
  }
  bool anySkipped = false;
  for (const SummaryRow& row : rows) anySkipped = anySkipped || !row.skipped.empty();
  if (anySkipped) {
    out += "\nSkipped: ";
    for (const SummaryRow& row : rows)
      if (!row.skipped.empty())
        out += fmt::format("{} on {} ({}); ", row.variant, row.tree, row.skipped);
    out += "\n";
  }
  if (!elevations.empty()) {
    out += "\n## PSNR by elevation\n\n" +
           markdownHeader({"tree", "method"}, labels(elevations, "{:g}°"));
    for (const SummaryRow& row : rows) {
      out += fmt::format("| {} | {} |", row.tree, row.variant);
      for (double e : elevations) out += " " + number(lookup(row.psnrByElevation, e), 2) + " |";
      out += "\n";
    }
  }
  if (!sizes.empty()) {
    out +=
        "\n## Frame time by forest size\n\nMedian ms / FPS / speedup vs polygonal: the median "
        "of per-block ratios with their interquartile range, blocks of reference and method "
        "frames timed in turn on the same cameras in the same run.\n\n" +
        markdownHeader({"tree", "method"}, labels(sizes, "{} trees"));
    for (const SummaryRow& row : rows) {
      out += fmt::format("| {} | {} |", row.tree, row.variant);
      for (int n : sizes) {
        const nlohmann::json* f = forestOfSize(row, n);
        out += f ? fmt::format(" {} / {} / {} |", number(jsonNumber(f, "frame_ms_median"), 1),
                               number(jsonNumber(f, "fps"), 1), speedupText(f))
                 : " |";
      }
      out += "\n";
    }
    out += "\n## Forest frames against the reference's (PSNR over the frame / FLIP)\n\n" +
           markdownHeader({"tree", "method"}, labels(sizes, "{} trees"));
    for (const SummaryRow& row : rows) {
      out += fmt::format("| {} | {} |", row.tree, row.variant);
      for (int n : sizes) {
        const nlohmann::json* f = forestOfSize(row, n);
        out += f && std::isfinite(jsonNumber(f, "flip"))
                   ? fmt::format(" {} / {} |", number(jsonNumber(f, "psnr"), 2),
                                 number(jsonNumber(f, "flip"), 3))
                   : " |";
      }
      out += "\n";
    }
  }
  return out;
}

namespace {

std::string latexEscape(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '_':
      case '%':
      case '&':
      case '#':
      case '$':
      case '{':
      case '}':
        out += '\\';
        out += c;
        break;
      case '\\':
        out += "\\textbackslash{}";
        break;
      case '^':
        out += "\\textasciicircum{}";
        break;
      case '~':
        out += "\\textasciitilde{}";
        break;
      default:
        out += c;
    }
  }
  return out;
}

}  // namespace

std::string formatSummaryLatex(const std::vector<SummaryRow>& rows, const std::string& title,
                               const std::string& renderer) {
  const auto distances = collectKeys(rows, [](const SummaryRow& r) { return r.psnrByDistance; });
  const auto sizes = forestSizes(rows);
  bool anyCloseup = false;
  for (const SummaryRow& row : rows) anyCloseup = anyCloseup || row.closeupViews > 0;
  const size_t numbers = 2 + distances.size() + (anyCloseup ? 1 : 0) + 3 + sizes.size();
  std::string out = "% Generated by canopy-bench; needs \\usepackage{booktabs}.\n";
  out += "\\begin{table}\n\\centering\n\\small\n\\begin{tabular}{ll" + std::string(numbers, 'r') +
         "}\n\\toprule\n";
  out += "Tree & Method & Bake (s) & Memory (MB)";
  for (double d : distances) out += fmt::format(" & PSNR@{:g}r", d);
  if (anyCloseup) out += " & PSNR close-up";
  out += " & SSIM & FLIP & Cov.\\ err.";
  for (int n : sizes) out += fmt::format(" & Speedup@{}", n);
  out += " \\\\\n\\midrule\n";
  for (const SummaryRow& row : rows) {
    const nlohmann::json* bake = row.bake.is_object() ? &row.bake : nullptr;
    const double memory =
        bake ? mb((*bake)["memory_bytes"].value("total", nlohmann::json())) : std::nan("");
    out += latexEscape(row.tree) + " & " + latexEscape(row.variant) + " & " +
           number(jsonNumber(bake, "bake_s"), 2) + " & " + number(memory, 2);
    for (double d : distances) out += " & " + number(lookup(row.psnrByDistance, d), 2);
    if (anyCloseup) out += " & " + number(row.psnrCloseup, 2);
    out += " & " + number(row.ssim, 3) + " & " + number(row.flip, 3) + " & " +
           number(row.coverageError, 3);
    for (int n : sizes)
      out += " & " + number(jsonNumber(forestOfSize(row, n), "speedup_vs_polygonal"), 2);
    out += " \\\\\n";
  }
  out += "\\bottomrule\n\\end{tabular}\n";
  out += "\\caption{" + latexEscape(title) +
         ": PSNR in dB over the union of coverage masks, LDR-FLIP (mean over the frame), memory "
         "from the GPU ledger, speedup = polygonal / method frame time (median of interleaved "
         "blocks in the same run). Renderer: " +
         latexEscape(renderer) + ".}\n\\end{table}\n";
  return out;
}

std::string formatMainTable(const std::vector<SummaryRow>& rows, const std::string& renderer) {
  const std::string tree = rows.front().tree;
  std::vector<SummaryRow> subset;
  for (const SummaryRow& row : rows)
    if (row.tree == tree) subset.push_back(row);
  const auto distances = collectKeys(subset, [](const SummaryRow& r) { return r.psnrByDistance; });
  const auto sizes = forestSizes(subset);
  const int largest = sizes.empty() ? 0 : sizes.back();
  bool anyCloseup = false, anyPopping = false;
  for (const SummaryRow& row : subset) {
    anyCloseup = anyCloseup || row.closeupViews > 0;
    anyPopping = anyPopping || poppingOf(row, "dolly");
  }
  std::string rings;
  for (double d : distances) rings += (rings.empty() ? "" : " / ") + fmt::format("{:g}r", d);
  std::vector<std::string> columns = {"GPU memory (MB)", "bake (s)", "PSNR (dB)", "FLIP",
                                      "PSNR @" + rings};
  if (anyCloseup) columns.push_back("close-up PSNR / FLIP");
  columns.push_back("leaf polygons");
  if (largest > 0) {
    columns.push_back(fmt::format("speedup, {} trees [IQR]", largest));
    columns.push_back(fmt::format("forest FLIP, {} trees", largest));
  }
  if (anyPopping) columns.push_back("popping peak (dolly)");
  std::string out =
      fmt::format("{} (renderer: {})\n\n", tree, renderer) + markdownHeader({"method"}, columns);
  for (const SummaryRow& row : subset) {
    const nlohmann::json* bake = row.bake.is_object() ? &row.bake : nullptr;
    std::string byRing;
    for (double d : distances)
      byRing += (byRing.empty() ? "" : " / ") + number(lookup(row.psnrByDistance, d), 1);
    out += fmt::format(
        "| `{}` | {} | {} | {} | {} | {} |", row.variant,
        number(bake ? mb((*bake)["memory_bytes"].value("total", nlohmann::json())) : std::nan(""),
               2),
        number(jsonNumber(bake, "bake_s"), 2), number(row.psnr, 2), number(row.flip, 3), byRing);
    if (anyCloseup)
      out += " " + number(row.psnrCloseup, 1) + " / " + number(row.flipCloseup, 3) + " |";
    out += " " + number(100.0 * row.leafGeometryFraction, 0) + " % |";
    if (largest > 0) {
      const nlohmann::json* f = forestOfSize(row, largest);
      out += " " + speedupText(f) + " | " + number(jsonNumber(f, "flip"), 3) + " |";
    }
    if (anyPopping)
      out += " " + number(jsonNumber(poppingOf(row, "dolly"), "peak_excess"), 2) + " |";
    out += "\n";
  }
  return out;
}

void writeSummaries(const std::filesystem::path& directory,
                    const std::vector<nlohmann::json>& records, const std::string& title,
                    const std::string& renderer) {
  const auto rows = summarize(records);
  writeTextAtomically(directory / "summary.csv", formatSummaryCsv(rows));
  writeTextAtomically(directory / "summary.md", formatSummaryMarkdown(rows, title, renderer));
  writeTextAtomically(directory / "summary.tex", formatSummaryLatex(rows, title, renderer));
  const std::string popping = formatPoppingCsv(rows);
  if (!popping.empty()) writeTextAtomically(directory / "popping.csv", popping);
}

}  // namespace canopy
