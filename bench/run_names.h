#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace canopy {

struct SummaryRow;

// What file-system name a tree or variant label gets (its images/ and assets/ folders):
// letters, digits and _ . = , - are kept, anything else becomes '_'.
std::string safeName(const std::string& label);

// DIR/names.json: {"trees": {label: name}, "variants": {label: name}} for the rows' labels, so
// scripts (paper_figures/make_figures.py) read the names instead of deriving them again.
void writeRunNames(const std::filesystem::path& directory, const std::vector<SummaryRow>& rows);

}  // namespace canopy
