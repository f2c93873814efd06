#!/usr/bin/python3
"""Thread-count independence of the main pipelines (issue 9).

Runs, once with OMP_NUM_THREADS=1 and once with 2, on small inputs:
  synth (spheres preset, 48^3, --float) -> segment -> measure (CSV + HDF5,
  CGAL box on) -> psd;  dem oedometer (126 grains, breakage on, weak grains
  so three of them split; run.parallel_min_items = 100 so the sphere and
  contact loops really run on two threads; the default 2048 would keep this
  small scene serial) -> voxelise of the last snapshot (fragments as hulls; as member spheres with --truth-table).
The packing comes from one `dem pack` with 1 thread, shared by both runs:
pluviation runs the same engine as the oedometer (covered here) and with 2
threads it cost 6-24 s more on the shared 2-core machine.
Every output file must be identical, compared bit for bit:
  .h5    every object, dataset (dtype, shape, bytes) and attribute via h5py
         (not the file bytes: HDF5 stores object times);
  .json  parsed, equal after removing IGNORED fields (the same fields inside
         JSON held by an HDF5 attribute: IGNORED_H5_JSON);
  other  (CSV, XDMF, TOML, checkpoint.bin) byte for byte.
No tolerance is needed: every module sums in a fixed order (static schedules,
per-thread partials combined in thread-independent order or serial
reductions), so none is granted. If this test ever needs one, state it here
with its reason.

OMP_WAIT_POLICY=passive is set for both runs: on a shared 2-core machine
spinning OpenMP barriers made the 2-thread DEM run 10x slower. It changes
scheduling only, not results.

Usage: determinism_test.py TOMOGRAIN
"""
import json
import os
import shutil
import subprocess
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import pyharness as H  # noqa: E402
from pyharness import TG  # noqa: E402

# Fields that legitimately depend on the run, not on the data: timings, peak
# memory, the thread count itself. File (relative to the run folder) -> keys
# (dotted paths into the JSON object).
IGNORED = {
    "labels.segment.json": ["seconds", "seconds_total", "peak_rss_bytes", "peak_rss_bytes_per_voxel"],
    "oed/run.json": ["threads"],
}
# The same, inside JSON text stored as an HDF5 attribute: (file, object, attribute) -> keys.
IGNORED_H5_JSON = {
    ("labels.h5", "/", "segment_summary"): IGNORED["labels.segment.json"],
}
# Outputs that hold nothing but timings (none at present).
IGNORED_FILES = set()

PACK_CFG = H.demo_cell_pack_config()

# The weak-grain run (pyharness); its loops run on two threads from 100 items.
OED_CFG = H.weak_grain_run_config(run="parallel_min_items = 100\n", breakage="time_step_safety = 1.0\n")

STEPS = [
    ("synth", ["synth", "--preset", "spheres", "--size", "48", "--seed", "3", "--float", "-o", "s.h5"]),
    ("segment", ["segment", "s.h5", "-o", "labels.h5", "--grain-diameter-um", "400"]),
    ("measure", ["measure", "labels.h5", "-o", "particles.csv", "-o", "particles.h5"]),
    ("psd", ["psd", "particles.csv", "-o", "psd.csv"]),
    ("dem oedometer", ["dem", "oedometer", "oed.toml", "-o", "oed"]),
    # Fragments as hull bodies (the default), and as member spheres with the
    # truth table (its exact integrals cost ~1.6 CPU-s per hull cluster).
    ("voxelise", ["voxelise", "oed/snapshots/strain_04.00pct.h5", "-o", "vox.h5", "--voxel-um", "100"]),
    ("voxelise members", ["voxelise", "oed/snapshots/strain_04.00pct.h5", "-o", "vox_members.h5", "--voxel-um", "100",
                          "--cluster-body", "members", "--truth-table"]),
]


def run_all(d, threads, packing):
    os.makedirs(d)
    shutil.copy(packing, os.path.join(d, "pack.csv"))
    with open(os.path.join(d, "oed.toml"), "w") as f:
        f.write(OED_CFG)
    env = dict(os.environ, OMP_NUM_THREADS=str(threads), OMP_WAIT_POLICY="passive", TOMOGRAIN_QUIET="1")
    times = {}
    for name, args in STEPS:
        t0 = time.monotonic()
        r = subprocess.run([TG] + args, cwd=d, env=env, capture_output=True, text=True)
        times[name] = time.monotonic() - t0
        if r.returncode != 0:
            sys.exit(f"FAIL {name} with {threads} thread(s): exit {r.returncode}\n{r.stdout}\n{r.stderr}")
    return times


def main():
    failures = 0
    with H.workdir("tg_det_") as w:
        with open(os.path.join(w, "pack.toml"), "w") as f:
            f.write(PACK_CFG)
        subprocess.run([TG, "dem", "pack", "pack.toml", "-o", "pack.csv"], cwd=w, env=H.ENV, check=True,
                       stdout=subprocess.DEVNULL)
        t1 = run_all(os.path.join(w, "t1"), 1, os.path.join(w, "pack.csv"))
        t2 = run_all(os.path.join(w, "t2"), 2, os.path.join(w, "pack.csv"))
        # The DEM part must exercise breakage (splits, bonds, fragments).
        hist = open(os.path.join(w, "t1", "oed", "history.csv")).read().splitlines()
        broken = float(hist[-1].split(",")[hist[0].split(",").index("grains_broken")])
        print(f"{'ok  ' if broken >= 1 else 'FAIL'} the DEM run splits grains ({broken:.0f})")
        failures += broken < 1
        print("seconds (1 thread / 2 threads): " + ", ".join(f"{k} {t1[k]:.1f}/{t2[k]:.1f}" for k in t1))
        inputs = ("pack.csv", "oed.toml")
        diffs, compared = H.tree_diffs(os.path.join(w, "t1"), os.path.join(w, "t2"), IGNORED, IGNORED_H5_JSON,
                                       skip=lambda rel: rel in IGNORED_FILES or rel in inputs)
        for rel in compared:
            ign = IGNORED.get(rel, []) + [f"{o}@{k}: {v}" for (f, o, k), v in IGNORED_H5_JSON.items() if f == rel]
            note = f" (ignoring {ign})" if ign else ""
            if rel not in diffs:
                print(f"ok   {rel}{note}")
        for rel, d in diffs.items():
            failures += 1
            print(f"FAIL {rel}: " + "; ".join(d[:5]))
    print(f"{'FAILED' if failures else 'passed'}: {failures} file(s) differ between 1 and 2 threads")
    sys.exit(1 if failures else 0)


main()
