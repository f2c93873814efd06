#include "data_synth/truth.hpp"

#include <algorithm>
#include <cmath>

#include "core/errors.hpp"

namespace tg::synth {

Table truth_table(const std::vector<Particle>& ps, const Volume<uint32_t>& labels, Shape shape,
                  const Geometry& g) {
  const int64_t n = static_cast<int64_t>(ps.size());
  std::vector<Truth> t(ps.size());
  // Wedges and clusters take milliseconds each: spread over threads; each
  // result lands in its own slot, so the schedule cannot change the table.
#pragma omp parallel for schedule(dynamic, 4)
  for (int64_t q = 0; q < n; ++q) t[q] = particle_truth(ps[q]);

  uint32_t max_id = 0;
  for (const Particle& p : ps) max_id = std::max(max_id, p.id);
  std::vector<int64_t> count(static_cast<size_t>(max_id) + 1, 0);
  for (uint32_t l : labels.span())
    if (l <= max_id) ++count[l];

  Table tab;
  std::vector<double> id, parent, cz, cy, cx, rad, vol, dmax, dmin, dmed, fr, ar, pores, lv, cropped;
  std::vector<std::string> kind;
  for (int64_t q = 0; q < n; ++q) {
    const Particle& p = ps[q];
    id.push_back(p.id);
    kind.emplace_back(kind_name(p.kind));
    parent.push_back(p.parent);
    cz.push_back(t[q].centroid[0]);
    cy.push_back(t[q].centroid[1]);
    cx.push_back(t[q].centroid[2]);
    rad.push_back(t[q].radius);
    vol.push_back(t[q].volume);
    dmax.push_back(t[q].dmax);
    dmin.push_back(t[q].dmin);
    dmed.push_back(t[q].dmed);
    fr.push_back(t[q].fr);
    ar.push_back(t[q].ar);
    pores.push_back(static_cast<double>(p.pores.size()));
    lv.push_back(static_cast<double>(count[p.id]));
    Vec3 lo, hi;
    bounding_box(p, lo, hi);
    const bool inside = lo[0] >= 0 && lo[1] >= 0 && lo[2] >= 0 && hi[0] <= static_cast<double>(shape.nz) &&
                        hi[1] <= static_cast<double>(shape.ny) && hi[2] <= static_cast<double>(shape.nx);
    cropped.push_back(inside ? 0 : 1);
  }
  tab.add("id", id);
  tab.add_text("kind", kind);
  tab.add("parent", parent);
  tab.add("cz_vox", cz);
  tab.add("cy_vox", cy);
  tab.add("cx_vox", cx);
  tab.add("radius_vox", rad);
  tab.add("volume_vox", vol);
  tab.add("dmax_vox", dmax);
  tab.add("dmin_vox", dmin);
  tab.add("dmed_vox", dmed);
  tab.add("fr", fr);
  tab.add("ar", ar);
  tab.add("pores", pores);
  tab.add("label_voxels", lv);
  tab.add("cropped", cropped);
  if (g.has_voxel_size()) {
    if (!g.isotropic()) throw UsageError("truth table: synthetic grids are isotropic");
    const double mm = 1e3 * g.voxel_size_m[0];
    auto phys = [&](const std::vector<double>& v, int axis) {
      std::vector<double> r(v.size());
      for (size_t q = 0; q < v.size(); ++q) r[q] = 1e3 * g.origin_m[axis] + mm * v[q];
      return r;
    };
    auto scale = [&](const std::vector<double>& v, double f) {
      std::vector<double> r(v.size());
      for (size_t q = 0; q < v.size(); ++q) r[q] = f * v[q];
      return r;
    };
    tab.add("cz_mm", phys(cz, 0));
    tab.add("cy_mm", phys(cy, 1));
    tab.add("cx_mm", phys(cx, 2));
    tab.add("radius_mm", scale(rad, mm));
    tab.add("volume_mm3", scale(vol, mm * mm * mm));
    tab.add("dmax_mm", scale(dmax, mm));
    tab.add("dmin_mm", scale(dmin, mm));
    tab.add("dmed_mm", scale(dmed, mm));
  }
  tab.source = "truth";
  return tab;
}

}  // namespace tg::synth
