#include "data_synth/scene.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>

#include <nlohmann/json.hpp>

#include "core/clock.hpp"
#include "core/errors.hpp"
#include "core/io/hdf5.hpp"
#include "core/io/volume_io.hpp"
#include "core/memory.hpp"
#include "data_synth/truth.hpp"

namespace tg::synth {

namespace {

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

std::string strip_h5(const std::string& path) { return ends_with(path, ".h5") ? path.substr(0, path.size() - 3) : path; }

double container_width(const Scene& s) {
  return s.packing.container == Container::cylinder ? s.packing.diameter : std::max(s.packing.box_y, s.packing.box_x);
}

}  // namespace

const std::vector<std::string>& preset_names() {
  static const std::vector<std::string> names{"spheres", "zeolite", "zeolite-stages", "extremes"};
  return names;
}

Scene preset_scene(const std::string& name) {
  Scene s;
  s.preset = name;
  if (name == "spheres") {
    s.packing.container = Container::box;
    s.packing.height = s.packing.box_y = s.packing.box_x = 3.2;
    s.packing.d50 = 0.4;
    s.packing.cu = 1.2;
    s.default_size = 128;  // 25 µm voxels, grain radius ~8 voxels
  } else if (name == "zeolite" || name == "zeolite-stages") {
    s.packing.container = Container::cylinder;
    s.packing.diameter = 15.0;
    s.packing.height = 12.25;
    s.packing.d50 = 1.36;
    s.packing.cu = 1.07;
    s.pores_per_grain = 3;
    s.pore_radius_fraction = 0.06;
    s.field_mm = 1220 * 0.0123;  // the study's 1220 voxels of 12.3 µm
    s.default_size = name == "zeolite" ? 256 : 128;
    s.stages = name == "zeolite-stages";
  } else if (name == "extremes") {
    s.default_size = 64;
  } else {
    std::string list;
    for (const auto& n : preset_names()) list += (list.empty() ? "" : ", ") + n;
    throw InputError("unknown preset '" + name + "' (presets: " + list + ")");
  }
  return s;
}

void apply_config(Scene& s, Config& c) {
  s.seed = static_cast<uint64_t>(c.get("seed", static_cast<int64_t>(s.seed)));
  PackingOptions& p = s.packing;
  const std::string cont = c.get("specimen.container", p.container == Container::cylinder ? "cylinder" : "box");
  c.require(cont == "cylinder" || cont == "box", "specimen.container", "must be \"cylinder\" or \"box\"");
  p.container = cont == "cylinder" ? Container::cylinder : Container::box;
  p.diameter = c.get("specimen.diameter_mm", p.diameter);
  p.height = c.get("specimen.height_mm", p.height);
  p.box_y = c.get("specimen.box_y_mm", p.box_y);
  p.box_x = c.get("specimen.box_x_mm", p.box_x);
  p.d50 = c.get("specimen.d50_mm", p.d50);
  p.cu = c.get("specimen.cu", p.cu);
  p.target_fraction = c.get("specimen.target_fraction", p.target_fraction);
  s.pores_per_grain = c.get("specimen.pores_per_grain", s.pores_per_grain);
  s.pore_radius_fraction = c.get("specimen.pore_radius_fraction", s.pore_radius_fraction);
  s.particles_file = c.get("specimen.particles", s.particles_file);
  c.require(p.d50 > 0 && p.cu >= 1, "specimen", "needs d50_mm > 0 and cu >= 1");
  c.require(s.pores_per_grain >= 0, "specimen.pores_per_grain", "must be >= 0");
  s.voxel_um = c.get("grid.voxel_um", s.voxel_um);
  s.size = c.get("grid.size", s.size);
  s.field_mm = c.get("grid.field_mm", s.field_mm);
  c.require(s.voxel_um >= 0 && s.size >= 0 && s.field_mm >= 0, "grid", "values must be >= 0");
  ImagingOptions& im = s.imaging;
  im.void_grey = c.get("imaging.void_grey", im.void_grey);
  im.solid_grey = c.get("imaging.solid_grey", im.solid_grey);
  im.psf_sigma = c.get("imaging.psf_sigma_vox", im.psf_sigma);
  im.noise_sigma = c.get("imaging.noise_sigma", im.noise_sigma);
  im.poisson_counts_per_grey = c.get("imaging.poisson_counts_per_grey", im.poisson_counts_per_grey);
  im.cupping = c.get("imaging.cupping", im.cupping);
  im.rings = c.get("imaging.rings", im.rings);
  im.ring_amplitude = c.get("imaging.ring_amplitude", im.ring_amplitude);
  c.require(im.psf_sigma >= 0 && im.noise_sigma >= 0 && im.rings >= 0, "imaging", "values must be >= 0");
  c.require(im.cupping >= 0 && im.cupping < 1, "imaging.cupping", "must be in [0, 1)");
  StageOptions& st = s.stage;
  st.strains = c.get("stages.strains", st.strains);
  st.broken = c.get("stages.broken", st.broken);
  c.require(st.strains.size() == st.broken.size() && !st.strains.empty(), "stages",
            "strains and broken must be non-empty lists of the same length");
  BreakageOptions& b = st.breakage;
  b.gap = c.get("stages.gap_vox", b.gap);
  b.mix_split = c.get("stages.mix_split", b.mix_split);
  b.mix_multi = c.get("stages.mix_multi", b.mix_multi);
  b.mix_chip = c.get("stages.mix_chip", b.mix_chip);
  b.chip_min = c.get("stages.chip_min", b.chip_min);
  b.chip_max = c.get("stages.chip_max", b.chip_max);
  c.require(b.gap >= 0, "stages.gap_vox", "must be >= 0");
  c.require(0 < b.chip_min && b.chip_min <= b.chip_max && b.chip_max < 1, "stages.chip_min",
            "need 0 < chip_min <= chip_max < 1");
  MotionOptions& mo = s.motion;
  const std::string motion = c.get("stages.motion", std::string(mo.oedometer ? "oedometer" : "stretch"));
  c.require(motion == "stretch" || motion == "oedometer", "stages.motion", "must be \"stretch\" or \"oedometer\"");
  mo.oedometer = motion == "oedometer";
  mo.jitter = c.get("stages.jitter", mo.jitter);
  mo.rotation_deg = c.get("stages.rotation_deg", mo.rotation_deg);
  mo.drift = c.get("stages.drift", mo.drift);
  mo.rebreak = c.get("stages.rebreak", mo.rebreak);
  c.require(mo.jitter >= 0 && mo.drift >= 0, "stages.jitter", "jitter and drift must be >= 0");
  c.require(mo.rebreak >= 0 && mo.rebreak <= 1, "stages.rebreak", "must be in [0, 1]");
  RenderOptions& r = s.render;
  r.chord_order = c.get("render.chord_order", r.chord_order);
  r.depth = c.get("render.depth", r.depth);
  r.slab = c.get("render.slab", r.slab);
  c.require(r.chord_order >= 1 && r.chord_order <= 32, "render.chord_order", "must be in [1, 32]");
  c.require(r.depth >= 0 && r.depth <= 6, "render.depth", "must be in [0, 6]");
  c.require(r.slab >= 1, "render.slab", "must be >= 1");
  c.finish();
}

Grid make_grid(const Scene& s) {
  const double field = s.field_mm > 0 ? s.field_mm : container_width(s);
  if (!(field > 0)) throw InputError("grid: field of view must be positive");
  Grid g;
  int64_t n;
  if (s.voxel_um > 0) {
    g.voxel_mm = s.voxel_um * 1e-3;
    n = s.size > 0 ? s.size : static_cast<int64_t>(std::ceil(field / g.voxel_mm - 1e-9));
  } else {
    n = s.size > 0 ? s.size : s.default_size;
    g.voxel_mm = field / static_cast<double>(n);
  }
  if (n < 1 || n > 4096) throw InputError("grid: size must be in [1, 4096] voxels (got " + std::to_string(n) + ")");
  g.shape = Shape{n, n, n};
  const double half = 0.5 * static_cast<double>(n) * g.voxel_mm;
  g.origin_mm = {0.5 * s.packing.height - half, -half, -half};
  for (int a = 0; a < 3; ++a) {
    g.geometry.voxel_size_m[a] = g.voxel_mm * 1e-3;
    g.geometry.origin_m[a] = g.origin_mm[a] * 1e-3;
  }
  return g;
}

std::vector<Particle> read_particles(const std::string& path, const Grid& g) {
  // DEM sphere tables (a CSV with x_m, or an HDF5 file without a /truth
  // table: a DEM snapshot) go through the one sphere-table reader and the one
  // spheres-to-particles mapping that voxelise and compare use.
  Table t;
  if (is_hdf5(path)) {
    const auto [file, group] = split_dataset_spec(path);
    H5Reader rd(file);
    bool truth = !group.empty();
    for (const std::string& d : rd.datasets()) truth = truth || d.rfind("/truth/", 0) == 0;
    if (!truth) return particles_from_spheres(read_spheres(path), g.geometry);
    t = rd.read_table(group.empty() ? "truth" : group);
    t.source = path;
  } else {
    t = read_csv(path);
  }
  std::vector<Particle> out;
  if (t.has("x_m")) {
    return particles_from_spheres(spheres_from_table(t), g.geometry);
  } else if (t.has("cz_vox")) {
    const auto &z = t.num("cz_vox"), &y = t.num("cy_vox"), &x = t.num("cx_vox"), &r = t.num("radius_vox");
    for (int64_t q = 0; q < t.rows(); ++q) {
      if (!(r[q] > 0)) throw InputError(path + ": row " + std::to_string(q + 2) + ": radius_vox must be > 0");
      const uint32_t id = t.has("id") ? static_cast<uint32_t>(t.num("id")[q]) : static_cast<uint32_t>(q + 1);
      out.push_back(make_grain(id, {z[q], y[q], x[q]}, r[q]));
    }
  } else {
    throw InputError(path + ": need columns x_m,y_m,z_m,r_m (DEM) or cz_vox,cy_vox,cx_vox,radius_vox");
  }
  return out;
}

Grains make_grains(const Scene& s, const Grid& g) {
  Grains out;
  out.z_bottom_vox = -g.origin_mm[0] / g.voxel_mm;
  if (!s.particles_file.empty()) {
    out.particles = read_particles(s.particles_file, g);
  } else {
    PackingOptions po = s.packing;
    po.seed = s.seed;
    if (s.stages) po.height *= 1 - *std::max_element(s.stage.strains.begin(), s.stage.strains.end());
    out.packing = dense_packing(po);
    uint32_t id = 1;
    for (const Sphere& sp : out.packing.spheres) {
      const Vec3 c{(sp.c[0] - g.origin_mm[0]) / g.voxel_mm, (sp.c[1] - g.origin_mm[1]) / g.voxel_mm,
                   (sp.c[2] - g.origin_mm[2]) / g.voxel_mm};
      out.particles.push_back(make_grain(id++, c, sp.r / g.voxel_mm));
    }
  }
  for (Particle& p : out.particles)
    if (p.kind == Kind::grain) add_pores(p, s.pores_per_grain, s.pore_radius_fraction, s.seed);
  return out;
}

WriteResult render_and_write(const std::vector<Particle>& particles, const Grid& grid, const Scene& scene,
                             const std::string& path, bool write_float, const std::string& provenance) {
  WriteResult res;
  res.particles = static_cast<int64_t>(particles.size());
  auto t0 = std::chrono::steady_clock::now();
  RenderOptions ro = scene.render;
  ro.progress = true;
  Rendered r = render(particles, grid.shape, grid.geometry, ro);
  res.t.render_s = seconds_since(t0);
  res.solid_fraction_voxels = mean_solid_fraction(r.solid);
  t0 = std::chrono::steady_clock::now();
  const Table truth = truth_table(particles, r.labels, grid.shape, grid.geometry);
  res.t.truth_s = seconds_since(t0);
  res.truth = truth;
  t0 = std::chrono::steady_clock::now();
  apply_imaging(r.solid, scene.imaging);
  U16Result u = to_u16(r.solid);
  res.saturated = u.saturated_high + u.saturated_low;
  res.t.imaging_s = seconds_since(t0);
  t0 = std::chrono::steady_clock::now();
  {
    H5Writer w(path);
    w.write_volume("/volume", u.volume);
    w.write_volume("/labels", r.labels);
    if (write_float) w.write_volume("/reconstruction", r.solid);
    w.write_table("/truth", truth);
    w.write_attribute("synth", provenance);
    w.commit();
  }
  write_csv(truth, strip_h5(path) + "_truth.csv");
  res.t.write_s = seconds_since(t0);
  return res;
}

namespace {

nlohmann::json provenance(const Scene& s, const Grid& g, const Packing& pk) {
  nlohmann::json j;
  j["generator"] = "tomograin synth";
  j["preset"] = s.preset;
  j["seed"] = s.seed;
  j["voxel_mm"] = g.voxel_mm;
  j["shape_zyx"] = {g.shape.nz, g.shape.ny, g.shape.nx};
  j["origin_mm_zyx"] = {g.origin_mm[0], g.origin_mm[1], g.origin_mm[2]};
  j["packing"] = {{"container", s.packing.container == Container::cylinder ? "cylinder" : "box"},
                  {"d50_mm", s.packing.d50},
                  {"cu", s.packing.cu},
                  {"grains", pk.spheres.size()},
                  {"solid_fraction", pk.fraction},
                  {"interior_solid_fraction", pk.interior_fraction},
                  {"mean_contacts", pk.mean_contacts},
                  {"method", "collective rearrangement with growth (data_synth/packing.hpp)"}};
  if (!s.particles_file.empty()) j["particles_file"] = s.particles_file;
  const ImagingOptions& im = s.imaging;
  j["imaging"] = {{"void_grey", im.void_grey},   {"solid_grey", im.solid_grey}, {"psf_sigma_vox", im.psf_sigma},
                  {"noise_sigma", im.noise_sigma}, {"poisson_counts_per_grey", im.poisson_counts_per_grey},
                  {"cupping", im.cupping},         {"rings", im.rings},           {"ring_amplitude", im.ring_amplitude}};
  j["coordinates"] = "voxel (k,j,i) covers [k,k+1)x[j,j+1)x[i,i+1); mm = origin + voxel * coordinate";
  return j;
}

void report(const std::string& path, const WriteResult& w, const Grid& g) {
  std::printf("%s: %lld particles, %s, voxel %.4g um, mean solid %.4f, render %.2f s, truth %.2f s, "
              "imaging %.2f s, write %.2f s%s\n",
              path.c_str(), static_cast<long long>(w.particles), g.shape.str().c_str(), g.voxel_mm * 1e3,
              w.solid_fraction_voxels, w.t.render_s, w.t.truth_s, w.t.imaging_s, w.t.write_s,
              w.saturated ? (", " + std::to_string(w.saturated) + " saturated voxels").c_str() : "");
}

// Extremes: five small files for edge cases.
int run_extremes(Scene base, const std::string& out, bool write_float) {
  const std::string prefix = strip_h5(out);
  auto box_scene = [&](double side_mm, double d50_mm, double cu, double target) {
    Scene s = base;
    s.packing.container = Container::box;
    s.packing.height = s.packing.box_y = s.packing.box_x = side_mm;
    s.packing.d50 = d50_mm;
    s.packing.cu = cu;
    s.packing.target_fraction = target;
    s.voxel_um = 10;
    s.size = s.size > 0 ? s.size : 64;
    return s;
  };
  auto write = [&](const std::string& name, const Scene& s, const Grid& g, const std::vector<Particle>& ps,
                   const Packing& pk) {
    nlohmann::json j = provenance(s, g, pk);
    j["case"] = name;
    const std::string path = prefix + "_" + name + ".h5";
    report(path, render_and_write(ps, g, s, path, write_float, j.dump()), g);
  };
  {  // grains of 1–3 voxels (d50 2 voxels, Cu 1.3), loosely packed
    Scene s = box_scene(0.64, 0.02, 1.3, 0.3);
    const Grid g = make_grid(s);
    const Grains gr = make_grains(s, g);
    write("tiny", s, g, gr.particles, gr.packing);
  }
  {  // grains cut by all six faces: a 0.8 mm packing seen through a centred 0.64 mm crop
    Scene s = box_scene(0.8, 0.16, 1.2, 0.6);
    const Grid g = make_grid(s);
    const Grains gr = make_grains(s, g);
    write("border", s, g, gr.particles, gr.packing);
  }
  {  // empty
    Scene s = box_scene(0.64, 0.1, 1.0, 0.3);
    const Grid g = make_grid(s);
    write("empty", s, g, {}, Packing{});
  }
  {  // all solid: one sphere containing the whole cube
    Scene s = box_scene(0.64, 0.1, 1.0, 0.3);
    const Grid g = make_grid(s);
    const double n = static_cast<double>(g.shape.nx);
    write("solid", s, g, {make_grain(1, {0.5 * n, 0.5 * n, 0.5 * n}, 0.5 * std::sqrt(3.0) * n + 1)}, Packing{});
  }
  {  // solid grey beyond the 16-bit range: clipped, counted
    Scene s = box_scene(0.64, 0.1, 1.2, 0.6);
    s.imaging.solid_grey = 70000;
    const Grid g = make_grid(s);
    const Grains gr = make_grains(s, g);
    write("saturated", s, g, gr.particles, gr.packing);
  }
  return 0;
}

}  // namespace

int run_synth(Scene scene, const std::string& out, bool write_float) {
  scene.imaging.seed = scene.seed;
  scene.stage.breakage.seed = scene.seed;
  if (scene.preset == "extremes") return run_extremes(scene, out, write_float);
  const Grid grid = make_grid(scene);
  auto t0 = std::chrono::steady_clock::now();
  const Grains gr = make_grains(scene, grid);
  const double packing_s = seconds_since(t0);
  if (gr.packing.spheres.empty())
    std::printf("%zu particles read from %s (%.2f s)\n", gr.particles.size(), scene.particles_file.c_str(), packing_s);
  else
    std::printf("packing: %zu grains, solid fraction %.4f (interior %.4f), %.2f contacts/grain, %d sweeps, "
                "%d removed at jams, radius factor %.9f, %.2f s\n",
                gr.packing.spheres.size(), gr.packing.fraction, gr.packing.interior_fraction,
                gr.packing.mean_contacts, gr.packing.sweeps, gr.packing.removed, gr.packing.final_scale, packing_s);
  nlohmann::json j = provenance(scene, grid, gr.packing);
  if (!scene.stages) {
    report(out, render_and_write(gr.particles, grid, scene, out, write_float, j.dump()), grid);
  } else {
    const std::string prefix = strip_h5(out);
    const double emax = *std::max_element(scene.stage.strains.begin(), scene.stage.strains.end());
    std::vector<std::vector<SeriesParticle>> series;  // oedometer motion: the truth lineage
    std::vector<Table> truths;
    for (int s = 0; s < static_cast<int>(scene.stage.strains.size()); ++s) {
      std::vector<Particle> ps;
      if (scene.motion.oedometer) {
        series.push_back(oedometer_stage(gr.particles, gr.z_bottom_vox, s, scene.stage, scene.motion));
        for (const auto& sp : series.back()) ps.push_back(sp.particle);
      } else {
        ps = stage_particles(gr.particles, gr.z_bottom_vox, s, scene.stage);
      }
      j["stage"] = s;
      j["axial_strain"] = scene.stage.strains[s];
      j["broken_fraction"] = scene.stage.broken[s];
      j["specimen_height_mm"] = scene.packing.height * (1 - scene.stage.strains[s]);
      j["packing"]["solid_fraction"] = gr.packing.fraction * (1 - emax) / (1 - scene.stage.strains[s]);
      j["motion"] = scene.motion.oedometer ? "oedometer" : "stretch";
      const std::string path = prefix + "_stage" + std::to_string(s) + ".h5";
      WriteResult w = render_and_write(ps, grid, scene, path, write_float, j.dump());
      report(path, w, grid);
      truths.push_back(std::move(w.truth));
    }
    if (scene.motion.oedometer) {
      write_csv(lineage_truth(series, truths), prefix + "_lineage.csv");
      std::printf("%s_lineage.csv: truth lineage of %zu stages\n", prefix.c_str(), series.size());
    }
  }
  std::printf("peak memory %s\n", human_bytes(static_cast<double>(peak_rss_bytes())).c_str());
  return 0;
}

}  // namespace tg::synth
