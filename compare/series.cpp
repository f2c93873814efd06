#include "compare/series.hpp"

namespace tg::compare {

void measure_series(const Volume<uint32_t>& labels, const measure::ParticleOptions& po, Series& s) {
  measure::ParticleOptions without = po;
  without.contacts = false;
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
