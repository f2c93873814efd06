#!/usr/bin/python3
"""A synthetic campaign to try the workflow on (docs/campaigns.md), and the
one the workflow's test and benches run (tests/workflow, bench/campaign).

Writes into DIR:
  scans/<name>_stage<i>.h5   `tomograin synth --preset zeolite-stages` at
                             --size, one seed per study, the first --stages
                             stages of the preset (strains 0, 4.4, 7.12, ... %)
  studies/<name>.toml        one study per scan series (names s01, s02, ...)
  dem/cell.toml, dem/pack.csv  with --dem: the tiny DEM cell of the tests
                             (the committed 126-grain packing
                             tests/apps/data/crash_pack.csv, weak grains, 4 %
                             strain; one thread: ~10 s per run on the shared
                             2-core VM, where two threads took 160 s)
  campaign.yaml              the workflow config: the studies, out: DIR/out

--dem 1 gives the first study one DEM run (and a comparison); --dem N (N > 1)
gives it a sweep of N variants of the grains' strength
(breakage.sigma_t0_Pa, SWEEP). The other studies have no DEM, so a campaign
holds both kinds of study.

Usage: make_synthetic_campaign.py TOMOGRAIN DIR [--studies N] [--size S]
                                  [--stages K] [--dem V] [--seed S0]
"""
import argparse
import os
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "tests"))
import pyharness as H  # noqa: E402  (the tests' weak-grain DEM cell: one definition)

PACKING = os.path.join(ROOT, "tests", "apps", "data", "crash_pack.csv")
# The preset's strains and broken fractions (data_synth/granule.hpp).
STRAINS = [0.0, 0.044, 0.0712, 0.1128, 0.1548]
BROKEN = [0.0, 0.15, 0.30, 0.50, 0.70]
# Strength of the grains in a sweep's variants (Pa; the cell's own is 3 MPa).
SWEEP = [2.0e6, 3.0e6, 4.5e6, 6.0e6, 8.0e6, 12.0e6]
GRAIN_DIAMETER_UM = 1360  # the zeolite preset's D50


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("tomograin")
    ap.add_argument("dir")
    ap.add_argument("--studies", type=int, default=2)
    ap.add_argument("--size", type=int, default=96)
    ap.add_argument("--stages", type=int, default=3)
    ap.add_argument("--dem", type=int, default=0, help="DEM runs of the first study: 0 none, 1 one, N a sweep of N")
    ap.add_argument("--seed", type=int, default=1, help="seed of the first study (then +1 each)")
    a = ap.parse_args()
    if not 2 <= a.stages <= len(STRAINS):
        sys.exit(f"make_synthetic_campaign: --stages must be in [2, {len(STRAINS)}]")
    if not 0 <= a.dem <= len(SWEEP):
        sys.exit(f"make_synthetic_campaign: --dem must be in [0, {len(SWEEP)}]")
    d = os.path.abspath(a.dir)
    for sub in ("scans", "studies"):
        os.makedirs(os.path.join(d, sub), exist_ok=True)
    scene = os.path.join(d, "scans", "stages.toml")
    with open(scene, "w") as f:
        f.write(f"[stages]\nstrains = {STRAINS[:a.stages]}\nbroken = {BROKEN[:a.stages]}\n")
    if a.dem:
        os.makedirs(os.path.join(d, "dem"), exist_ok=True)
        shutil.copyfile(PACKING, os.path.join(d, "dem", "pack.csv"))
        with open(os.path.join(d, "dem", "cell.toml"), "w") as f:
            f.write(H.weak_grain_run_config(run="threads = 1\n", breakage="time_step_safety = 1.0\n"))

    names = []
    for i in range(a.studies):
        name = f"s{i + 1:02d}"
        names.append(name)
        prefix = os.path.join(d, "scans", name + ".h5")
        if not os.path.exists(os.path.join(d, "scans", f"{name}_stage{a.stages - 1}.h5")):
            subprocess.run([a.tomograin, "synth", "--preset", "zeolite-stages", "--scene", scene, "--size",
                            str(a.size), "--seed", str(a.seed + i), "-o", prefix],
                           check=True, stdout=subprocess.DEVNULL, env=dict(os.environ, TOMOGRAIN_QUIET="1"))
        lines = [f'[study]\nname = "{name}"\ngrain_diameter_um = {GRAIN_DIAMETER_UM}\n']
        for s in range(a.stages):
            lines.append(f'[[stage]]\nscan = "../scans/{name}_stage{s}.h5"\nstrain = {STRAINS[s]}\nname = "s{s}"\n')
        if a.dem > 0 and i == 0:
            lines.append('[dem]\nconfig = "../dem/cell.toml"\n')
            if a.dem > 1:
                for v in SWEEP[:a.dem]:
                    lines.append(f'[[dem.variant]]\nname = "t{v / 1e3:.0f}kPa"\n'
                                 f'set = {{ "breakage.sigma_t0_Pa" = {v:.1e} }}\n')
        with open(os.path.join(d, "studies", name + ".toml"), "w") as f:
            f.write("\n".join(lines))
    with open(os.path.join(d, "campaign.yaml"), "w") as f:
        f.write("# Written by workflow/scripts/make_synthetic_campaign.py\nstudies:\n")
        f.writelines(f"  - {d}/studies/{n}.toml\n" for n in names)
        f.write(f"out: {d}/out\ntomograin: {os.path.abspath(a.tomograin)}\n")
    print(f"{a.studies} studies of {a.stages} stages at {a.size}^3 in {d}; config {d}/campaign.yaml")


main()
