"""What the Python end-to-end tests of `tomograin` share (tests/apps/*_test.py,
tests/determinism/determinism_test.py): the program under test and its quiet
environment, the ok/FAIL record, a scratch working folder, bit-for-bit
comparison of HDF5 files, and the demo's DEM cell as a packing config.

A test script imports it with its own folder's parent on the path (ctest runs
the scripts by absolute path, so this works from any working directory):

    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    import pyharness as H

Usage of a test built on it: TEST.py TOMOGRAIN [ARGS]; TG_KEEP=1 keeps its
scratch folder (printed) for a look after a failure.
"""
import contextlib
import hashlib
import json
import os
import shutil
import sys
import tempfile

import h5py
import numpy as np

TESTS = os.path.dirname(os.path.abspath(__file__))
TG = os.path.abspath(sys.argv[1]) if len(sys.argv) > 1 else None
# Single-threaded and without progress output unless a test says otherwise.
ENV = dict(os.environ, TOMOGRAIN_QUIET="1", OMP_NUM_THREADS="1")

failures = []


def check(cond, what):
    """Print one ok/FAIL line and remember the failures for finish()."""
    print(("ok   " if cond else "FAIL ") + what, flush=True)
    if not cond:
        failures.append(what)


def finish():
    """The last line of a test's output and its exit status."""
    print(f"{'FAILED' if failures else 'passed'}: {len(failures)} failure(s)")
    sys.exit(1 if failures else 0)


@contextlib.contextmanager
def workdir(prefix):
    """A fresh temporary folder as the working directory, removed afterwards
    (kept, and its path printed, when TG_KEEP is set)."""
    w = tempfile.mkdtemp(prefix=prefix)
    os.chdir(w)
    try:
        yield w
    finally:
        os.chdir("/")
        if os.environ.get("TG_KEEP") is None:
            shutil.rmtree(w, ignore_errors=True)
        else:
            print("kept", w)


def same_bytes(a, b):
    with open(a, "rb") as fa, open(b, "rb") as fb:
        return fa.read() == fb.read()


def drop(obj, dotted):
    """Remove the key at a dotted path ("a.b.c") of a parsed JSON object, if there."""
    keys = dotted.split(".")
    for k in keys[:-1]:
        obj = obj.get(k, {})
    obj.pop(keys[-1], None)


def h5_diffs(a, b, json_ignored=lambda name, attr: None, timing_keys=()):
    """Differences between two HDF5 files: the set of objects, every attribute
    (dtype, shape, bytes) and every dataset (dtype, shape, bytes). Not the
    file bytes: HDF5 stores object times. An attribute for which
    json_ignored(object name, attribute name) gives a list of dotted keys
    holds JSON text, compared parsed without those keys; with timing_keys,
    every attribute holding a JSON object is compared parsed, without those
    keys at any depth. [] when identical."""
    out = []
    with h5py.File(a, "r") as fa, h5py.File(b, "r") as fb:
        na, nb = [], []
        fa.visit(na.append)
        fb.visit(nb.append)
        if sorted(na) != sorted(nb):
            return [f"objects differ: {sorted(set(na) ^ set(nb))}"]
        for name in ["/"] + na:
            oa, ob = fa[name], fb[name]
            if set(oa.attrs) != set(ob.attrs):
                out.append(f"{name}: attribute names differ")
            for k in oa.attrs:
                ignored = json_ignored(name, k)
                text = oa.attrs[k].decode() if isinstance(oa.attrs[k], bytes) else oa.attrs[k]
                if ignored is None and timing_keys and isinstance(text, str) and text.startswith("{"):
                    ignored = []
                if ignored is not None:
                    ja, jb = json.loads(oa.attrs[k]), json.loads(ob.attrs[k])
                    for key in ignored:
                        drop(ja, key)
                        drop(jb, key)
                    ja, jb = json_without(ja, timing_keys), json_without(jb, timing_keys)
                    if ja != jb:
                        out.append(f"{name}@{k}: JSON differs")
                    continue
                va, vb = np.asarray(oa.attrs[k]), np.asarray(ob.attrs[k])
                if va.dtype != vb.dtype or va.shape != vb.shape or va.tobytes() != vb.tobytes():
                    out.append(f"{name}@{k}: {va} vs {vb}")
            if isinstance(oa, h5py.Dataset):
                if oa.dtype != ob.dtype or oa.shape != ob.shape:
                    out.append(f"{name}: dtype/shape differ")
                    continue
                x, y = np.asarray(oa[()]), np.asarray(ob[()])
                if x.tobytes() != y.tobytes():
                    if x.dtype.kind in "fiu":
                        xf, yf = x.astype(float), y.astype(float)
                        out.append(f"{name}: {int(np.sum(xf != yf))} of {x.size} values differ, "
                                   f"max |diff| {np.max(np.abs(xf - yf)):.3g}")
                    else:
                        out.append(f"{name}: contents differ")
    return out


