#include "compare/series.hpp"

#include "core/errors.hpp"
#include "segmentation/threshold.hpp"

namespace tg::compare {

void measure_series(const Volume<uint32_t>& labels, const measure::ParticleOptions& po, Series& s,
                    const Volume<uint16_t>* grey) {
  measure::ParticleOptions without = po;
  without.contacts = false;
  VolumeView<const uint16_t> grey_view;
  PhaseLevels levels;
  bool levels_found = false;
  if (grey) {
    try {
      levels = phase_levels(histogram_u16(*grey));
      levels_found = levels.solid > levels.void_level;
    } catch (const InputError&) {  // one grey level: the label volumes, as without a scan
    }
  }
  if (levels_found) {
    grey_view = grey->view();
    without.grey = &grey_view;
    without.grey_levels.void_grey = levels.void_level;
    without.grey_levels.solid_grey = levels.solid;
    s.info["volume_from"] = "grey";
  }
  std::vector<measure::Particle> ps = measure::measure_particles(labels.view(), without);
  if (po.contacts) {  // what measure_particles does with contacts on, keeping the contacts themselves
    measure::ContactOptions co = po.contact;
    co.threads = po.threads;
    const measure::ContactResult res = measure::find_contacts(labels.view(), co);
    std::vector<uint32_t> ids;
    for (const auto& p : ps) ids.push_back(p.stats.label);
    const std::vector<int> z = measure::coordination(res.contacts, ids);
    for (size_t p = 0; p < ps.size(); ++p) ps[p].coordination = z[p];
    std::vector<std::pair<int64_t, int64_t>> pairs;
    std::vector<Eigen::Vector3d> normals;
    for (const auto& c : res.contacts) {
      pairs.emplace_back(c.a, c.b);
      normals.push_back(c.normal);
    }
    s.contacts = contact_series(pairs, normals);
  }
  s.particles = measure::particle_table(ps);
  s.sample = measure::grading_sample(s.particles);
  s.coordination = mean_interior_coordination(s.particles);
  s.contacts.by_size = coordination_by_size(s.particles);
}

}  // namespace tg::compare
