#!/usr/bin/python3
"""Every flag of segment, measure, synth, convert, info, voxelise and dem, once (issue 25).

Table-driven: each row runs one command with one flag (or one value of a
choice) added to a base invocation and checks a visible effect, computed
here from the outputs with numpy/h5py: mostly "the output differs from the
base run's" (the flag reached an option), and where the effect is known, the
effect itself (a dtype, a file, a count, a column). A flag whose wiring is
broken (parsed but never copied into the options) leaves the output as the
base run's and fails its row. Not here: `psd` and `compare` (the report's
own tests), `analyse` and `demo` (tests/apps/analyse_test.sh, cli.demo).

Inputs are made at test time, small: `synth --preset spheres --size 64`
(a few seconds), its labels for measure, a 4-grain packing for voxelise and
the committed 126-grain packing (tests/apps/data/crash_pack.csv) for dem.

Usage: flags_test.py TOMOGRAIN
"""
import csv
import hashlib
import json
import math
import os
import shutil
import subprocess
import sys

import h5py
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import pyharness as H  # noqa: E402
from pyharness import TG, ENV, check  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))


def run(args, ok=True):
    r = subprocess.run([TG] + args, env=ENV, capture_output=True, text=True)
    if ok and r.returncode != 0:
        check(False, f"{' '.join(args)}: exit {r.returncode}: {r.stderr.strip()[:200]}")
    return r


def digest(path, dataset=None):
    """Hash of a dataset's values (HDF5) or of the file's bytes."""
    if dataset:
        with h5py.File(path, "r") as f:
            a = f[dataset][()]
            return hashlib.sha256(np.ascontiguousarray(a).tobytes() + str(a.dtype).encode()).hexdigest()
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def info(path):
    return json.loads(run(["info", path, "--json"]).stdout)


def rows(path):
    return list(csv.DictReader(open(path)))


def segment_rows(base):
    # (flags, what must hold) -- "differs": /labels differ from the base run's.
    return [
        (["--threshold", "otsu"], "differs"),
        (["--threshold", "manual", "--manual-value", "20000"], "differs"),
        (["--no-pores"], "differs"),
        (["--pore-max-vox", "1"], "differs"),
        (["--pore-min-sphericity", "0.99"], ("pores", "min_sphericity", 0.99)),  # no pore of this crop is that round
        (["--h", "3"], "differs"),
        (["--connectivity", "6"], "differs"),
        (["--no-lines"], "differs"),
        (["--buckets-per-voxel", "1"], "differs"),
        (["--no-merge"], ("merge", "enabled", False)),  # intact grains: nothing to merge
        # Grey evidence: this crop's contacts are dim, so no interface is
        # bright enough to merge at any ratio; the ratio shows on the plain mask.
        (["--merge-ratio", "0.2", "--no-grey-evidence"], "differs"),
        (["--no-grey-evidence"], "differs"),
        (["--bright-fraction", "0.1"], "differs"),
        (["--bright-sigmas", "0"], ("grey_evidence", "bright_sigmas", 0.0)),
        (["--pore-shell", "0"], ("grey_evidence", "pore_shell_vox", 0)),
        (["--min-size", "5000"], "differs"),
        # Split repair: this crop's grains are whole, so the options show in the summary.
        (["--no-split"], ("split", "enabled", False)),
        # Noise specks: this crop has none at its noise, so the options show in the summary.
        (["--keep-noise-specks"], ("noise_specks", "enabled", False)),
        (["--speck-z", "7"], ("noise_specks", "z_crit", 7.0)),
        (["--split-depth-sigmas", "3"], ("split", "depth_sigmas", 3.0)),
        (["--split-depth-sigmas-correlated", "5"], ("split", "depth_sigmas_correlated", 5.0)),
        (["--split-min-depth-contrast", "0.3"], ("split", "min_depth_contrast", 0.3)),
        (["--split-min-piece", "0.05"], ("split", "min_piece_fraction", 0.05)),
        (["--split-smoothing-vox", "1.5"], ("split", "smoothing_sigma_vox", 1.5)),
        # The scale: recorded in the summary (the labels of this crop do not
        # move with it: it sets only the default pore size limit).
        (["--grain-radius-vox", "10"], ("grain_radius_vox", None, 10.0)),
        (["--grain-diameter-um", "400"], ("grain_radius_vox", None, 400 / 2 / 30)),
        # Real-scan options (docs/real_scans.md): this crop has no constant
        # outside, so detection finds nothing and --no-fov shows in the summary only.
        (["--threshold", "local", "--local-window-vox", "32"], "differs"),
        (["--local-window-vox", "40"], ("threshold", "local", {"window_vox": 40})),
        (["--fov-radius-vox", "30"], "differs"),
        (["--fov-radius-vox", "30", "--fov-centre-vox", "30,50"], ("field_of_view", "centre_yx", [30.0, 50.0])),
        (["--no-fov"], ("field_of_view", "detection", False)),
        (["--compress", "0"], "bigger"),
        (["--summary", "other.json"], "summary"),
        # --config: the file's keys are the options (otsu.toml: threshold = "otsu",
        # no_merge = true); an option on the command line wins over the file.
        (["--config", "otsu.toml"], ("threshold", "method", "otsu")),
        (["--config", "otsu.toml"], ("merge", "enabled", False)),
        (["--config", "otsu.toml", "--threshold", "moments"], ("threshold", "method", "moments")),
    ]


