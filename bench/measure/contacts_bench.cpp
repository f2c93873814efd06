// measure_contacts_bench: contact detection, normals and fabric against the
// exact truth of grown sphere scenes (tests/measure/contact_scenes.hpp) at
// grain diameters from 10 to 86 voxels: the same physical scene (one seed)
// rendered at each voxel size; contacts overlap by 2.8 % of the radius,
// non-contacts stay >= 14 % of the radius apart. Both images: labels face to
// face, and with one-voxel watershed-style lines.
//
//   measure_contacts_bench [seeds]   (default 3 seeds: 11, 12, 13)
//
// Columns: grain diameter (voxels), image kind, share of interior particles
// whose coordination is right, contacts missed / extra (of the truth's),
// median and 90th-percentile normal error (deg), |a - a_truth| (fabric
// anisotropy), find_contacts time (2 threads, s).
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <set>

#include "measure/contacts.hpp"
#include "tests/measure/contact_scenes.hpp"

using namespace tg;
using namespace tg::measure;
using V3 = Eigen::Vector3d;

int main(int argc, char** argv) {
  const int seeds = argc > 1 ? std::atoi(argv[1]) : 3;
  std::printf("| D (vox) | image | coordination right | missed | extra | normal err median / p90 (deg) | abs(a - a_truth) | time (s) |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  for (double r : {5.0, 10.0, 15.0, 20.0, 30.0, 43.0}) {
    const double scale = r / 21.5;
    const int64_t n = static_cast<int64_t>(std::lround(176 * scale));
    for (int lines = 0; lines < 2; ++lines) {
      int interior = 0, right = 0, missed = 0, extra = 0, truth_n = 0;
      std::vector<double> errs, da;
      double t_sum = 0;
      for (int sd = 0; sd < seeds; ++sd) {
        const auto s = test::grow_scene(n, 11u + static_cast<unsigned>(sd), 40, 0.6, 3.0, scale);
        auto labels = test::render_scene(s, n, 1e-5);
        if (lines) labels = test::cut_lines(labels);
        ContactOptions o;
        o.threads = 2;
        const auto t0 = std::chrono::steady_clock::now();
        const auto res = find_contacts(labels.view(), o);
        t_sum += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        std::map<std::pair<uint32_t, uint32_t>, V3> found;
        for (const auto& c : res.contacts) found[{c.a, c.b}] = c.normal;
        std::set<std::pair<uint32_t, uint32_t>> truth;
        std::vector<int> tz(s.c.size(), 0), iz(s.c.size(), 0);
        std::vector<V3> nt, ni;
        for (const auto& [p, q] : s.contacts) {
          truth.insert({static_cast<uint32_t>(p + 1), static_cast<uint32_t>(q + 1)});
          ++tz[static_cast<size_t>(p)];
          ++tz[static_cast<size_t>(q)];
          const V3 nn = (s.c[q] - s.c[p]).normalized();
          nt.push_back(nn);
          ++truth_n;
          auto it = found.find({static_cast<uint32_t>(p + 1), static_cast<uint32_t>(q + 1)});
          if (it == found.end()) { ++missed; continue; }
          errs.push_back(std::acos(std::clamp(it->second.dot(nn), -1.0, 1.0)) * 180 / std::numbers::pi);
        }
        for (const auto& c : res.contacts) {
          extra += !truth.count({c.a, c.b});
          ni.push_back(c.normal);
          ++iz[c.a - 1];
          ++iz[c.b - 1];
        }
        for (size_t p = 0; p < s.c.size(); ++p)
          if (((s.c[p].array() - s.r[p]) > 1).all() && ((s.c[p].array() + s.r[p]) < static_cast<double>(n) - 1).all()) {
            ++interior;
            right += iz[p] == tz[p];
          }
        da.push_back(std::abs(fabric(ni).anisotropy - fabric(nt).anisotropy));
      }
      std::sort(errs.begin(), errs.end());
      auto q = [&](double f) { return errs.empty() ? NAN : errs[static_cast<size_t>(f * static_cast<double>(errs.size() - 1))]; };
      std::printf("| %.0f | %s | %.1f %% (%d/%d) | %d/%d | %d | %.2f / %.2f | %.3f (worst %.3f) | %.3f |\n", 2 * r,
                  lines ? "lines" : "face to face", 100.0 * right / std::max(1, interior), right, interior, missed,
                  truth_n, extra, q(0.5), q(0.9), [&] { double m = 0; for (double d : da) m += d; return m / static_cast<double>(da.size()); }(),
                  *std::max_element(da.begin(), da.end()), t_sum / seeds);
    }
  }
  return 0;
}
