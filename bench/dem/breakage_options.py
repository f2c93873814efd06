#!/usr/bin/env python3
"""Screen of the breakage model's open choices (issue 21): each variant is a
set of config keys on top of the oedometer as shipped; one table row each.

Usage:
  breakage_options.py small TOMOGRAIN OUTDIR [VARIANT ...]   # demo cell (126 grains, Ø8 mm)
  breakage_options.py full  TOMOGRAIN OUTDIR PACKING VARIANT ...  # the 910-grain pressed specimen
  breakage_options.py table OUTDIR                            # the table of finished runs
  breakage_options.py stress_table OUTDIR                     # the same runs by stress level (issue 21's targets)
  breakage_options.py config KIND PACKING VARIANT             # print a variant's config (e.g. for calibrate)

A VARIANT is a name below, optionally followed by keys of its own:
"study,breakage.min_time_step_s=5e-8,breakage.sigma_t0_Pa=16e6" (TOML values).

small: tests/apps/data/crash_pack.csv (the demo cell's packing) with
dem/examples/oedometer.toml's keys (Table 1, sigma_t0 12 MPa, splits down to
0.2 mm) except the cell (Ø8 mm), min_time_step_s 2e-8 (the demo's, halves the
run) and a history row every 100 steps; to 15.48 %. full: the shipped config
with packing_csv = PACKING (`tomograin dem pack dem/examples/oedometer.toml`),
history every 1000 steps. Every run: 1 thread, `nice`, two at a time at most
(`-j`, default 2); wall and CPU time from /usr/bin/time.

Figures (rules stated, not tuned):
  * yield: `tomograin dem yield` (bilinear strain-log sigma above 0.1 MPa, the
    issue's rule and the report's; breakage_analysis.yield_stress_mpa);
  * sigma at 10 / 15.48 %: top-platen stress, mean of the history rows within
    +-0.25 % strain (the small cell's sigma is noisy);
  * grains / bonds broken at yield, at 4 MPa (first row >= 4 MPa) and at the end;
    bonds = broken by stress (bonds dropped with split elements not counted);
  * per height fifth: generation-0 splits by z / h(t), as breakage_analysis.py;
  * KE at splits: for each check step with a split, the largest kinetic energy
    of the history rows in the next 20 rows over the last row before it
    (median and max over splits; small cell only, 100-step rows);
  * a run the engine stopped (SimulationError) is reported as such with its
    strain.
"""
import csv
import json
import os
import statistics
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, HERE)
from breakage_analysis import read_csv, yield_stress_mpa  # noqa: E402  (the product's rule for the yield)

FRICTIONLESS = {"walls.platen_friction": 0.0, "walls.cylinder_friction": 0.0}
TOTAL07 = {"contact.local_damping": 0.7, "contact.local_damping_scope": '"total"'}
# Name -> keys set on top of the shipped config.
VARIANTS = {
    "baseline": {},
    "walls0": FRICTIONLESS,
    "walls0_cyl": {"walls.cylinder_friction": 0.0},
    "walls0+local0.7": {**FRICTIONLESS, "contact.local_damping": 0.7},
    "walls0+total0.7": {**FRICTIONLESS, **TOTAL07},
    "walls0+bond0.5": {**FRICTIONLESS, "breakage.bond_damping": 0.5},
    "walls0+total0.7+bond0.5": {**FRICTIONLESS, **TOTAL07, "breakage.bond_damping": 0.5},
    "walls0+total0.7+nosplitbonded": {**FRICTIONLESS, **TOTAL07, "breakage.split_bonded": "false"},
    "keep": {"breakage.sublimit_policy": '"keep"'},
    "keep_unbreakable": {"breakage.sublimit_policy": '"keep_unbreakable"'},
    "walls0+total0.7+nosplitbonded+keepu": {**FRICTIONLESS, **TOTAL07, "breakage.split_bonded": "false",
                                            "breakage.sublimit_policy": '"keep_unbreakable"'},
    "walls0+total0.7+nosplitbonded+keepu+min": {**FRICTIONLESS, **TOTAL07, "breakage.split_bonded": "false",
                                                "breakage.sublimit_policy": '"keep_unbreakable"',
                                                "breakage.bond_radius_rule": '"min"'},
    "walls0+total0.7+bond0.5+nosplitbonded+keepu": {**FRICTIONLESS, **TOTAL07, "breakage.bond_damping": 0.5,
                                                    "breakage.split_bonded": "false",
                                                    "breakage.sublimit_policy": '"keep_unbreakable"'},
    "min": {"breakage.bond_radius_rule": '"min"'},
    # The study's reading (dem/breakage/README.md, "The model chosen"): PEEK cell walls without
    # friction, PFC's default local damping 0.7 on the unbalanced force, replacement for grains and
    # bond breakage for fragments, spheres under 0.2 mm kept and never broken.
    "study": {**FRICTIONLESS, **TOTAL07, "breakage.split_bonded": "false",
              "breakage.sublimit_policy": '"keep_unbreakable"'},
    "nosplitbonded": {"breakage.split_bonded": "false"},
}
# dem/examples/oedometer_calibrated.toml as a variant (same keys: the study's reading, the speed
# knobs, sigma_t0 and lambda calibrated), so that its remedies and seeds are rows: e.g.
# 'calibrated,breakage.seed=2,breakage.birth_overlap="none"'.
VARIANTS["calibrated"] = {**VARIANTS["study"], "breakage.min_time_step_s": "5.0e-8", "run.neighbour_skin_m": "1.0e-4",
                          "breakage.sigma_t0_Pa": "10.3e6", "breakage.bond_radius_multiplier": "2.40"}