def main():
    with H.workdir("tg_flags_"):
        # ------------------------------------------------------------ synth
        with open("otsu.toml", "w") as f:
            f.write('threshold = "otsu"\nno_merge = true\n')
        run(["synth", "--preset", "spheres", "--size", "64", "-o", "s.h5"])
        base_grey = digest("s.h5", "/volume")
        for flags, what in [(["--seed", "2"], "differs"), (["--voxel-um", "7"], "voxel"),
                            (["--size", "48"], "shape"), (["--float"], "float")]:
            out = "syn_" + flags[0].strip("-") + ".h5"
            size = [] if flags[0] == "--size" else ["--size", "64"]
            run(["synth", "--preset", "spheres", "-o", out] + size + flags)
            with h5py.File(out, "r") as f:
                if what == "differs":
                    check(digest(out, "/volume") != base_grey, f"synth {' '.join(flags)}: another scan")
                elif what == "voxel":
                    vs = info(out)["voxel_size_um_zyx"]
                    check(vs == [7.0, 7.0, 7.0], f"synth --voxel-um 7: voxel size {vs}")
                elif what == "shape":
                    check(f["/volume"].shape == (48, 48, 48), f"synth --size 48: shape {f['/volume'].shape}")
                elif what == "float":
                    check("/reconstruction" in f and f["/reconstruction"].dtype == np.float32,
                          "synth --float: /reconstruction is float32")
        scene = "scene.toml"
        with open(scene, "w") as f:
            f.write("seed = 5\n")
        r = run(["synth", "--preset", "spheres", "--size", "64", "--scene", scene, "-o", "syn_scene.h5"], ok=False)
        check(r.returncode == 0 and digest("syn_scene.h5", "/volume") != base_grey,
              f"synth --scene (seed 5): another scan (exit {r.returncode}: {r.stderr.strip()[:120]})")
        r = run(["synth", "--preset", "extremes", "--size", "48", "-o", "ext"], ok=False)
        check(r.returncode == 0, f"synth --preset extremes (exit {r.returncode})")
        # The extremes through segment and measure: each ends with exit 0 and
        # a table, or refuses with exit 2 and one line naming the file.
        for name in ("tiny", "border", "empty", "solid", "saturated"):
            scan = f"ext_{name}.h5"
            r = run(["segment", scan, "-o", f"ext_{name}_seg.h5", "--grain-radius-vox", "5"], ok=False)
            lines = r.stderr.strip().splitlines()
            if r.returncode != 0:
                check(r.returncode == 2 and len(lines) == 1 and scan in lines[0],
                      f"segment {scan}: refused cleanly (exit {r.returncode}: {r.stderr.strip()[:160]})")
                continue
            r = run(["measure", f"ext_{name}_seg.h5", "-o", f"ext_{name}.csv"], ok=False)
            ok = r.returncode == 0 and os.path.exists(f"ext_{name}.csv")
            t = rows(f"ext_{name}.csv") if ok else []
            if name in ("empty", "solid"):
                # No grains to find: the segmenter still cuts the noise
                # (empty: 8 labels) but says so in its summary.
                notes = json.load(open(f"ext_{name}_seg.segment.json"))["notes"]
                ok = ok and any("bimodal" in n for n in notes)
            if name == "border":
                ok = ok and any(x["touches_border"] in ("1", "1.0", "true") for x in t)
            check(ok, f"segment + measure {scan}: exit {r.returncode}, {len(t)} particles {r.stderr.strip()[:120]}")

        # ---------------------------------------------------------- segment
        # A crop of the zeolite specimen (intra-granular pores, grains of
        # radius ~22 voxels that touch): every segment option has work to do.
        run(["synth", "--preset", "zeolite", "--voxel-um", "30", "--size", "80", "-o", "z.h5"])
        run(["segment", "z.h5", "-o", "zseg.h5", "--grain-radius-vox", "22"])
        base_lab = digest("zseg.h5", "/labels")
        size0 = os.path.getsize("zseg.h5")
        for k, (flags, what) in enumerate(segment_rows(base_lab)):
            out = f"seg_{k}.h5"
            extra = [] if any(f.startswith("--grain") for f in flags) else ["--grain-radius-vox", "22"]
            run(["segment", "z.h5", "-o", out] + extra + flags)
            name = "segment " + " ".join(flags)
            if what == "differs":
                check(digest(out, "/labels") != base_lab, f"{name}: other labels")
            elif what == "bigger":
                check(os.path.getsize(out) > size0 and digest(out, "/labels") == base_lab,
                      f"{name}: same labels, uncompressed file ({os.path.getsize(out)} vs {size0} bytes)")
            elif isinstance(what, tuple):  # recorded in the summary: (section, key, value)
                j = json.load(open(out.replace(".h5", ".segment.json")))[what[0]]
                v = j if what[1] is None else j[what[1]]
                if isinstance(what[2], dict):  # a sub-object: these keys with these values
                    same = all(v.get(k2) == v2 for k2, v2 in what[2].items())
                elif isinstance(what[2], (bool, list, str)):
                    same = v == what[2]
                else:
                    same = abs(v - what[2]) < 1e-9
                check(same, f"{name}: summary {what[0]} {what[1] or ''} = {v} (expected {what[2]})")
            elif what == "summary":
                check(os.path.exists("other.json") and json.load(open("other.json")), f"{name}: the summary is there")

        # ---------------------------------------------------------- measure
        run(["segment", "s.h5", "-o", "seg.h5", "--grain-diameter-um", "400"])
        run(["measure", "seg.h5", "-o", "m.csv"])
        base = rows("m.csv")
        # The box's base run is the "--box" row's (m_box.csv, above the
        # "--seed" row): a CGAL box search per particle (~20 ms each) was
        # most of this test's time, so the box rows read a corner of the
        # labels (seg_box.h5, ~40 particles) and the base is not run twice.
        run(["convert", "seg.h5", "-o", "seg_box.h5", "--crop", "0:24,0:24,0:24"])
        box_rows = {"--box", "--seed", "--sizing"}
        base_box = lambda: rows("m_box.csv")
        col = lambda t, c: [float(r[c]) for r in t]
        checks = [
            (["--feret", "exact"], lambda t: t[0]["sizing"] == "feret-exact" and col(t, "d_min_mm") != col(base, "d_min_mm")),
            (["--feret", "12"], lambda t: t[0]["sizing"] == "feret-12"),
            (["--sizing", "obb"], lambda t: t[0]["sizing"] == "obb" and col(t, "d_max_mm") == col(t, "obb_max_mm")),
            (["--detection-limit-mm", "10"], lambda t: all(r["below_limit"] in ("1", "1.0", "true") for r in t)),
            (["--face-offset", "0.9"], lambda t: col(t, "d_max_mm") != col(base, "d_max_mm")),
            (["--box"], lambda t: all(float(r["obb_max_mm"]) > 0 for r in t)),
            (["--no-box"], lambda t: all(float(r["obb_max_mm"]) == 0 for r in t)),  # the default since issue 22
            (["--seed", "7", "--box"], lambda t: col(t, "obb_max_mm") != col(base_box(), "obb_max_mm") or
             col(t, "obb_min_mm") != col(base_box(), "obb_min_mm")),
            (["--no-contacts"], lambda t: "coordination" not in t[0] and "coordination" in base[0]),
            (["--convex"], lambda t: "convex_volume_mm3" in t[0] and "solidity" in t[0] and "solidity" not in base[0]),
            (["--surface"], lambda t: "surface_mm2" in t[0] and "surface_mm2" not in base[0]),
            (["--columns", "sphericity"], lambda t: "sphericity" in t[0] and "convex_volume_mm3" not in t[0]),
            (["--voxel-um", "10"], lambda t: abs(float(t[0]["volume_mm3"]) /
                                                 float(base[0]["volume_mm3"]) - (10 / voxel_um()) ** 3) < 1e-9),
            (["--threads", "2"], lambda t: t == base),  # no effect by design: results do not depend on it
        ]

        def voxel_um():
            return info("seg.h5")["voxel_size_um_zyx"][0]

        for flags, ok in checks:
            out = "m_" + flags[0].strip("-") + ".csv"
            run(["measure", "seg_box.h5" if flags[0] in box_rows else "seg.h5", "-o", out] + flags)
            check(os.path.exists(out) and ok(rows(out)), "measure " + " ".join(flags))
        # Two outputs at once.
        run(["measure", "seg.h5", "-o", "m2.csv", "-o", "m2.h5"])
        with h5py.File("m2.h5", "r") as f:
            check("/particles" in f or any("particles" in k for k in f.keys()), "measure -o a.csv -o a.h5: the .h5 holds the table")

        # ---------------------------------------------------------- convert
        run(["convert", "s.h5", "-o", "c.tif"])
        run(["convert", "c.tif", "-o", "c_f.h5", "--to", "float32"])
        with h5py.File("c_f.h5", "r") as f:
            check(f["/volume"].dtype == np.float32, "convert --to float32")
        run(["convert", "c_f.h5", "-o", "c_u.h5", "--to", "uint16", "--range", "0,65535"])
        run(["convert", "c_f.h5", "-o", "c_u2.h5", "--to", "uint16"])
        check(digest("c_u.h5", "/volume") != digest("c_u2.h5", "/volume"), "convert --range 0,65535 vs auto: other grey values")
        run(["convert", "s.h5", "-o", "c0.h5", "--compress", "0"])
        run(["convert", "s.h5", "-o", "c9.h5", "--compress", "9"])
        check(os.path.getsize("c0.h5") > os.path.getsize("c9.h5"), "convert --compress 0 vs 9: bigger file")

        # ------------------------------------------------------------- info
        r = run(["info", "s.h5", "--json"])
        try:
            j = json.loads(r.stdout)
            check(j["shape_zyx"] == [64, 64, 64] and j["dtype"] == "uint16", f"info --json: shape and dtype ({r.stdout[:100]!r})")
        except json.JSONDecodeError:
            check(False, f"info --json: not JSON ({r.stdout[:100]!r})")

        # --------------------------------------------------------- voxelise
        with open("spheres.csv", "w") as f:
            f.write("x_m,y_m,z_m,r_m,particle\n0,0,0.5e-3,2e-4,1\n4e-4,0,0.5e-3,2e-4,1\n0,5e-4,0.5e-3,2e-4,2\n"
                    "-5e-4,-2e-4,0.5e-3,1.5e-4,3\n")
        run(["voxelise", "spheres.csv", "-o", "v.h5", "--voxel-um", "20"])
        vbase = digest("v.h5", "/volume")
        vshape = h5py.File("v.h5", "r")["/volume"].shape
        for flags, what in [
            (["--voxel-um", "10"], "shape"), (["--margin", "5"], "shape"),
            (["--field", "cylinder", "--cylinder-mm", "3"], "shape"),
            (["--void-grey", "5000"], "grey"), (["--solid-grey", "30000"], "grey"), (["--noise", "0"], "grey"),
            (["--psf", "0"], "grey"), (["--seed", "9"], "grey"), (["--field", "cylinder"], "grey"),
            (["--like", "s.h5"], "grey"), (["--no-grey"], "nogrey"),
            (["--cluster-body", "members"], "grey")]:  # particle 1: two tangent spheres, not their hull
            out = "v_" + flags[0].strip("-") + ".h5"
            args = ["voxelise", "spheres.csv", "-o", out] + (["--voxel-um", "20"] if flags[0] != "--voxel-um" else []) + flags
            r = run(args, ok=False)
            name = "voxelise " + " ".join(flags)
            if r.returncode != 0:
                check(False, f"{name}: exit {r.returncode}: {r.stderr.strip()[:160]}")
                continue
            with h5py.File(out, "r") as f:
                if what == "shape":
                    check(f["/labels"].shape != vshape if "/labels" in f else f["/volume"].shape != vshape, f"{name}: other shape")
                elif what == "grey":
                    check(digest(out, "/volume") != vbase, f"{name}: other grey values")
                elif what == "nogrey":
                    check("/volume" not in f and "/labels" in f, f"{name}: labels only")

        # -------------------------------------------------------------- dem
        shutil.copyfile(os.path.join(HERE, "data", "crash_pack.csv"), "pack.csv")
        cfg = ("[walls]\ncylinder_radius_m = 4.0e-3\n[specimen]\npacking_csv = \"pack.csv\"\n[run]\nthreads = 1\n"
               "[oedometer]\ntarget_strain = 0.002\nsnapshot_strains = [0.0, 0.002]\nhistory_every_steps = 200\n"
               "checkpoint_every_steps = 2000\n[breakage]\nenabled = false\n")
        open("o.toml", "w").write(cfg)
        run(["dem", "oedometer", "o.toml", "-o", "oed"])
        h = rows("oed/history.csv")
        check(abs(float(h[-1]["strain"]) - 0.002) < 1e-4, f"dem oedometer -o: ran to 0.2 % ({h[-1]['strain']})")
        # --restart: a run stopped by SIGKILL is tests/apps/crash_restart_test.py's;
        # here, a fresh folder cannot be restarted (no checkpoint): exit 2.
        r = run(["dem", "oedometer", "o.toml", "-o", "fresh", "--restart"], ok=False)
        check(r.returncode == 2 and not os.path.exists("fresh/history.csv"),
              f"dem oedometer --restart without a checkpoint: exit {r.returncode}, nothing written")
        # Past the first split (5.3 % of d with the default strength draw).
        base = run(["dem", "crush", "-o", "cr0.csv", "--travel", "0.08"])
        c0 = rows("cr0.csv")
        strength = lambda r: float(r.stdout.split("grain strength ")[1].split()[0])
        last = lambda t, c: float(t[-1][c])
        for flags, ok in [
            (["-d", "1.0e-3"], lambda t: t != c0),
            (["--speed", "0.05"], lambda t: t != c0),
            (["--travel", "0.02"], lambda t: len(t) < len(c0)),
            (["--d0", "2e-3"], lambda t: t != c0),
            (["--seed", "4"], lambda t: t != c0),
            (["--min-split", "1e-2"], lambda t: t != c0),  # nothing that small splits... nor the grain
            (["--min-dt", "1e-9"], lambda t: t != c0),
            (["--bond-radius-multiplier", "1.6"], lambda t: t != c0)]:
            out = "cr_" + flags[0].strip("-") + ".csv"
            args = ["dem", "crush", "-o", out] + (["--travel", "0.08"] if flags[0] != "--travel" else []) + flags
            run(args)
            check(os.path.exists(out) and ok(rows(out)), "dem crush " + " ".join(flags))
        # --model: an oedometer config's breakage options (here sigma_t0 doubled, d0 as the
        # command's default): the drawn strength is sigma_t0 times a factor of the seed and size,
        # so it doubles; an option given on the command line still wins over the config.
        open("model.toml", "w").write("[breakage]\nsigma_t0_Pa = 24.0e6\nd0_m = 1.0e-3\n")
        rm = run(["dem", "crush", "-o", "crm.csv", "--travel", "0.08", "--model", "model.toml"])
        check(abs(strength(rm) / strength(base) - 2) < 2e-3,
              f"dem crush --model: strength {strength(rm)} MPa, twice {strength(base)} MPa")
        r = run(["dem", "crush", "-o", "crm2.csv", "--travel", "0.08", "--model", "model.toml", "--d0", "2e-3"])
        # Weibull size effect: strength ~ (d / d0)^(-3/m) with m = 3, so doubling d0 doubles it.
        check(abs(strength(r) / strength(rm) - 2) < 2e-3, f"dem crush --model CONFIG --d0 2e-3: the option wins ({strength(r)} MPa)")
        r = run(["dem", "crush", "-o", "crm3.csv", "--model", "missing.toml"], ok=False)
        check(r.returncode == 2 and not os.path.exists("crm3.csv"), "dem crush --model missing.toml: exit 2, nothing written")
        # dem yield: a curve whose two lines (0.01 and 0.15 strain per decade of stress) meet at
        # exactly 2 MPa; a floor of 1 MPa leaves fewer points, the same yield.
        stresses = [0.12 * 10 ** (0.05 * k) for k in range(40)]  # MPa, 0.12 .. 10.4
        with open("curve.csv", "w") as f:
            f.write("strain,stress_Pa\n")
            for sp in stresses:
                e = 0.01 * math.log10(sp / 0.1) if sp <= 2 else 0.01 * math.log10(20) + 0.15 * math.log10(sp / 2)
                f.write(f"{e!r},{sp * 1e6!r}\n")
        y = run(["dem", "yield", "curve.csv"]).stdout.split()
        check(abs(float(y[1]) - 2.0) < 1e-6 and int(y[5]) == 40, f"dem yield: {y[1]} MPa from {y[5]} points, the lines meet at 2 MPa")
        y = run(["dem", "yield", "curve.csv", "--floor-mpa", "1"]).stdout.split()
        above = sum(sp > 1 for sp in stresses)
        check(abs(float(y[1]) - 2.0) < 1e-6 and int(y[5]) == above,
              f"dem yield --floor-mpa 1: {y[1]} MPa from {y[5]} points ({above} above 1 MPa)")
        r = run(["dem", "yield", "o.toml"], ok=False)
        check(r.returncode == 2 and "o.toml" in r.stderr, f"dem yield o.toml: exit {r.returncode}, the file named")


main()
H.finish()
