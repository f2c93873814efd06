#!/bin/bash
# lambda's signature in the single-grain crush test (bench/dem/RESULTS.md,
# "Calibration"): d = 1.2 mm, travel 0.4 d, strength seeds 1-3, lambda 0.9 /
# 1.25 / 1.6. Usage: crush_lambda.sh TOMOGRAIN (in an empty folder; 2 at a time).
TG=$1
for s in 1 2 3; do for l in 0.9 1.25 1.6; do
  [ -f c_${l}_$s.csv ] || nice -n 10 "$TG" dem crush -d 1.2e-3 --seed $s --bond-radius-multiplier $l -o c_${l}_$s.csv > c_${l}_$s.log &
  [ $(jobs -r | wc -l) -ge 2 ] && wait -n
done; done; wait
/usr/bin/python3 - <<'PY'
import csv, numpy as np
for l in ("0.9", "1.25", "1.6"):
    out = []
    for s in (1, 2, 3):
        r = list(csv.DictReader(open(f"c_{l}_{s}.csv")))
        F = np.array([float(x["force_N"]) for x in r]); g = np.array([float(x["grains_broken"]) for x in r])
        b = np.array([float(x["bonds_broken"]) for x in r]); tr = np.array([float(x["travel_m"]) for x in r])
        i = np.argmax(g > 0)  # first split
        out.append((F[:i].max(), F[i:].max(), b[-1], np.trapz(F[i:], tr[i:]) * 1e3))
    o = np.array(out)
    print(f"lambda {l}: peak before split {o[:,0].round(2)} N; peak after {o[:,1].round(2)} N; bonds broken {o[:,2].astype(int)}; work after split {o[:,3].round(3)} mJ")
PY
