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
for f in report.json summary.csv psd.csv shape_classes.csv distances.csv stress_strain.csv broken.csv; do
  test -s "$W/report/$f" || { echo "missing $f"; exit 1; }
done

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
# 6 plots + one slice figure per stage.
[ "$total" -ge 8 ] || { echo "expected >= 8 images, found $total"; exit 1; }
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
$CHROME --user-data-dir="$PROFILE" --virtual-time-budget=10000 --window-size=1280,2000 \
  --screenshot="$W/report_screenshot.png" "file://$W/report/index.html" 2>> "$W/chromium.log"
test -s "$W/report_screenshot.png"
echo "screenshot: $W/report_screenshot.png"
