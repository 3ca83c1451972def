#include "bench/report.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include <fmt/format.h>

#include "bench/run_names.h"
#include "common/atomic_file.h"

namespace canopy {
namespace {

const double kNan = std::nan("");

struct Mean {
  double sum = 0;
  int count = 0;
  void add(double v) {
    if (std::isfinite(v)) {
      sum += v;
      ++count;
    }
  }
  double value() const { return count ? sum / count : kNan; }
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

double mb(double bytes) {
  return bytes / 1e6;
}

template <typename Rows, typename Get>
std::vector<double> collectKeys(const Rows& rows, Get get) {
  std::set<double> keys;
  for (const auto& row : rows)
    for (const auto& [key, value] : get(row)) keys.insert(key);
  return {keys.begin(), keys.end()};
}

std::vector<double> distancesOf(const std::vector<SummaryRow>& rows) {
  return collectKeys(rows, [](const SummaryRow& r) { return r.psnrByDistance; });
}

std::vector<double> elevationsOf(const std::vector<SummaryRow>& rows) {
  return collectKeys(rows, [](const SummaryRow& r) { return r.psnrByElevation; });
}

double lookup(const std::vector<std::pair<double, double>>& pairs, double key) {
  for (const auto& [k, v] : pairs)
    if (k == key) return v;
  return kNan;
}

const ForestRecord* forestOfSize(const SummaryRow& row, int size) {
  for (const ForestRecord& f : row.forests)
    if (f.trees == size) return &f;
  return nullptr;
}

std::vector<int> forestSizes(const std::vector<SummaryRow>& rows) {
  std::set<int> sizes;
  for (const SummaryRow& row : rows)
    for (const ForestRecord& f : row.forests) sizes.insert(f.trees);
  return {sizes.begin(), sizes.end()};
}

const PoppingRecord* poppingOf(const SummaryRow& row, const std::string& path) {
  for (const PoppingRecord& p : row.popping)
    if (p.path == path) return &p;
  return nullptr;
}

std::vector<std::string> poppingPaths(const std::vector<SummaryRow>& rows) {
  std::set<std::string> paths;
  for (const SummaryRow& row : rows)
    for (const PoppingRecord& p : row.popping) paths.insert(p.path);
  return {paths.begin(), paths.end()};
}

const BudgetRecord* budgetOf(const SummaryRow& row) {
  return row.bake && row.bake->budget ? &*row.bake->budget : nullptr;
}

bool anyCloseupIn(const std::vector<SummaryRow>& rows) {
  for (const SummaryRow& row : rows)
    if (row.closeupViews > 0) return true;
  return false;
}

// Fields of a row's bake record as numbers, NaN without one.
double bakeSeconds(const SummaryRow& row) {
  return row.bake ? row.bake->bakeSeconds : kNan;
}
double memoryMb(const SummaryRow& row) {
  return row.bake ? mb(double(row.bake->memory.total)) : kNan;
}
double diskMb(const SummaryRow& row) {
  return row.bake && row.bake->diskBytes ? mb(double(*row.bake->diskBytes)) : kNan;
}

// A forest record's fragment-shader invocations per pixel of its frame.
double forestFragmentsPerPixel(const ForestRecord* forest) {
  if (!forest) return kNan;
  return double(forest->drawn.fragments) / (double(forest->resolution[0]) * forest->resolution[1]);
}

double forestLeafFraction(const ForestRecord* forest) {
  return forest ? forest->drawn.leafGeometryFraction : kNan;
}

// The interquartile range of a forest's per-block speedups: (q25, q75).
std::pair<double, double> speedupSpread(const ForestRecord* forest) {
  if (!forest || !forest->speedupSpread) return {kNan, kNan};
  return {(*forest->speedupSpread)[0], (*forest->speedupSpread)[1]};
}

// "2.95× [2.80–3.10]": a speedup with its interquartile range, "–" without one.
std::string speedupText(const ForestRecord* forest) {
  const double speedup = forest ? forest->speedupVsPolygonal : kNan;
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
  result.reserve(keys.size());
  for (const T& key : keys) result.push_back(fmt::format(fmt::runtime(format), key));
  return result;
}

// The per-row sums summarize() turns into means.
struct Accumulator {
  Mean psnr, psnrFrame, ssim, coverage, flip, psnrCloseup, flipCloseup, ssimCloseup;
  Mean primitives, fragmentsPerPixel, leafFraction;
  std::map<double, Mean> byDistance, byElevation;
};

void addView(SummaryRow& row, Accumulator& acc, const ViewRecord& view) {
  if (view.ring == "closeup") {
    acc.psnrCloseup.add(view.psnr);
    acc.flipCloseup.add(view.flip);
    acc.ssimCloseup.add(view.ssim);
    ++row.closeupViews;
    return;
  }
  acc.psnr.add(view.psnr);
  acc.psnrFrame.add(view.psnrFrame);
  acc.ssim.add(view.ssim);
  acc.coverage.add(view.coverageError);
  acc.flip.add(view.flip);
  const double s = view.supersample, pixels = double(view.resolution[0]) * view.resolution[1];
  acc.primitives.add(double(view.drawn.primitives));
  acc.fragmentsPerPixel.add(double(view.drawn.fragments) / (s * s * pixels));
  acc.leafFraction.add(view.drawn.leafGeometryFraction);
  acc.byDistance[view.distance].add(view.psnr);
  // Capture views have no elevation (the capture's up axis is its own).
  if (view.elevation) acc.byElevation[*view.elevation].add(view.psnr);
  ++row.views;
}

void finishRow(SummaryRow& row, const Accumulator& acc) {
  row.psnr = acc.psnr.value();
  row.psnrFrame = acc.psnrFrame.value();
  row.ssim = acc.ssim.value();
  row.coverageError = acc.coverage.value();
  row.flip = acc.flip.value();
  row.psnrCloseup = acc.psnrCloseup.value();
  row.flipCloseup = acc.flipCloseup.value();
  row.ssimCloseup = acc.ssimCloseup.value();
  row.primitives = acc.primitives.value();
  row.fragmentsPerPixel = acc.fragmentsPerPixel.value();
  row.leafGeometryFraction = acc.leafFraction.value();
  for (const auto& [d, m] : acc.byDistance) row.psnrByDistance.emplace_back(d, m.value());
  for (const auto& [e, m] : acc.byElevation) row.psnrByElevation.emplace_back(e, m.value());
  std::sort(row.forests.begin(), row.forests.end(),
            [](const ForestRecord& a, const ForestRecord& b) { return a.trees < b.trees; });
}

// The record's effective parameters, for the kinds that carry them.
nlohmann::json paramsOf(const Record& record) {
  return std::visit(
      [](const auto& r) -> nlohmann::json {
        if constexpr (requires { r.params; })
          return r.params;
        else
          return nlohmann::json::object();
      },
      record);
}

}  // namespace

std::vector<SummaryRow> summarize(const std::vector<Record>& records) {
  std::vector<SummaryRow> rows;
  std::vector<Accumulator> accumulators;
  std::map<std::pair<std::string, std::string>, size_t> index;
  for (const Record& record : records) {
    if (recordAs<TreeRecord>(record)) continue;
    const VariantFields names = variantOf(record);
    auto [it, inserted] = index.try_emplace({names.tree, names.variant}, rows.size());
    if (inserted) {
      rows.push_back({names.tree, names.method, names.variant, paramsOf(record)});
      accumulators.emplace_back();
    }
    SummaryRow& row = rows[it->second];
    if (const auto* bake = recordAs<BakeRecord>(record)) {
      row.bake = *bake;
      row.params = bake->params;
    } else if (const auto* view = recordAs<ViewRecord>(record)) {
      addView(row, accumulators[it->second], *view);
    } else if (const auto* forest = recordAs<ForestRecord>(record)) {
      row.forests.push_back(*forest);
    } else if (const auto* popping = recordAs<PoppingRecord>(record)) {
      row.popping.push_back(*popping);
    } else if (const auto* skip = recordAs<SkipRecord>(record)) {
      row.skipped = skip->reason;
    }
  }
  for (size_t i = 0; i < rows.size(); ++i) finishRow(rows[i], accumulators[i]);
  return rows;
}

std::string formatPoppingCsv(const std::vector<SummaryRow>& rows) {
  std::string out;
  for (const SummaryRow& row : rows) {
    for (const PoppingRecord& p : row.popping) {
      for (size_t i = 0; i < p.distance.size(); ++i) {
        out += fmt::format("{},{},{},{},{},{},{},{},{},{}\n", csvField(row.tree),
                           csvField(row.variant), p.path, i, p.distance[i], p.psnrFrame[i],
                           p.change[i], p.referenceChange[i], p.temporalExcess[i],
                           p.lodSwitch[i] ? 1 : 0);
      }
    }
  }
  if (out.empty()) return out;
  return "tree,variant,path,frame,distance,psnr,change,reference_change,temporal_excess,"
         "lod_switch\n" +
         out;
}

namespace {

std::string csvHeader(const std::vector<double>& distances, const std::vector<double>& elevations,
                      const std::vector<int>& sizes, const std::vector<std::string>& paths) {
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
  for (const std::string& path : paths)
    out += fmt::format(",popping_{0}_peak,popping_{0}_mean,popping_{0}_switches", path);
  return out + ",budget_parameter,budget_value,budget_reached,skipped\n";
}

// The row's bake, memory, quality and drawn fields, as formatSummaryCsv lays them out.
std::string csvQuality(const SummaryRow& row) {
  const std::optional<BakeRecord>& bake = row.bake;
  std::string out = csvField(row.tree) + "," + csvField(row.method) + "," + csvField(row.variant) +
                    "," + csvField(row.params.dump());
  out += "," + number(bakeSeconds(row), 4);
  out += "," + number(bake ? mb(double(bake->bakePeakRssBytes)) : kNan, 2);
  for (const uint64_t bytes : {bake ? bake->memory.texture : 0, bake ? bake->memory.geometry : 0,
                               bake ? bake->memory.other : 0, bake ? bake->memory.total : 0})
    out += "," + number(bake ? mb(double(bytes)) : kNan, 4);
  out += "," + number(diskMb(row), 4);
  out += fmt::format(",{}", row.views);
  out += "," + number(row.psnr, 3) + "," + number(row.psnrFrame, 3) + "," + number(row.ssim, 4) +
         "," + number(row.coverageError, 5) + "," + number(row.flip, 4);
  out += fmt::format(",{}", row.closeupViews) + "," + number(row.psnrCloseup, 3) + "," +
         number(row.flipCloseup, 4) + "," + number(row.ssimCloseup, 4);
  out += "," + number(row.primitives, 0) + "," + number(row.fragmentsPerPixel, 4) + "," +
         number(row.leafGeometryFraction, 4);
  return out;
}

std::string csvForest(const ForestRecord* f) {
  const auto [q25, q75] = speedupSpread(f);
  const auto field = [&](double ForestRecord::*member) { return f ? f->*member : kNan; };
  return "," + number(field(&ForestRecord::frameMsMedian), 3) + "," +
         number(field(&ForestRecord::frameMsP95), 3) + "," + number(field(&ForestRecord::fps), 3) +
         "," + number(field(&ForestRecord::speedupVsPolygonal), 3) + "," + number(q25, 3) + "," +
         number(q75, 3) + "," + number(field(&ForestRecord::psnr), 3) + "," +
         number(field(&ForestRecord::flip), 4) + "," +
         number(field(&ForestRecord::coverageError), 5) + "," +
         number(forestFragmentsPerPixel(f), 4) + "," + number(forestLeafFraction(f), 4);
}

std::string csvPopping(const PoppingRecord* p) {
  return "," + number(p ? p->peakExcess : kNan, 3) + "," + number(p ? p->meanExcess : kNan, 3) +
         "," + number(p ? double(p->switches) : kNan, 0);
}

}  // namespace

std::string formatSummaryCsv(const std::vector<SummaryRow>& rows) {
  const auto distances = distancesOf(rows);
  const auto elevations = elevationsOf(rows);
  const auto sizes = forestSizes(rows);
  const auto paths = poppingPaths(rows);
  std::string out = csvHeader(distances, elevations, sizes, paths);
  for (const SummaryRow& row : rows) {
    out += csvQuality(row);
    for (double d : distances) out += "," + number(lookup(row.psnrByDistance, d), 3);
    for (double e : elevations) out += "," + number(lookup(row.psnrByElevation, e), 3);
    for (int n : sizes) out += csvForest(forestOfSize(row, n));
    for (const std::string& path : paths) out += csvPopping(poppingOf(row, path));
    const BudgetRecord* budget = budgetOf(row);
    out += budget ? fmt::format(",{},{},{}", budget->parameter, budget->value.dump(),
                                budget->reached ? 1 : 0)
                  : ",,,";
    out += "," + csvField(row.skipped) + "\n";
  }
  return out;
}

namespace {

std::string qualityTable(const std::vector<SummaryRow>& rows) {
  const auto distances = distancesOf(rows);
  const bool closeups = anyCloseupIn(rows);
  std::vector<std::string> quality = {"bake s", "memory MB", "disk MB",     "PSNR",
                                      "FLIP",   "SSIM",      "coverage err"};
  for (const std::string& label : labels(distances, "PSNR @{:g}r")) quality.push_back(label);
  if (closeups) {
    quality.emplace_back("PSNR close-up");
    quality.emplace_back("FLIP close-up");
  }
  std::string out =
      "## Quality, memory and bake\n\nPSNR, FLIP, SSIM and coverage error are means over the "
      "orbit rings' views; the close-up ring (a narrow field of view, leaves tens of pixels "
      "wide) has its own columns.\n\n" +
      markdownHeader({"tree", "method"}, quality);
  for (const SummaryRow& row : rows) {
    out += fmt::format("| {} | {} | {} | {} | {} | {} | {} | {} | {} |", row.tree, row.variant,
                       number(bakeSeconds(row), 2), number(memoryMb(row), 2),
                       number(diskMb(row), 2), number(row.psnr, 2), number(row.flip, 3),
                       number(row.ssim, 3), number(row.coverageError, 4));
    for (double d : distances) out += " " + number(lookup(row.psnrByDistance, d), 2) + " |";
    if (closeups)
      out += " " + number(row.psnrCloseup, 2) + " | " + number(row.flipCloseup, 3) + " |";
    out += "\n";
  }
  return out;
}

std::string drawnTable(const std::vector<SummaryRow>& rows) {
  const auto sizes = forestSizes(rows);
  std::vector<std::string> columns = {"primitives / view", "fragments / px", "leaf polygons %"};
  for (int n : sizes) {
    columns.push_back(fmt::format("fragments / px, {} trees", n));
    columns.push_back(fmt::format("leaf polygons %, {} trees", n));
  }
  std::string out =
      "\n## What was drawn\n\nGL query counts of the orbit views (fragment-shader "
      "invocations per output pixel, supersampling divided out) and of the forests' scored "
      "frames; leaf polygons: the share of the tree's leaves drawn as leaf polygons (100 % for "
      "the reference, 0 % for a pure impostor).\n\n" +
      markdownHeader({"tree", "method"}, columns);
  for (const SummaryRow& row : rows) {
    out +=
        fmt::format("| {} | {} | {} | {} | {} |", row.tree, row.variant, number(row.primitives, 0),
                    number(row.fragmentsPerPixel, 2), number(100.0 * row.leafGeometryFraction, 1));
    for (int n : sizes) {
      const ForestRecord* f = forestOfSize(row, n);
      out += " " + number(forestFragmentsPerPixel(f), 2) + " | " +
             number(100.0 * forestLeafFraction(f), 1) + " |";
    }
    out += "\n";
  }
  return out;
}

std::string poppingTable(const std::vector<SummaryRow>& rows) {
  const auto paths = poppingPaths(rows);
  if (paths.empty()) return "";
  std::vector<std::string> columns;
  for (const std::string& path : paths) {
    columns.push_back(path + " peak");
    columns.push_back(path + " mean");
    columns.push_back(path + " LoD switches");
  }
  std::string out = "\n## Popping (temporal error in excess of the reference's, 8-bit RMS)\n\n" +
                    markdownHeader({"tree", "method"}, columns);
  for (const SummaryRow& row : rows) {
    if (row.popping.empty()) continue;
    out += fmt::format("| {} | {} |", row.tree, row.variant);
    for (const std::string& path : paths) {
      const PoppingRecord* p = poppingOf(row, path);
      out += " " + number(p ? p->peakExcess : kNan, 2) + " | " +
             number(p ? p->meanExcess : kNan, 2) + " | " +
             number(p ? double(p->switches) : kNan, 0) + " |";
    }
    out += "\n";
  }
  return out;
}

std::string budgetTable(const std::vector<SummaryRow>& rows) {
  bool anyBudget = false;
  for (const SummaryRow& row : rows) anyBudget = anyBudget || budgetOf(row);
  if (!anyBudget) return "";
  std::string out = "\n## Budget (each method's memory knob set by bisection)\n\n" +
                    markdownHeader({"tree", "method", "parameter", "reached"},
                                   {"value", "target", "memory MB", "PSNR", "bakes"});
  for (const SummaryRow& row : rows) {
    const BudgetRecord* b = budgetOf(row);
    if (!b) continue;
    out += fmt::format("| {} | {} | {} | {} | {} | {} {} | {} | {} | {} |\n", row.tree, row.variant,
                       b->parameter, b->reached ? "yes" : "no", b->value.dump(),
                       number(b->target, 2), b->mode == "memory_mb" ? "MB" : "dB",
                       number(memoryMb(row), 2), number(row.psnr, 2), number(double(b->steps), 0));
  }
  return out;
}

std::string skippedLine(const std::vector<SummaryRow>& rows) {
  std::string out;
  for (const SummaryRow& row : rows)
    if (!row.skipped.empty())
      out += fmt::format("{} on {} ({}); ", row.variant, row.tree, row.skipped);
  return out.empty() ? "" : "\nSkipped: " + out + "\n";
}

std::string elevationTable(const std::vector<SummaryRow>& rows) {
  const auto elevations = elevationsOf(rows);
  if (elevations.empty()) return "";
  std::string out = "\n## PSNR by elevation\n\n" +
                    markdownHeader({"tree", "method"}, labels(elevations, "{:g}°"));
  for (const SummaryRow& row : rows) {
    out += fmt::format("| {} | {} |", row.tree, row.variant);
    for (double e : elevations) out += " " + number(lookup(row.psnrByElevation, e), 2) + " |";
    out += "\n";
  }
  return out;
}

// One table with a cell per forest size, `cell` giving its text (for a present record).
template <typename Cell>
std::string forestTable(const std::vector<SummaryRow>& rows, const std::string& heading,
                        Cell cell) {
  const auto sizes = forestSizes(rows);
  std::string out = heading + markdownHeader({"tree", "method"}, labels(sizes, "{} trees"));
  for (const SummaryRow& row : rows) {
    out += fmt::format("| {} | {} |", row.tree, row.variant);
    for (int n : sizes) out += cell(forestOfSize(row, n));
    out += "\n";
  }
  return out;
}

std::string forestTables(const std::vector<SummaryRow>& rows) {
  if (forestSizes(rows).empty()) return "";
  std::string out = forestTable(
      rows,
      "\n## Frame time by forest size\n\nMedian ms / FPS / speedup vs polygonal: reference "
      "and method timed in turn on each camera of the path in the same run; the speedup "
      "summarizes the per-camera ratios (their geometric mean in runs after 1fe1cdd, their "
      "median before: results/README.md) with their interquartile range.\n\n",
      [](const ForestRecord* f) {
        return f ? fmt::format(" {} / {} / {} |", number(f->frameMsMedian, 1), number(f->fps, 1),
                               speedupText(f))
                 : std::string(" |");
      });
  out += forestTable(
      rows, "\n## Forest frames against the reference's (PSNR over the frame / FLIP)\n\n",
      [](const ForestRecord* f) {
        return f && std::isfinite(f->flip)
                   ? fmt::format(" {} / {} |", number(f->psnr, 2), number(f->flip, 3))
                   : std::string(" |");
      });
  return out;
}

}  // namespace

std::string formatSummaryMarkdown(const std::vector<SummaryRow>& rows, const std::string& title,
                                  const std::string& renderer) {
  std::string out = fmt::format(
      "# {}\n\nRenderer: `{}`. PSNR in dB over the union of coverage masks "
      "(capped at 100 dB for identical images); memory from the GPU ledger.\n\n",
      title, renderer);
  return out + qualityTable(rows) + drawnTable(rows) + poppingTable(rows) + budgetTable(rows) +
         skippedLine(rows) + elevationTable(rows) + forestTables(rows);
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
  const auto distances = distancesOf(rows);
  const auto sizes = forestSizes(rows);
  const bool closeups = anyCloseupIn(rows);
  const size_t numbers = 2 + distances.size() + (closeups ? 1 : 0) + 3 + sizes.size();
  std::string out = "% Generated by canopy-bench; needs \\usepackage{booktabs}.\n";
  out += "\\begin{table}\n\\centering\n\\small\n\\begin{tabular}{ll" + std::string(numbers, 'r') +
         "}\n\\toprule\n";
  out += "Tree & Method & Bake (s) & Memory (MB)";
  for (double d : distances) out += fmt::format(" & PSNR@{:g}r", d);
  if (closeups) out += " & PSNR close-up";
  out += " & SSIM & FLIP & Cov.\\ err.";
  for (int n : sizes) out += fmt::format(" & Speedup@{}", n);
  out += " \\\\\n\\midrule\n";
  for (const SummaryRow& row : rows) {
    out += latexEscape(row.tree) + " & " + latexEscape(row.variant) + " & " +
           number(bakeSeconds(row), 2) + " & " + number(memoryMb(row), 2);
    for (double d : distances) out += " & " + number(lookup(row.psnrByDistance, d), 2);
    if (closeups) out += " & " + number(row.psnrCloseup, 2);
    out += " & " + number(row.ssim, 3) + " & " + number(row.flip, 3) + " & " +
           number(row.coverageError, 3);
    for (int n : sizes) {
      const ForestRecord* f = forestOfSize(row, n);
      out += " & " + number(f ? f->speedupVsPolygonal : kNan, 2);
    }
    out += " \\\\\n";
  }
  out += "\\bottomrule\n\\end{tabular}\n";
  out += "\\caption{" + latexEscape(title) +
         ": PSNR in dB over the union of coverage masks, LDR-FLIP (mean over the frame), memory "
         "from the GPU ledger, speedup = polygonal / method frame time per camera, timed in turn "
         "in the same run, summarized over the camera path. Renderer: " +
         latexEscape(renderer) + ".}\n\\end{table}\n";
  return out;
}

namespace {

// The main table's header: which columns this tree's rows fill.
struct MainColumns {
  std::vector<double> distances;
  int largest = 0;  // the largest forest, 0 without forests
  bool closeups = false, popping = false;
};

MainColumns mainColumns(const std::vector<SummaryRow>& rows) {
  MainColumns c;
  c.distances = distancesOf(rows);
  const auto sizes = forestSizes(rows);
  c.largest = sizes.empty() ? 0 : sizes.back();
  c.closeups = anyCloseupIn(rows);
  for (const SummaryRow& row : rows) c.popping = c.popping || poppingOf(row, "dolly");
  return c;
}

std::string mainRow(const SummaryRow& row, const MainColumns& c) {
  std::string byRing;
  for (double d : c.distances)
    byRing += (byRing.empty() ? "" : " / ") + number(lookup(row.psnrByDistance, d), 1);
  std::string out =
      fmt::format("| `{}` | {} | {} | {} | {} | {} |", row.variant, number(memoryMb(row), 2),
                  number(bakeSeconds(row), 2), number(row.psnr, 2), number(row.flip, 3), byRing);
  if (c.closeups)
    out += " " + number(row.psnrCloseup, 1) + " / " + number(row.flipCloseup, 3) + " |";
  out += " " + number(100.0 * row.leafGeometryFraction, 0) + " % |";
  if (c.largest > 0) {
    const ForestRecord* f = forestOfSize(row, c.largest);
    out += " " + speedupText(f) + " | " + number(f ? f->flip : kNan, 3) + " |";
  }
  if (c.popping) {
    const PoppingRecord* p = poppingOf(row, "dolly");
    out += " " + number(p ? p->peakExcess : kNan, 2) + " |";
  }
  return out + "\n";
}

}  // namespace

std::string formatMainTable(const std::vector<SummaryRow>& rows, const std::string& renderer) {
  const std::string tree = rows.front().tree;
  std::vector<SummaryRow> subset;
  for (const SummaryRow& row : rows)
    if (row.tree == tree) subset.push_back(row);
  const MainColumns c = mainColumns(subset);
  std::string rings;
  for (double d : c.distances) rings += (rings.empty() ? "" : " / ") + fmt::format("{:g}r", d);
  std::vector<std::string> columns = {"GPU memory (MB)", "bake (s)", "PSNR (dB)", "FLIP",
                                      "PSNR @" + rings};
  if (c.closeups) columns.emplace_back("close-up PSNR / FLIP");
  columns.emplace_back("leaf polygons");
  if (c.largest > 0) {
    columns.push_back(fmt::format("speedup, {} trees [IQR]", c.largest));
    columns.push_back(fmt::format("forest FLIP, {} trees", c.largest));
  }
  if (c.popping) columns.emplace_back("popping peak (dolly)");
  std::string out =
      fmt::format("{} (renderer: {})\n\n", tree, renderer) + markdownHeader({"method"}, columns);
  for (const SummaryRow& row : subset) out += mainRow(row, c);
  return out;
}

void writeSummaries(const std::filesystem::path& directory, const std::vector<Record>& records,
                    const std::string& title, const std::string& renderer) {
  const auto rows = summarize(records);
  writeTextAtomically(directory / "summary.csv", formatSummaryCsv(rows));
  writeTextAtomically(directory / "summary.md", formatSummaryMarkdown(rows, title, renderer));
  writeTextAtomically(directory / "summary.tex", formatSummaryLatex(rows, title, renderer));
  const std::string popping = formatPoppingCsv(rows);
  if (!popping.empty()) writeTextAtomically(directory / "popping.csv", popping);
  writeRunNames(directory, rows);
}

}  // namespace canopy
