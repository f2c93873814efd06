#include "dem/pluviation.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "core/errors.hpp"
#include "core/progress.hpp"
#include "dem/time_step.hpp"

namespace tg::dem {

double sigma_from_cu(double d50, double cu) { return (cu - 1) * d50 / (0.2533 + 1.2816 * cu); }

Particles insert_grains(const PluviationOptions& o, double density) {
  if (!(o.d50_m > 0) || !(o.cu >= 1) || !(o.cylinder_radius_m > o.d50_m) || !(o.generation_height_m > o.d50_m) ||
      !(o.target_porosity > 0 && o.target_porosity < 1) || !(o.target_height_m > 0))
    throw InputError("pluviation: need d50 > 0, cu >= 1, cylinder and heights larger than d50, porosity in (0, 1)");
  const double sigma = sigma_from_cu(o.d50_m, o.cu);
  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> nd(o.d50_m, sigma);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double pi = std::numbers::pi, R = o.cylinder_radius_m;
  const double v_target = (1 - o.target_porosity) * pi * R * R * o.target_height_m;
  Particles p;
  double v = 0;
  int64_t tries = 0;
  while (v < v_target) {
    double d = nd(rng);
    while (std::abs(d - o.d50_m) > 3 * sigma) d = nd(rng);  // truncate at ±3σ
    const double r = d / 2;
    for (;;) {
      if (++tries > o.max_insert_tries)
        throw InputError("pluviation: could not place grain " + std::to_string(p.size()) +
                         " without overlap; the generation cylinder is too small for the target volume");
      const double x = u(rng) * (R - r), y = u(rng) * (R - r);
      if (x * x + y * y > (R - r) * (R - r)) continue;
      const double z = r + 0.5 * (u(rng) + 1) * (o.generation_height_m - 2 * r);
      bool ok = true;
      for (int64_t k = 0; k < p.size() && ok; ++k) {
        const double dx = p.x[k] - x, dy = p.y[k] - y, dz = p.z[k] - z, c = p.r[k] + r;
        ok = dx * dx + dy * dy + dz * dz >= c * c;
      }
      if (!ok) continue;
      p.append_sphere(x, y, z, r, density, p.size());
      v += 4.0 / 3.0 * pi * r * r * r;
      break;
    }
  }
  return p;
}

void packing_height_porosity(const Particles& p, double cylinder_radius, double& height, double& porosity) {
  height = 0;
  double vs = 0;
  for (int64_t i = 0; i < p.size(); ++i) {
    height = std::max(height, p.z[i] + p.r[i]);
    vs += 4.0 / 3.0 * std::numbers::pi * p.r[i] * p.r[i] * p.r[i];
  }
  porosity = height > 0 ? 1 - vs / (std::numbers::pi * cylinder_radius * cylinder_radius * height) : 1;
}

PluviationResult pluviate(const PluviationOptions& o, EngineOptions eo) {
  Particles p = insert_grains(o, eo.material.density_kg_m3);
  const CriticalTimeStep c = critical_time_step(p, eo.material, {});
  eo.time_step = o.time_step_safety * c.dt_critical;
  if (!(o.deposition_friction >= 0)) throw InputError("pluviation: deposition friction must be >= 0");
  eo.friction = eo.walls.platen_friction = eo.walls.cylinder_friction = o.deposition_friction;
  eo.walls.bottom = eo.walls.top = eo.walls.cylinder = true;
  eo.walls.cylinder_radius = o.cylinder_radius_m;
  eo.walls.top_z = o.generation_height_m;
  eo.walls.top_vz = 0;
  Engine e(std::move(p), eo);
  Progress bar("pluviation (simulated s)", o.max_time_s, "s");  // the deposit's phase; pressing runs past it
  PluviationResult res;
  const int64_t chunk = std::max<int64_t>(1, static_cast<int64_t>(1e-3 / eo.time_step));  // check every 1 ms
  // Let the grains fall first: free fall from the top takes sqrt(2H/g).
  const double t_fall = eo.gravity_z < 0 ? std::sqrt(2 * o.generation_height_m / -eo.gravity_z) : 0;
  // Runs until the kinetic energy falls below the tolerance (after `t_min`)
  // or the time limit; true when settled. (Taps after settling were tried
  // and loosened the frictionless deposit: 45.53 % vs 45.22 %, README.)
  // Each settling phase (the deposit; after pressing, held and released)
  // gets max_time_s of simulated time.
  // At rest: below the tolerance at every check over rest_window_s.
  if (!(o.rest_window_s >= 0) || !std::isfinite(o.rest_window_s)) throw InputError("pluviation: rest window must be >= 0 s");
  const int64_t quiet_checks = 1 + static_cast<int64_t>(std::round(o.rest_window_s / (chunk * eo.time_step)));
  auto settle = [&](double t_min) {
    const double t_end = e.time() + o.max_time_s;
    int64_t quiet = 0;
    while (e.time() < t_end) {
      e.run(chunk);
      bar.update(e.time());
      res.kinetic_energy_J = e.kinetic_energy();
      quiet = res.kinetic_energy_J < o.kinetic_energy_tol_J ? quiet + 1 : 0;
      if (e.time() > t_min && quiet >= quiet_checks) return true;
    }
    return false;
  };
  res.settled = settle(t_fall);
  packing_height_porosity(e.particles(), o.cylinder_radius_m, res.deposit_height_m, res.deposit_porosity);
  if (o.press_to_target_height && res.settled && res.deposit_height_m > o.target_height_m) {
    if (!(o.press_speed_m_s > 0) || !std::isfinite(o.press_speed_m_s) || !(o.press_max_stress_Pa > 0))
      throw InputError("pluviation: press speed and maximum press stress must be positive");
    // Platen from the top of the highest grain down to the target height...
    Walls& w = e.walls();
    w.top_z = res.deposit_height_m;
    w.top_vz = -o.press_speed_m_s;
    const int64_t steps = static_cast<int64_t>(std::ceil((res.deposit_height_m - o.target_height_m) / (o.press_speed_m_s * eo.time_step)));
    const int64_t every = 100;  // platen travel between stress checks: 100 dt v (~1 µm)
    const double area = std::numbers::pi * o.cylinder_radius_m * o.cylinder_radius_m;
    for (int64_t done = 0; done < steps; done += every) {
      e.run(std::min(every, steps - done));
      if (done % chunk < every) bar.update(e.time());
      const double stress = e.wall_forces().top_z / area;
      if (stress > o.press_max_stress_Pa) {
        res.press_stop_stress_Pa = stress;
        break;
      }
    }
    // ...held there until the grains are at rest, then taken away.
    w.top_vz = 0;
    if (res.press_stop_stress_Pa == 0) w.top_z = o.target_height_m;
    res.settled = settle(e.time());
    double ignored = 0;
    packing_height_porosity(e.particles(), o.cylinder_radius_m, res.held_height_m, ignored);
    // Lifted off at the press speed until it carries nothing, then taken
    // away. Removed at once, the platen released the packing's elastic energy
    // in one step and could throw a top grain onto a perch high above the
    // rest (seen: a grain on two others and the cylinder, 0.63 mm above the
    // next one, H0 7.00 mm over a 6.55 mm deposit; the oedometer's platen
    // then met that grain alone for 9 % strain).
    w.top_vz = o.press_speed_m_s;
    const double lift_max = w.top_z + o.d50_m;  // far beyond any elastic rebound (µm)
    while (e.wall_forces().top_z > 0 && w.top_z < lift_max) e.run(every);
    w.top_vz = 0;
    w.top = false;
    res.settled = res.settled && settle(e.time());
    res.pressed = true;
  }
  bar.finish();
  res.settle_time_s = e.time();
  res.particles = e.particles();
  // The packing is the geometry at rest: zero the motion and the loads.
  Particles& q = res.particles;
  for (auto* v : {&q.vx, &q.vy, &q.vz, &q.wx, &q.wy, &q.wz, &q.fx, &q.fy, &q.fz, &q.tx, &q.ty, &q.tz,
                  &q.hbx, &q.hby, &q.hbz, &q.htx, &q.hty, &q.htz, &q.hcx, &q.hcy, &q.hcz})
    std::fill(v->begin(), v->end(), 0.0);
  packing_height_porosity(q, o.cylinder_radius_m, res.height_m, res.porosity);
  return res;
}

}  // namespace tg::dem
