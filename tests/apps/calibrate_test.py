"""`tomograin dem calibrate` end to end (issue 21), on the committed demo-cell
packing (data/crash_pack.csv) compressed to 2.5 % strain, 3 runs: the target
is a run of that cell with sigma_t0 = 3.5 MPa (3 grains split before 2.5 %;
much stronger grains do not split by then; the time step stays at 1e-7 s
after splits, density scaling, to keep the test short). Checks: every output exists;
runs.csv has a row per run with its parameters inside the ranges; best.toml
is the config with the best run's parameters and runs as it is; the
proposals and every figure are the same with --jobs 1 and --jobs 2 (only
the wall times differ); with a crush target (2 grains) the crush term gets
a GP of its own; a used output folder is refused. 6.6 s on the shared
2-core VM beside a calibration (1.6 s of it the plot's matplotlib).
"""
import csv
import json
import os
import shutil
import subprocess
import sys
import tomllib

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import pyharness as H  # noqa: E402

PACKING = os.path.join(H.TESTS, "apps", "data", "crash_pack.csv")
CFG = ("[walls]\ncylinder_radius_m = 4.0e-3\n[specimen]\npacking_csv = \"pack.csv\"\n"
       "[oedometer]\ntarget_strain = 0.025\nsnapshot_strains = [0.0]\nhistory_every_steps = 250\n"
       "[breakage]\nmin_time_step_s = 1.0e-7\nmin_split_diameter_m = 7.0e-4\n")


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def main():
    with H.workdir("tg_calib_"):
        shutil.copyfile(PACKING, "pack.csv")
        with open("cfg.toml", "w") as f:
            f.write(CFG)
        with open("target_cfg.toml", "w") as f:
            f.write(CFG + "sigma_t0_Pa = 3.5e6\n")
        subprocess.run([H.TG, "dem", "oedometer", "target_cfg.toml", "-o", "target"], env=H.ENV, check=True,
                       stdout=subprocess.DEVNULL)
        with open("target.toml", "w") as f:
            f.write('[target]\nstress_strain_csv = "target/history.csv"\n'
                    "[parameters]\nsigma_t0_Pa = [3.0e6, 9.0e6]\n")
        outs = {}
        for jobs in (1, 2):
            out = f"cal{jobs}"
            r = subprocess.run([H.TG, "dem", "calibrate", "cfg.toml", "--target", "target.toml", "-o", out,
                                "--runs", "3", "--initial", "2", "--seed", "5", "--jobs", str(jobs)]
                               + ([] if jobs == 1 else ["--no-plot"]),
                               env=H.ENV, capture_output=True, text=True)
            H.check(r.returncode == 0, f"calibrate --jobs {jobs} exits 0 ({r.stderr.strip()[-300:]})")
            outs[jobs] = out
        out = outs[1]
        for name in ("runs.csv", "best.toml", "calibration.json", "surface.csv", "objective_surface.png"):
            H.check(os.path.exists(os.path.join(out, name)), f"{name} written")
        runs = rows(os.path.join(out, "runs.csv"))
        H.check(len(runs) == 3 and all(r["status"] == "ok" for r in runs), f"3 runs, all ok ({len(runs)})")
        sig = [float(r["sigma_t0_Pa"]) for r in runs]
        lam = [float(r["bond_radius_multiplier"]) for r in runs]
        H.check(all(3e6 <= s <= 9e6 for s in sig) and all(0.8 <= x <= 1.6 for x in lam),
                f"parameters inside the ranges ({sig}, {lam})")
        # The Latin hypercube: one of the 2 initial runs in each half of each range.
        H.check(sorted(int((s - 3e6) / 6e6 * 2) for s in sig[:2]) == [0, 1]
                and sorted(int((x - 0.8) / 0.8 * 2) for x in lam[:2]) == [0, 1], "initial runs form a Latin hypercube")
        meta = json.load(open(os.path.join(out, "calibration.json")))
        j = [float(r["objective"]) for r in runs]
        best = min(range(3), key=lambda i: j[i])
        H.check(meta["best"]["run"] == f"run_{best:03d}" and abs(meta["best"]["objective"] - j[best]) < 1e-12,
                f"calibration.json names the lowest objective ({meta['best']['run']}, {j})")
        H.check(meta["objective"]["weights"] == {"stress_strain": 1.0, "yield_stress": 0.0, "broken_fraction": 0.0,
                                                 "broken_at_stress": 0.0, "bonds_at_stress": 0.0, "crush": 0.0},
                f"weights stated ({meta['objective']['weights']})")
        # best.toml sets the best run's parameters and runs as it is.
        b = tomllib.load(open(os.path.join(out, "best.toml"), "rb"))["breakage"]
        H.check(b["sigma_t0_Pa"] == sig[best] and b["bond_radius_multiplier"] == lam[best],
                f"best.toml has the best run's parameters ({b})")
        r = subprocess.run([H.TG, "dem", "oedometer", os.path.join(out, "best.toml"), "-o", "best_run"], env=H.ENV,
                           capture_output=True, text=True)
        H.check(r.returncode == 0, f"best.toml runs ({r.stderr.strip()[-200:]})")
        if r.returncode == 0:
            a = open("best_run/history.csv").read()
            b = open(os.path.join(out, "runs", f"run_{best:03d}", "history.csv")).read()
            H.check(a == b, "best.toml reproduces the best run's history bit for bit")
        # --jobs changes nothing but the wall times.
        r1, r2 = rows(os.path.join(outs[1], "runs.csv")), rows(os.path.join(outs[2], "runs.csv"))
        strip = lambda rs: [{k: v for k, v in r.items() if k != "seconds"} for r in rs]  # noqa: E731
        H.check(strip(r1) == strip(r2), "runs.csv identical with --jobs 1 and 2 (but seconds)")
        # With a crush target the crush term is modelled apart (dem/calibration/README.md step 4):
        # calibration.json says so and gives log b's GP; every run has its crush mean.
        with open("target_crush.toml", "w") as f:
            f.write('[target]\nstress_strain_csv = "target/history.csv"\n'
                    "[crush]\nbonds_broken = 20.0\ngrains = 2\n[parameters]\nsigma_t0_Pa = [3.0e6, 9.0e6]\n")
        r = subprocess.run([H.TG, "dem", "calibrate", "cfg.toml", "--target", "target_crush.toml", "-o", "calc",
                            "--runs", "3", "--initial", "2", "--seed", "5", "--jobs", "2", "--no-plot"],
                           env=H.ENV, capture_output=True, text=True)
        H.check(r.returncode == 0, f"calibrate with a crush target exits 0 ({r.stderr.strip()[-300:]})")
        if r.returncode == 0:
            c = json.load(open(os.path.join("calc", "calibration.json")))
            cr = rows(os.path.join("calc", "runs.csv"))
            H.check(c["surrogate"]["crush_term_modelled_apart"] is True and "log_crush_bonds" in c["surrogate"],
                    f"the crush term has its own GP ({c['surrogate']})")
            H.check(len(cr) == 3 and all(float(x["crush_bonds_broken"]) > 0 for x in cr),
                    f"every run has its crush mean ({[x['crush_bonds_broken'] for x in cr]})")
            H.check(not meta["surrogate"]["crush_term_modelled_apart"] and "log_crush_bonds" not in meta["surrogate"],
                    "without a crush target one GP of the objective")
        # A second calibrate into a used folder is refused, nothing touched.
        r = subprocess.run([H.TG, "dem", "calibrate", "cfg.toml", "--target", "target.toml", "-o", out],
                           env=H.ENV, capture_output=True, text=True)
        H.check(r.returncode == 2 and "not empty" in r.stderr, f"used output folder refused ({r.stderr.strip()})")
    H.finish()


if __name__ == "__main__":
    main()