def variant_keys(name):
    """Keys of "NAME[,table.key=value,...]": NAME's keys with the extra ones on top."""
    base, *extra = name.split(",")
    if base not in VARIANTS:
        raise SystemExit(f"breakage_options.py: unknown variant {base!r}; known: {list(VARIANTS)}")
    keys = dict(VARIANTS[base])
    for kv in extra:
        k, _, v = kv.partition("=")
        if not v or "." not in k:
            raise SystemExit(f"breakage_options.py: {kv!r} in {name!r} is not table.key=value")
        keys[k] = v
    return keys


def config_text(kind, packing, keys):
    """The shipped oedometer.toml with `keys` (table.key -> TOML value) set."""
    lines = open(os.path.join(ROOT, "dem/examples/oedometer.toml")).read().splitlines()
    keys = dict(keys)
    keys["specimen.packing_csv"] = json.dumps(os.path.abspath(packing))
    keys["run.threads"] = 1
    if kind == "small":
        keys.setdefault("walls.cylinder_radius_m", 4.0e-3)
        keys["breakage.min_time_step_s"] = 2.0e-8
        keys["oedometer.history_every_steps"] = 100
        keys["oedometer.snapshot_strains"] = "[0.0, 0.1548]"
    out, table, done = [], None, set()
    for line in lines:
        s = line.strip()
        if s.startswith("[") and "]" in s:
            table = s[1:s.index("]")]
        elif "=" in s and not s.startswith("#") and table:
            k = f"{table}.{s.split('=')[0].strip()}"
            if k in keys:
                line = f"{k.split('.', 1)[1]} = {keys[k]}"
                done.add(k)
        out.append(line)
    missing = set(keys) - done
    if missing:
        raise SystemExit(f"breakage_options.py: keys not in dem/examples/oedometer.toml: {sorted(missing)}")
    return "\n".join(out) + "\n"


def run_one(binary, outdir, kind, packing, name):
    run = os.path.join(outdir, name)
    cfg = run + ".toml"
    # A variant whose config exists was run (or is running in another
    # invocation): delete RUN.toml and RUN/ to run it again.
    if os.path.exists(cfg):
        return name
    with open(cfg, "w") as f:
        f.write(config_text(kind, packing, variant_keys(name)))
    env = dict(os.environ, OMP_NUM_THREADS="1", OMP_WAIT_POLICY="passive", TOMOGRAIN_QUIET="1")
    t0 = time.time()
    p = subprocess.run(["nice", "-n", "19", "/usr/bin/time", "-f", "%e %U %S", binary, "dem", "oedometer", cfg, "-o", run],
                       env=env, capture_output=True, text=True)
    wall, user, sys_ = (float(x) for x in p.stderr.strip().splitlines()[-1].split())
    with open(run + ".time", "w") as f:
        json.dump({"wall_s": wall, "cpu_s": user + sys_, "rc": p.returncode, "stderr": p.stderr[-2000:],
                   "started": t0}, f)
    if p.returncode != 0:
        open(run + ".stopped", "w").write(p.stderr)
    return name


