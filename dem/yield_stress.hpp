// Yield stress of an oedometer curve (the study's "yielding near 2 MPa"):
// the stress where the compression curve turns from its stiff to its soft
// branch in the e–log σ plane. Strain stands in for the void ratio (in an
// oedometer e is linear in strain while the solids' volume is constant).
// Used by the study summary (study/summary.cpp) and the calibration
// objective (dem/calibration/objective.cpp): one rule, one place.
#pragma once
#include <vector>

namespace tg::dem {

// The intersection of two straight lines fitted (least squares) to strain
// against log10(stress) over the points above `floor_mpa`, split where the two
// fits leave the least residual (each side at least 3 points) among the
// splits where the second line is at least 1.5 times as steep as the first
// (a knee: compression steepens past yield); only the curve up to each new
// peak counts (unloading and drops are left out). NaN when fewer than 6
// points qualify, or no such split's lines meet within the fitted stresses
// (a straight line, a curve that only stiffens). Stresses in MPa.
double yield_stress_mpa(const std::vector<double>& strain, const std::vector<double>& stress_mpa,
                        double floor_mpa = 0.1);

}  // namespace tg::dem
