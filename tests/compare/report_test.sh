#!/bin/bash
# End-to-end: synthetic XCT stages + a stand-in DEM run -> tomograin compare
# -> index.html opened in headless Chromium. Checks that every <img> decodes
# (naturalWidth > 0), that the page names every stage from report.json and
# marks the synthetic inputs; keeps the screenshot in the build folder.
# Usage: report_test.sh TOMOGRAIN SRC_DIR WORK_DIR
set -euo pipefail
BIN=$1 SRC=$2 W=$3
PY=/usr/bin/python3
rm -rf "$W" && mkdir -p "$W"
cat > "$W/scene.toml" <<'TOML'
seed = 3
[specimen]
diameter_mm = 5.0
height_mm = 4.0
d50_mm = 1.0
cu = 1.1
pores_per_grain = 0
[grid]
size = 64
field_mm = 5.2
[stages]
strains = [0.0, 0.0712]
broken = [0.0, 0.3]
TOML
"$BIN" synth --preset zeolite-stages --scene "$W/scene.toml" -o "$W/xct.h5" > "$W/synth.log"
$PY "$SRC/make_dem_run.py" "$W/xct_stage0_truth.csv" "$W/dem_run" "$W/exp_curve.csv"
"$BIN" compare --xct "$W/xct_stage0.h5" "$W/xct_stage1.h5" --dem "$W/dem_run" --curve "$W/exp_curve.csv" \
  -o "$W/report" --notes "report test: synthetic stages, stand-in DEM run" | tee "$W/compare.log"
test -s "$W/report/index.html"
for f in report.json summary.csv psd.csv shape_classes.csv distances.csv stress_strain.csv broken.csv \
         fabric.csv normals.csv coordination_by_size.csv lineage.csv tracker_bias.csv; do
  test -s "$W/report/$f" || { echo "missing $f"; exit 1; }
done
# The yield (dem/yield_stress.hpp's rule, tested in tests/study) lies inside each curve's stresses,
# and the study's Fig. 10 columns are the DEM history's counts.
$PY - "$W/report" <<'PY'
import csv, json, sys
d = sys.argv[1]
y = json.load(open(f"{d}/report.json"))["yield"]
ss = list(csv.DictReader(open(f"{d}/stress_strain.csv")))
for series in ("dem", "experiment"):
    s = [float(r["stress_mpa"]) for r in ss if r["series"] == series]
    assert y[f"{series}_mpa"] is not None and 0.1 < y[f"{series}_mpa"] < max(s), (series, y)
br = [r for r in csv.DictReader(open(f"{d}/broken.csv")) if r["series"] == "dem_history"]
assert br and all(float(r["grains_broken"]) >= 0 for r in br), "broken.csv: no DEM history counts"
# Each stage states its memory: the peak while it ran, and per voxel of its XCT volume
# (a 4 B/voxel label volume at least is held while it is measured).
for st in json.load(open(f"{d}/report.json"))["stages"]:
    assert st["peak_rss_bytes"] > 0 and st["peak_scope"] in ("stage", "process"), st
    assert st["peak_rss_bytes_per_voxel"] is None or st["peak_rss_bytes_per_voxel"] > 4, st
PY

# The page plus a script that reports, after load, how many images decoded.
cp "$W/report/index.html" "$W/report/check.html"
cat >> "$W/report/check.html" <<'JS'
<script>
window.addEventListener('load', () => {
  const imgs = Array.from(document.images);
  const bad = imgs.filter(i => !(i.complete && i.naturalWidth > 0)).length;
  const d = document.createElement('pre');
  d.id = 'imgcheck';
  d.textContent = `IMGCHECK total=${imgs.length} bad=${bad}`;
  document.body.appendChild(d);
});
</script>
JS
CHROME="chromium --headless --no-sandbox --disable-gpu --disable-background-networking --disable-component-update --disable-sync --no-first-run"
PROFILE=$(mktemp -d)
trap 'rm -rf "$PROFILE"' EXIT
$CHROME --user-data-dir="$PROFILE" --virtual-time-budget=10000 --dump-dom "file://$W/report/check.html" \
  > "$W/dom.html" 2> "$W/chromium.log"