def figures(outdir, name, kind):
    run = os.path.join(outdir, name)
    # A run still going (no .time yet): its figures so far (history.csv is
    # flushed at checkpoints and snapshots).
    t = json.load(open(run + ".time")) if os.path.exists(run + ".time") else {"rc": 0, "wall_s": None, "cpu_s": None}
    row = {"variant": name, "wall_s": t["wall_s"], "cpu_s": t["cpu_s"]}
    if t["rc"] != 0:
        msg = [l for l in t["stderr"].splitlines() if "tomograin" in l]
        row["stopped"] = (msg[-1] if msg else t["stderr"].strip().splitlines()[-1])[:160]
        return row
    h = read_csv(f"{run}/history.csv")
    info = json.load(open(f"{run}/run.json"))
    n0, h0 = int(info["spheres"]), info["initial_height_m"]
    sig, eps = h["top_stress_Pa"], h["strain"]
    sy = yield_stress_mpa(run) * 1e6

    def first(cond):
        return next((i for i in range(len(sig)) if cond(i)), None)

    def mean_sigma(e0):
        v = [s for s, e in zip(sig, eps) if abs(e - e0) <= 0.0025]
        return statistics.mean(v) / 1e6 if v else float("nan")

    def broken(i):
        return None if i is None else (int(h["grains_broken"][i]), int(h["bonds_broken"][i]))

    last = len(sig) - 1
    row["at_2"] = broken(first(lambda i: sig[i] >= 2e6))
    row.update(yield_MPa=sy / 1e6, s10=mean_sigma(0.10), s1548=mean_sigma(0.1548), smax=max(sig) / 1e6,
               at_yield=broken(first(lambda i: sig[i] >= sy)), at_4=broken(first(lambda i: sig[i] >= 4e6)),
               at_end=broken(last), intact_pct=100 * h["grains_broken"][last] / n0,
               end_strain=eps[last], spheres=int(h["spheres"][last]), fines=int(h["fines_removed"][last]),
               dropped=int(h["bonds_dropped"][last]), gen1plus=int(sum(h[f"splits_gen{g}"][last] for g in (1, 2, 3))))
    bins = [0] * 5
    split_steps = []
    if os.path.exists(f"{run}/splits.csv"):
        sp = read_csv(f"{run}/splits.csv")
        for g, z, tt, st in zip(sp.get("generation", []), sp.get("z_m", []), sp.get("time_s", []), sp.get("step", [])):
            split_steps.append(int(st))
            if g == 0:
                bins[min(4, max(0, int(z / (h0 - 0.1 * tt) * 5)))] += 1
    row["fifths"] = bins
    # Wall friction shows as a bottom stress below the top one: their ratio,
    # mean over the rows past 5 % strain (loaded, not seating).
    ratios = [b / t for b, t, e in zip(h["bottom_stress_Pa"], sig, eps) if e > 0.05 and t > 0]
    row["bottom_top"] = statistics.mean(ratios) if ratios else float("nan")
    row["added_mass"] = float(h["added_mass_fraction"][last])
    if kind == "small":
        ke, steps = h["kinetic_energy_J"], [int(s) for s in h["step"]]
        jumps = []
        for st in sorted(set(split_steps)):
            k = next((i for i in range(len(steps)) if steps[i] >= st), None)
            if k is None or k == 0 or ke[k - 1] <= 0:
                continue
            jumps.append(max(ke[k:k + 20]) / ke[k - 1])
        row["ke_jump_median"] = statistics.median(jumps) if jumps else float("nan")
        row["ke_jump_max"] = max(jumps) if jumps else float("nan")
    return row


