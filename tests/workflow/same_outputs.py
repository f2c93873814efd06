#!/usr/bin/python3
"""Are two runs of the same studies identical? (issue 24: a campaign run by
Snakemake locally, on SLURM, or by `tomograin run` by hand.)

Compares every file under two folders as tests/determinism/determinism_test.py
does: .h5 by object, dataset and attribute (pyharness.h5_diffs; not the file
bytes, HDF5 stores object times), .json parsed without the fields that
depend on the run rather than the data (is_run_field, at any depth, also
inside JSON held by an HDF5 attribute), .html with its compute times masked,
everything else byte for byte. Left out:
what is about the run, not its results (SKIP: Snakemake's logs and benchmark
files, tomograin run's hash cache, whose entries carry file times).

As a module: diffs(a, b) -> list of (relative path, problem). As a program:
  same_outputs.py DIR_A DIR_B   prints one line per difference; exit 1 if any.
"""
import fnmatch
import json
import os
import re
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import pyharness as H  # noqa: E402

# JSON keys that hold timings, memory peaks or thread counts (segment's
# summary, the run records, run.json, compare's report.json): "threads", and
# names that start with "seconds" or "peak_rss" or end in "_s" or "_seconds".


def is_run_field(key):
    return (key == "threads" or key.startswith(("seconds", "peak_rss")) or key.endswith(("_s", "_seconds")))


def html_without_times(text):
    """compare's index.html shows the compute time twice: "Compute time: X s"
    and the last column of the stages' table, headed "time (s)". Both masked."""
    text = re.sub(r"Compute time: [0-9.]+ s", "Compute time: T s", text)
    parts = text.split("<table")
    for i, t in enumerate(parts):
        if "time (s)</th></tr>" in t:
            parts[i] = re.sub(r"<td>[0-9.eE+-]+</td></tr>", "<td>T</td></tr>", t)
    return "<table".join(parts)
# Paths (relative, fnmatch patterns) that are about the run, not its results.
SKIP = ["logs/*", "benchmarks/*", ".snakemake/*", "*/.run/hashes.json", ".run/hashes.json",
        "*/.run/*.lock", ".run/*.lock"]


def without_run_fields(obj):
    if isinstance(obj, dict):
        return {k: without_run_fields(v) for k, v in obj.items() if not is_run_field(k)}
    if isinstance(obj, list):
        return [without_run_fields(v) for v in obj]
    return obj


def _files(d):
    out = set()
    for root, _, fs in os.walk(d):
        for f in fs:
            rel = os.path.relpath(os.path.join(root, f), d)
            if not any(fnmatch.fnmatch(rel, p) for p in SKIP):
                out.add(rel)
    return out


def _h5_json_attr(a, name, attr):
    """Which keys to drop from an HDF5 attribute that holds JSON (None: not JSON)."""
    import h5py
    with h5py.File(a, "r") as f:
        v = f[name].attrs[attr]
    if isinstance(v, bytes):
        v = v.decode("utf-8", "replace")
    if not isinstance(v, str):
        return None
    try:
        parsed = json.loads(v)
    except ValueError:
        return None
    return sorted(_keys_in(parsed))


def _keys_in(obj, prefix=""):
    """Dotted paths of every run field in a parsed JSON object."""
    out = set()
    if isinstance(obj, dict):
        for k, v in obj.items():
            p = f"{prefix}{k}"
            if is_run_field(k):
                out.add(p)
            else:
                out |= _keys_in(v, p + ".")
    return out


def diffs(a, b):
    fa, fb = _files(a), _files(b)
    out = [(rel, f"only in {a if rel in fa else b}") for rel in sorted(fa ^ fb)]
    for rel in sorted(fa & fb):
        pa, pb = os.path.join(a, rel), os.path.join(b, rel)
        if rel.endswith(".h5"):
            d = H.h5_diffs(pa, pb, lambda name, attr: _h5_json_attr(pa, name, attr))
        elif rel.endswith(".json"):
            with open(pa) as x, open(pb) as y:
                same = without_run_fields(json.load(x)) == without_run_fields(json.load(y))
            d = [] if same else ["JSON differs (run fields left out)"]
        elif rel.endswith(".html"):
            with open(pa) as x, open(pb) as y:
                same = html_without_times(x.read()) == html_without_times(y.read())
            d = [] if same else ["HTML differs (compute times masked)"]
        else:
            d = [] if H.same_bytes(pa, pb) else ["bytes differ"]
        out += [(rel, p) for p in d]
    return out


def count_files(d):
    return len(_files(d))


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit("usage: same_outputs.py DIR_A DIR_B")
    found = diffs(sys.argv[1], sys.argv[2])
    for rel, problem in found:
        print(f"DIFF {rel}: {problem}")
    print(f"{count_files(sys.argv[1])} files compared, {len(found)} difference(s)")
    sys.exit(1 if found else 0)