grep -o 'IMGCHECK total=[0-9]* bad=[0-9]*' "$W/dom.html" | tee "$W/imgcheck.txt"
total=$(sed -n 's/.*total=\([0-9]*\).*/\1/p' "$W/imgcheck.txt")
bad=$(sed -n 's/.*bad=\([0-9]*\).*/\1/p' "$W/imgcheck.txt")
# 7 plots + one slice figure per stage.
[ "$total" -ge 9 ] || { echo "expected >= 9 images, found $total"; exit 1; }
[ "$bad" -eq 0 ] || { echo "$bad images did not load"; exit 1; }
$PY - "$W/report/report.json" "$W/dom.html" <<'PYC'
import html, json, sys
meta = json.load(open(sys.argv[1]))
dom = html.unescape(open(sys.argv[2]).read())
names = [s["name"] for s in meta["stages"]]
assert len(names) == 2, names
for n in names:
    assert n in dom, f"stage {n!r} not named in the page"
assert "Synthetic inputs" in dom, "synthetic inputs not marked"
print("stages named:", names)
PYC
# The numbers the report prints, against independent computations (numpy,
# the inputs themselves): issue 25.
$PY - "$W" <<'PYN'
import csv, json, os, sys
import numpy as np
W = sys.argv[1]
R = os.path.join(W, "report")
rows = lambda p: list(csv.DictReader(open(p)))
summ = {(r["stage"], r["series"]): r for r in rows(os.path.join(R, "summary.csv"))}
names = [s["name"] for s in json.load(open(os.path.join(R, "report.json")))["stages"]]
# 1. The stress-strain file is the DEM history (Pa -> MPa), row for row.
hist = rows(os.path.join(W, "dem_run", "history.csv"))
dem = [r for r in rows(os.path.join(R, "stress_strain.csv")) if r["series"] == "dem"]
assert len(dem) == len(hist), (len(dem), len(hist))
for a, b in zip(dem, hist):
    assert float(a["axial_strain"]) == float(b["strain"])
    assert abs(float(a["stress_mpa"]) - float(b["top_stress_Pa"]) * 1e-6) <= 1e-12 * max(1, abs(float(a["stress_mpa"])))
# 2. The experiment's broken fraction at the last stage: grains with fragments in the synthetic truth.
truth = rows(os.path.join(W, "xct_stage1_truth.csv"))
parents = {}
for t in truth:
    parents[t["parent"]] = parents.get(t["parent"], False) or t["kind"] != "grain"
want = sum(parents.values()) / len(parents)
got = float(summ[(names[1], "experiment")]["broken_fraction"])
assert abs(got - want) < 1e-12, (got, want)
# 3. D10 / D50 / D60 of every series: mass quantiles of its own particle table (numpy, log-linear).
for n, name in enumerate(names):
    for series in ("experiment", "dem_ideal", "dem_imaged"):
        p = rows(os.path.join(R, "particles", f"stage{n}_{series}.csv"))
        d = np.array([float(r["d_med_mm"]) for r in p if float(r["volume_mm3"]) > 0])
        v = np.array([float(r["volume_mm3"]) for r in p if float(r["volume_mm3"]) > 0])
        o = np.argsort(d)
        c = np.cumsum(v[o]) / v.sum() * 100
        for k, q in (("d10_mm", 10), ("d50_mm", 50), ("d60_mm", 60)):
            ref = float(np.exp(np.interp(q, c, np.log(d[o]))))
            assert abs(float(summ[(name, series)][k]) - ref) <= 1e-9 * ref, (name, series, k, summ[(name, series)][k], ref)
# 4. The PSD distance experiment vs DEM ideal at every stage: KS of the mass-weighted Dmed CDFs.
def ks(a, wa, b, wb):
    x = np.union1d(a, b)
    fa = np.array([wa[a <= t].sum() for t in x]) / wa.sum()
    fb = np.array([wb[b <= t].sum() for t in x]) / wb.sum()
    return float(np.abs(fa - fb).max())
dist = {(r["stage"], r["pair"]): r for r in rows(os.path.join(R, "distances.csv"))}
for n, name in enumerate(names):
    s = {}
    for series in ("experiment", "dem_ideal"):
        p = [r for r in rows(os.path.join(R, "particles", f"stage{n}_{series}.csv")) if float(r["volume_mm3"]) > 0]
        s[series] = (np.array([float(r["d_med_mm"]) for r in p]), np.array([float(r["volume_mm3"]) for r in p]))
    ref = ks(*s["experiment"], *s["dem_ideal"])
    got = float(dist[(name, "experiment_vs_dem_ideal")]["psd_ks"])
    assert abs(got - ref) <= 1e-12, (name, got, ref)
