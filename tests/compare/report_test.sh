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
$CHROME --user-data-dir="$PROFILE" --virtual-time-budget=10000 --window-size=1280,2000 \
  --screenshot="$W/report_screenshot.png" "file://$W/report/index.html" 2>> "$W/chromium.log"
test -s "$W/report_screenshot.png"
echo "screenshot: $W/report_screenshot.png"
