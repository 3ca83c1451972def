#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "bench/records.h"

namespace canopy {

// One row per tree × method variant, aggregated from the records of metrics.jsonl.
struct SummaryRow {
  std::string tree;
  std::string method;
  std::string variant;
  nlohmann::json params;           // effective
  std::optional<BakeRecord> bake;  // absent when the run has none
  // Means over the views of the orbit rings (or a capture's test views); the close-up ring has
  // its own means below, as its narrow field of view makes it another measurement.
  double psnr = 0, psnrFrame = 0, ssim = 0, coverageError = 0, flip = 0;
  int views = 0;
  double psnrCloseup = 0, flipCloseup = 0, ssimCloseup = 0;  // NaN without a close-up ring
  int closeupViews = 0;
  // What the views drew (means over the orbit views): primitives, fragment-shader invocations
  // per output pixel (÷ supersample² · width · height) and the share of leaves drawn as polygons.
  double primitives = 0, fragmentsPerPixel = 0, leafGeometryFraction = 0;
  std::vector<std::pair<double, double>> psnrByDistance;   // (distance, mean PSNR)
  std::vector<std::pair<double, double>> psnrByElevation;  // (elevation, mean PSNR)
  std::vector<ForestRecord> forests;                       // by size
  std::vector<PoppingRecord> popping;                      // dolly, orbit
  std::string skipped;  // why the method did not run on this tree (kind:"skip"), else empty
};

std::vector<SummaryRow> summarize(const std::vector<Record>& records);

// One line per frame of every popping record: tree, variant, path, frame, distance, psnr,
// change, reference_change, temporal_excess, lod_switch (0/1). Empty when there are none.
std::string formatPoppingCsv(const std::vector<SummaryRow>& rows);

std::string formatSummaryCsv(const std::vector<SummaryRow>& rows);
std::string formatSummaryMarkdown(const std::vector<SummaryRow>& rows, const std::string& title,
                                  const std::string& renderer);

// The README's main table for the first tree of the rows: memory, bake, quality on the orbit
// rings and the close-ups, what was drawn, and speed at the largest forest (median and IQR of
// interleaved per-frame ratios) with its forest-frame FLIP.
std::string formatMainTable(const std::vector<SummaryRow>& rows, const std::string& renderer);

// A booktabs table for a paper: per tree and method, bake time, memory, PSNR by distance ring,
// the close-up PSNR, SSIM, FLIP, coverage error and the speedup by forest size. Text is escaped
// for LaTeX.
std::string formatSummaryLatex(const std::vector<SummaryRow>& rows, const std::string& title,
                               const std::string& renderer);

// Writes summary.csv, summary.md and summary.tex (and popping.csv, names.json) into `directory`
// atomically.
void writeSummaries(const std::filesystem::path& directory, const std::vector<Record>& records,
                    const std::string& title, const std::string& renderer);

}  // namespace canopy
