// A small oedometer stage series in memory (data_synth/motion.hpp), for the
// tracker's tests: truth labels, 16-bit grey scans and the truth lineage.
#pragma once
#include <cstdint>
#include <vector>

#include "core/volume.hpp"
#include "data_synth/imaging.hpp"
#include "data_synth/motion.hpp"
#include "data_synth/packing.hpp"
#include "data_synth/render.hpp"
#include "data_synth/truth.hpp"
#include "track/track.hpp"

namespace tg::test {

struct SeriesSpec {
  uint64_t seed = 1;
  int64_t side = 64;        // box edge (y, x), voxels; the volume adds `margin` on each side
  int64_t height = 64;      // specimen height at stage 0, voxels
  int64_t margin = 4;
  double d50 = 18;          // grain diameter, voxels
  double gap = 1.5;         // fragment gap, voxels
  bool grey = false;        // also make the grey scans
  synth::MotionOptions motion{true, 0.04, 5, 0.08, 0.25};
  synth::StageOptions stages;
};

struct Series {
  std::vector<Volume<uint32_t>> labels;
  std::vector<Volume<uint16_t>> grey;
  std::vector<track::LineageRow> lineage;
};

inline Series make_series(const SeriesSpec& sp) {
  synth::StageOptions so = sp.stages;
  so.breakage.seed = sp.seed;
  so.breakage.gap = sp.gap;
  const double emax = so.strains.back();
  synth::PackingOptions po;
  po.container = synth::Container::box;
  po.box_y = po.box_x = static_cast<double>(sp.side);
  po.height = static_cast<double>(sp.height) * (1 - emax);
  po.d50 = sp.d50;
  po.cu = 1.1;
  po.seed = sp.seed;
  const auto pk = synth::dense_packing(po);
  const double m = static_cast<double>(sp.margin), h = 0.5 * static_cast<double>(sp.side);
  std::vector<synth::Particle> grains;
  for (size_t q = 0; q < pk.spheres.size(); ++q) {
    const auto& s = pk.spheres[q];
    grains.push_back(synth::make_grain(static_cast<uint32_t>(q + 1), {s.c[0] + m, s.c[1] + h + m, s.c[2] + h + m}, s.r));
  }
  const Shape shape{sp.height + 2 * sp.margin, sp.side + 2 * sp.margin, sp.side + 2 * sp.margin};
  const Geometry geom = Geometry::isotropic_m(12.3e-6);
  Series out;
  std::vector<std::vector<synth::SeriesParticle>> parts;
  std::vector<Table> truths;
  for (int s = 0; s < static_cast<int>(so.strains.size()); ++s) {
    parts.push_back(synth::oedometer_stage(grains, m, s, so, sp.motion));
    std::vector<synth::Particle> ps;
    for (const auto& x : parts.back()) ps.push_back(x.particle);
    auto r = synth::render(ps, shape, geom);
    truths.push_back(synth::truth_table(ps, r.labels, shape, geom));
    if (sp.grey) {
      synth::ImagingOptions im;
      im.seed = sp.seed * 100 + static_cast<uint64_t>(s);
      synth::apply_imaging(r.solid, im);
      out.grey.push_back(synth::to_u16(r.solid).volume);
    }
    out.labels.push_back(std::move(r.labels));
  }
  out.lineage = track::read_lineage(synth::lineage_truth(parts, truths));
  return out;
}

}  // namespace tg::test