def table(outdir, kind):
    def started(n):  # finished, stopped, or running with history rows
        history = os.path.join(outdir, n, "history.csv")
        return os.path.exists(os.path.join(outdir, n + ".time")) or (os.path.exists(history) and os.path.getsize(history) > 0)

    names = sorted((f[:-5] for f in os.listdir(outdir) if f.endswith(".toml")), key=lambda n: os.path.getmtime(os.path.join(outdir, n + ".toml")))
    names = [n for n in names if started(n)]
    rows = [figures(outdir, n, kind) for n in names]
    fmt = lambda p: "-" if p is None else f"{p[0]} / {p[1]}"
    print("| variant | yield MPa | σ at 10 / 15.48 % MPa (max) | grains / bonds broken at yield | at 4 MPa | at end "
          "| intact broken % | per fifth, bottom → top | σ_bottom / σ_top | gen ≥ 1 splits / fines / spheres "
          "| added mass % | KE ×, median / max | wall / CPU s |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        if "stopped" in r:
            print(f"| {r['variant']} | stopped: {r['stopped']} | | | | | | | | | | | {r['wall_s']:.0f} / {r['cpu_s']:.0f} |")
            continue
        ke = (f"{r['ke_jump_median']:.2f} / {r['ke_jump_max']:.1f}" if "ke_jump_median" in r else "-")
        end = "" if r["end_strain"] >= 0.1547 else f" (at {100 * r['end_strain']:.2f} %)"
        times = "running" if r["wall_s"] is None else f"{r['wall_s']:.0f} / {r['cpu_s']:.0f}"
        if r["wall_s"] is None:  # the bilinear fit needs the whole curve
            r["yield_MPa"], r["at_yield"] = float("nan"), None
        print(f"| {r['variant']} | {r['yield_MPa']:.2f} | {r['s10']:.2f} / {r['s1548']:.2f} ({r['smax']:.2f}) "
              f"| {fmt(r['at_yield'])} | {fmt(r['at_4'])} | {fmt(r['at_end'])}{end} | {r['intact_pct']:.1f} "
              f"| {', '.join(map(str, r['fifths']))} | {r['bottom_top']:.2f} | {r['gen1plus']} / {r['fines']} / {r['spheres']} "
              f"| {100 * r['added_mass']:.1f} | {ke} "
              f"| {times} |")


def stress_table(outdir):
    """Rows by the issue's targets: yield, peak, grains / bonds broken when the stress first
    reaches 2 and 4 MPa, bonds per broken grain there, % intact broken at the end, fifths, CPU."""
    names = sorted((f[:-5] for f in os.listdir(outdir) if f.endswith(".toml") and os.path.exists(os.path.join(outdir, f[:-5] + ".time"))),
                   key=lambda n: os.path.getmtime(os.path.join(outdir, n + ".toml")))
    fmt = lambda p: "never" if p is None else f"{p[0]} / {p[1]}"
    per = lambda p: "-" if p is None or p[0] == 0 else f"{p[1] / p[0]:.0f}"
    print("| run | yield MPa | σ peak MPa | grains / bonds at 2 MPa | at 4 MPa | bonds per broken grain at 4 MPa "
          "| intact broken at 15.48 % | per fifth, bottom → top | CPU s |")
    print("|---|---|---|---|---|---|---|---|---|")
    for n in names:
        r = figures(outdir, n, "full")
        if "stopped" in r:
            print(f"| {n} | stopped: {r['stopped']} | | | | | | | {r['cpu_s']:.0f} |")
            continue
        end = "" if r["end_strain"] >= 0.1547 else f" (at {100 * r['end_strain']:.2f} %)"
        print(f"| {n} | {r['yield_MPa']:.2f} | {r['smax']:.2f} | {fmt(r['at_2'])} | {fmt(r['at_4'])} | {per(r['at_4'])} "
              f"| {r['intact_pct']:.1f} %{end} | {', '.join(map(str, r['fifths']))} | {r['cpu_s']:.0f} |")


def main():
    if len(sys.argv) < 3:
        raise SystemExit(__doc__)
    kind = sys.argv[1]
    if kind == "config" and len(sys.argv) == 5:
        sys.stdout.write(config_text(sys.argv[2], os.path.abspath(sys.argv[3]), variant_keys(sys.argv[4])))
        return
    if kind == "stress_table":
        stress_table(sys.argv[2])
        return
    if kind == "table":
        outdir = sys.argv[2]
        table(outdir, json.load(open(os.path.join(outdir, "kind.json")))["kind"])
        return
    jobs = 2
    args = sys.argv[2:]
    if args and args[0].startswith("-j"):
        jobs, args = int(args[0][2:]), args[1:]
    binary, outdir = os.path.abspath(args[0]), args[1]
    os.environ.setdefault("TOMOGRAIN", binary)  # the yield of the figures: the same binary's rule
    if kind == "small":
        packing, names = os.path.join(ROOT, "tests/apps/data/crash_pack.csv"), args[2:] or list(VARIANTS)
    elif kind == "full":
        packing, names = args[2], args[3:]
    else:
        raise SystemExit(__doc__)
    for n in names:
        variant_keys(n)  # unknown names and malformed keys stop here, before any run
    os.makedirs(outdir, exist_ok=True)
    json.dump({"kind": kind}, open(os.path.join(outdir, "kind.json"), "w"))
    with ThreadPoolExecutor(jobs) as ex:
        for n in ex.map(lambda n: run_one(binary, outdir, kind, packing, n), names):
            print(f"done {n}", flush=True)
    table(outdir, kind)


if __name__ == "__main__":
    main()