print("report numbers: stress-strain = history, broken fraction = truth, D-values and PSD KS = numpy")
PYN
# The contact fabric (issue 22): fabric.csv, normals.csv and coordination_by_size.csv against numpy,
# from the per-series contact tables and particle tables, and for dem_exact from the snapshot's spheres
# themselves (brute-force sphere pairs, not the report's contact list).
$PY - "$W" <<'PYF'
import csv, json, os, sys
import h5py
import numpy as np
R = os.path.join(sys.argv[1], "report")
rows = lambda p: list(csv.DictReader(open(p)))
meta = json.load(open(os.path.join(R, "report.json")))
fab = {(r["stage"], r["series"]): r for r in rows(os.path.join(R, "fabric.csv"))}
nor = rows(os.path.join(R, "normals.csv"))
bys = rows(os.path.join(R, "coordination_by_size.csv"))
edges = np.degrees(np.arccos(1 - np.arange(10) / 9))  # 9 bands of equal solid angle

def check(stage, series, n):
    """fabric.csv and normals.csv rows of one series against numpy on the normals n (k x 3, z y x)."""
    f = fab[(stage, series)]
    assert int(f["n_contacts"]) == len(n), (stage, series, f["n_contacts"], len(n))
    N = n.T @ n / len(n)
    for key, (a, b) in {"N_zz": (0, 0), "N_yy": (1, 1), "N_xx": (2, 2), "N_zy": (0, 1), "N_zx": (0, 2), "N_yx": (1, 2)}.items():
        assert abs(float(f[key]) - N[a, b]) < 1e-12, (stage, series, key, f[key], N[a, b])
    F = 7.5 * (N - np.eye(3) / 3)
    assert abs(float(f["anisotropy"]) - np.sqrt(1.5 * (F * F).sum())) < 1e-12, (stage, series)
    theta = np.degrees(np.arccos(np.minimum(1, np.abs(n[:, 0]))))
    assert abs(float(f["near_axis_share"]) - np.mean(theta <= 30)) < 1e-12, (stage, series)
    count, _ = np.histogram(theta, bins=edges)
    dens = count / len(n) * 9
    got = [r for r in nor if r["stage"] == stage and r["series"] == series]
    assert [int(r["contacts"]) for r in got] == list(count), (stage, series, [r["contacts"] for r in got], count)
    assert np.allclose([float(r["density"]) for r in got], dens, rtol=0, atol=1e-12), (stage, series)
    assert np.allclose([float(r["theta_to_deg"]) for r in got], edges[1:], atol=1e-9)

