// A study's key figures in one row per comparison (one row without a DEM):
// DIR/summary/summary.csv, what a campaign collects (workflow/scripts/
// campaign_summary.py). Read from the files the other steps wrote.
#pragma once
#include <filesystem>
#include <vector>

#include "study/study.hpp"

namespace tg::study {

// Yield stress of an oedometer curve: the intersection of two straight lines
// fitted (least squares) to strain against log10(stress) over the points above
// `floor_mpa`, split where the two fits leave the least residual (each side at
// least 3 points). NaN when fewer than 6 points qualify or no split's lines
// meet within the fitted stresses.
double yield_stress_mpa(const std::vector<double>& strain, const std::vector<double>& stress_mpa,
                        double floor_mpa = 0.1);

void write_summary(const Study& s, const Plan& p, const std::filesystem::path& out_csv);

}  // namespace tg::study
