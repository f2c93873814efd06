// A study's key figures in one row per comparison (one row without a DEM):
// DIR/summary/summary.csv, what a campaign collects (workflow/scripts/
// campaign_summary.py). Read from the files the other steps wrote.
#pragma once
#include <filesystem>
#include <vector>

#include "dem/yield_stress.hpp"
#include "study/study.hpp"

namespace tg::study {

// The yield rule lives with the DEM (dem/yield_stress.hpp); the summary uses it.
using dem::yield_stress_mpa;

void write_summary(const Study& s, const Plan& p, const std::filesystem::path& out_csv);

}  // namespace tg::study