def check_by_size(stage, series, d, z):
    """coordination_by_size.csv rows against numpy quartiles (sorted by size, then coordination)."""
    o = np.lexsort((z, d))
    got = [r for r in bys if r["stage"] == stage and r["series"] == series]
    assert len(got) == 4, (stage, series, len(got))
    for q, r in enumerate(got):
        k = o[len(o) * q // 4: len(o) * (q + 1) // 4]
        assert int(r["particles"]) == len(k)
        assert abs(float(r["coordination_mean"]) - z[k].mean()) < 1e-12, (stage, series, q)
        assert abs(float(r["d_eq_from_mm"]) - d[k].min()) < 1e-12 and abs(float(r["d_eq_to_mm"]) - d[k].max()) < 1e-12

def spheres(path):
    if path.endswith(".h5"):
        g = h5py.File(path, "r")["spheres"]
        return np.stack([g["z_m"][:], g["y_m"][:], g["x_m"][:]], 1), g["r_m"][:], g["particle"][:]
    t = rows(path)
    return (np.array([[float(r["z_m"]), float(r["y_m"]), float(r["x_m"])] for r in t]),
            np.array([float(r["r_m"]) for r in t]), np.array([float(r["particle"]) for r in t]))

for n, st in enumerate(meta["stages"]):
    name = st["name"]
    for series in ("experiment", "dem_ideal", "dem_imaged"):
        c = rows(os.path.join(R, "contacts", f"stage{n}_{series}.csv"))
        check(name, series, np.array([[float(r["normal_z"]), float(r["normal_y"]), float(r["normal_x"])] for r in c]))
        p = [r for r in rows(os.path.join(R, "particles", f"stage{n}_{series}.csv")) if r["touches_border"] == "0"]
        check_by_size(name, series, np.array([float(r["d_eq_mm"]) for r in p]), np.array([float(r["coordination"]) for r in p]))
    # DEM exact: every pair of spheres of different particles within 1e-3 of the smaller radius.
    x, r, pid = spheres(st["dem"]["snapshot"])
    d = np.linalg.norm(x[:, None, :] - x[None, :, :], axis=2)
    touch = (d <= r[:, None] + r[None, :] + 1e-3 * np.minimum(r[:, None], r[None, :])) & (pid[:, None] != pid[None, :])
    i, j = np.nonzero(np.triu(touch, 1))
    check(name, "dem_exact", (x[j] - x[i]) / d[i, j][:, None])
    ids = np.unique(pid)
    partners = {p: set() for p in ids}
    for a, b in zip(pid[i], pid[j]):
        partners[a].add(b), partners[b].add(a)
    vol = np.array([(r[pid == p] ** 3).sum() for p in ids])
    check_by_size(name, "dem_exact", 2e3 * np.cbrt(vol), np.array([len(partners[p]) for p in ids], float))
    print(name, {s: (fab[(name, s)]["n_contacts"], round(float(fab[(name, s)]["anisotropy"]), 3))
                 for s in ("experiment", "dem_ideal", "dem_imaged", "dem_exact")})
print("fabric.csv, normals.csv, coordination_by_size.csv = numpy (contacts, particle tables, spheres)")
PYF
# The lineages (issue 20): lineage.csv's dem_exact rows against the snapshots' own previous_particle
# column (counted here from the CSV: a previous particle with two pieces = one split), the DEM's broken
# fraction from it, and tracker_bias.csv's % difference against lineage.csv's dem_imaged - dem_exact.
$PY - "$W" <<'PYL'
import csv, json, os, sys
from collections import Counter
W = sys.argv[1]
R = os.path.join(W, "report")
rows = lambda p: list(csv.DictReader(open(p)))
meta = json.load(open(os.path.join(R, "report.json")))
names = [s["name"] for s in meta["stages"]]
lin = {(r["stage"], r["series"]): r for r in rows(os.path.join(R, "lineage.csv"))}
assert {s for _, s in lin} == {"experiment", "dem_exact", "dem_imaged"}, sorted(lin)
snap = rows(meta["stages"][1]["dem"]["snapshot"])  # the stand-in run: CSV after stage 0
n0 = len(rows(os.path.join(W, "xct_stage0_truth.csv")))  # the grains of snapshot 0 (one sphere each)
pieces = Counter()
for prev, pid in {(r["previous_particle"], r["particle"]) for r in snap}:
    pieces[prev] += 1
splits = sum(1 for k in pieces.values() if k == 2)
assert all(k in (1, 2) for k in pieces.values()) and len(pieces) == n0, (len(pieces), n0)
e = lin[(names[1], "dem_exact")]
assert int(e["split"]) == splits and int(e["fragmentation"]) == 0 and int(e["chipping"]) == 0, (e, splits)
assert abs(float(e["pct_intact_broken"]) - 100 * splits / n0) < 1e-9, (e["pct_intact_broken"], splits, n0)
summ = {(r["stage"], r["series"]): r for r in rows(os.path.join(R, "summary.csv"))}
assert abs(float(summ[(names[1], "dem_ideal")]["broken_fraction"]) - splits / n0) < 1e-12
bias = {(r["stage"], r["quantity"]): float(r["value"]) for r in rows(os.path.join(R, "tracker_bias.csv"))}
for name in names:
    want = float(lin[(name, "dem_imaged")]["pct_intact_broken"]) - float(lin[(name, "dem_exact")]["pct_intact_broken"])
    assert abs(bias[(name, "pct_intact_broken_difference")] - want) < 1e-9, (name, want)
assert 0 <= bias[("all", "right_grain")] <= 1 and meta["dem_lineage"]["tracker_bias"], meta["dem_lineage"]
print("lineage.csv dem_exact = snapshot previous_particle counts:", splits, "splits of", n0,
      "; tracker bias:", {k[1]: round(v, 3) for k, v in bias.items() if k[0] == "all"})
PYL
$CHROME --user-data-dir="$PROFILE" --virtual-time-budget=10000 --window-size=1280,2000 \
  --screenshot="$W/report_screenshot.png" "file://$W/report/index.html" 2>> "$W/chromium.log"
test -s "$W/report_screenshot.png"
echo "screenshot: $W/report_screenshot.png"
