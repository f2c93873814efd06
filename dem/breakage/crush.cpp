#include "dem/breakage/crush.hpp"

#include <cmath>
#include <memory>

#include "core/errors.hpp"

namespace tg::dem::breakage {

CrushResult run_crush(const CrushOptions& opt) {
  if (!(opt.diameter_m > 0) || !(opt.platen_speed_m_s > 0) || !(opt.final_travel_fraction > 0 && opt.final_travel_fraction < 0.9))
    throw InputError("dem crush: diameter and platen speed must be positive, final travel in (0, 0.9) of d");
  const double r = 0.5 * opt.diameter_m;
  Particles p;
  p.append_sphere(0, 0, r, r, opt.engine.material.density_kg_m3, 0, 0, kFlagBreakable);
  EngineOptions eo = opt.engine;
  eo.gravity_z = 0;
  eo.walls.bottom = true;
  eo.walls.top = true;
  eo.walls.top_z = 2 * r;
  eo.walls.top_vz = -opt.platen_speed_m_s;
  eo.walls.cylinder = false;
  eo.skin = 0.1 * r;
  const HertzMindlin law = make_hertz_mindlin(eo.material, eo.material, eo.friction, 1.0);
  eo.time_step = opt.time_step_s > 0 ? opt.time_step_s : 0.2 * std::sqrt(p.m[0] / law.normal_stiffness(0.05 * r, r));
  Engine eng(p, eo);

  CrushResult res;
  res.time_step_initial_s = eo.time_step;
  std::unique_ptr<BreakageModel> model;
  if (opt.breakage_on) {
    model = std::make_unique<BreakageModel>(eng, opt.breakage);
    res.strength_Pa = model->strength(0);
  }
  const double final_travel = opt.final_travel_fraction * opt.diameter_m;
  const int64_t every = std::max<int64_t>(1, opt.history_every);
  auto travel = [&] { return 2 * r - eng.walls().top_z; };
  while (travel() < final_travel) {
    eng.step();
    if (model && model->check_due()) model->check();
    if (eng.step_count() % every == 0) {
      CrushRow row{eng.step_count(), eng.time(), travel(), eng.wall_forces().top_z, {}};
      if (model) row.record = model->record();
      res.history.push_back(row);
    }
  }
  res.time_step_final_s = eng.options().time_step;
  if (model) {
    res.splits = model->events();
    res.final_record = model->record();
  }
  return res;
}

}  // namespace tg::dem::breakage