def tree_state(d):
    """Every file under d with its size, mtime and content hash: equal before
    and after a command that must not touch the tree."""
    out = {}
    for root, _, files in os.walk(d):
        for f in files:
            p = os.path.join(root, f)
            st = os.stat(p)
            with open(p, "rb") as fh:
                out[os.path.relpath(p, d)] = (st.st_size, st.st_mtime_ns, hashlib.sha256(fh.read()).hexdigest())
    return out


# JSON keys that hold timings, memory peaks or thread counts (segment's
# summary, compare's report.json, the DEM's run.json, a study's step records):
# what differs between two runs that must otherwise be identical.
TIMING_KEYS = {"seconds", "seconds_total", "compute_seconds", "imaging_s", "render_s", "peak_rss_bytes",
               "peak_rss_bytes_per_voxel", "threads"}


def json_without(obj, keys):
    """A parsed JSON object with every key named in `keys` removed at any depth
    (timings such as "seconds" sit at many levels of a report)."""
    if isinstance(obj, dict):
        return {k: json_without(v, keys) for k, v in obj.items() if k not in keys}
    if isinstance(obj, list):
        return [json_without(v, keys) for v in obj]
    return obj


def tree_diffs(a, b, ignored=None, ignored_h5_json=None, skip=lambda rel: False, timing_keys=()):
    """Differences between two output trees, file by file: {relative path: [what differs]}.
    .h5 by object (h5_diffs), .json parsed without the dotted keys ignored[rel]
    and without any key in timing_keys at any depth (also inside JSON held by
    the HDF5 attributes named in ignored_h5_json[(rel, object, attribute)]),
    anything else byte for byte. Files only one tree has are reported under
    "(file set)". Files for which skip(rel) is true are not compared."""
    ignored, ignored_h5_json = ignored or {}, ignored_h5_json or {}

    def files(d):
        out = set()
        for root, _, fs in os.walk(d):
            out |= {os.path.relpath(os.path.join(root, f), d) for f in fs}
        return {r for r in out if not skip(r)}

    fa, fb = files(a), files(b)
    diffs = {}
    if fa != fb:
        diffs["(file set)"] = [f"only in one tree: {sorted(fa ^ fb)}"]
    for rel in sorted(fa & fb):
        x, y = os.path.join(a, rel), os.path.join(b, rel)
        if rel.endswith(".h5"):
            d = h5_diffs(x, y, lambda name, attr, rel=rel: ignored_h5_json.get((rel, name, attr)), timing_keys)
        elif rel.endswith(".json"):
            ja, jb = json.load(open(x)), json.load(open(y))
            for k in ignored.get(rel, []):
                drop(ja, k)
                drop(jb, k)
            ja, jb = json_without(ja, timing_keys), json_without(jb, timing_keys)
            d = [] if ja == jb else [f"JSON differs: {json.dumps(ja)[:200]} vs {json.dumps(jb)[:200]}"]
        else:
            d = [] if same_bytes(x, y) else ["bytes differ"]
        if d:
            diffs[rel] = d
    return diffs, sorted(fa & fb)


DEMO_TOML = os.path.join(TESTS, "..", "dem", "examples", "demo.toml")


def demo_cell_pack_config(extra=""):
    """dem/examples/demo.toml (the demo's Ø8 mm cell, ~130 grains) pressed to
    its target height of 6 mm: the free deposit's height varies with its
    realisation (6.55-7.06 mm over seeds 1-5), and a loose one saw no split
    before the end of a short run (seen when the force sums changed order).
    `extra` is appended (more tables)."""
    with open(DEMO_TOML) as f:
        text = f.read()
    assert "[pluviation]\n" in text, DEMO_TOML
    return text.replace("[pluviation]\n", "[pluviation]\npress_to_target_height = true\n", 1) + extra


def weak_grain_run_config(run, oedometer="", breakage="", strain=0.04):
    """A short oedometer run of a demo-cell packing (pack.csv in the working
    folder, e.g. the committed tests/apps/data/crash_pack.csv) to `strain`
    (4 %), snapshots at 0, half of it and all of it, a history row every 200 steps. Weak grains
    (sigma_t0 3 MPa instead of 12) so the first split comes at ~1-2 % strain,
    well before the end; fragments (d < 0.7 mm) do not split again, which
    keeps the time step (and the test) short. `run`, `oedometer`, `breakage`:
    more keys of those tables, one "key = value\\n" each."""
    return ("[walls]\ncylinder_radius_m = 4.0e-3\n"
            "[specimen]\npacking_csv = \"pack.csv\"\n"
            f"[run]\n{run}"
            f"[oedometer]\ntarget_strain = {strain}\nsnapshot_strains = [0.0, {strain / 2}, {strain}]\n"
            "history_every_steps = 200\n"
            f"{oedometer}"
            "[breakage]\nenabled = true\nsigma_t0_Pa = 3.0e6\nmin_split_diameter_m = 7.0e-4\n"
            f"{breakage}")
