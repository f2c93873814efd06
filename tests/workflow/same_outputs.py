#!/usr/bin/python3
"""Are two runs of the same campaign identical? (issue 24: Snakemake locally,
Snakemake on SLURM, `tomograin run` by hand.) Both must have written to the
same path (outputs name their own files; each step's key hashes its
arguments), one of them moved away afterwards.

pyharness.tree_diffs compares the files: HDF5 by object, dataset and
attribute, JSON without TIMING_KEYS at any depth (the step records in .run/
too: step and key must match, only "seconds" is left out), the rest byte for
byte. Two additions here:
  - compare's index.html prints the compute time twice ("Compute time: X s"
    and the stages' table's last column, "time (s)"): compared with those
    masked (html_without_times);
  - left out, being about the run and not its results (SKIP): Snakemake's
    logs/ and benchmarks/, tomograin run's hash cache (file times) and step
    locks, and the DEM's splits.csv logs (per process by design: a resumed
    run writes splits_after_restart.csv, tests/apps/crash_restart_test.py).

As a module: diffs(a, b) -> {relative path: [what differs]}. As a program:
  same_outputs.py DIR_A DIR_B   prints one line per difference; exit 1 if any.
"""
import fnmatch
import os
import re
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import pyharness as H  # noqa: E402

SKIP = ["logs/*", "benchmarks/*", "*.run/hashes.json", "*.run/*.lock", "*/splits.csv", "*/splits_after_restart.csv"]


def html_without_times(text):
    text = re.sub(r"Compute time: [0-9.]+ s", "Compute time: T s", text)
    parts = text.split("<table")
    for i, t in enumerate(parts):
        if "time (s)</th></tr>" in t:
            parts[i] = re.sub(r"<td>[0-9.eE+-]+</td></tr>", "<td>T</td></tr>", t)
    return "<table".join(parts)


def _skipped(rel):
    return any(fnmatch.fnmatch(rel, p) for p in SKIP)


def diffs(a, b):
    """{relative path: [what differs]} between the trees a and b; {} when identical."""
    found, _ = H.tree_diffs(a, b, skip=lambda rel: _skipped(rel) or rel.endswith(".html"), timing_keys=H.TIMING_KEYS)
    for rel in sorted(html_files(a) & html_files(b)):
        with open(os.path.join(a, rel)) as x, open(os.path.join(b, rel)) as y:
            if html_without_times(x.read()) != html_without_times(y.read()):
                found[rel] = ["HTML differs (compute times masked)"]
    only = html_files(a) ^ html_files(b)
    if only:
        found.setdefault("(file set)", []).append(f"only in one tree: {sorted(only)}")
    return found


def html_files(d):
    return {r for r in files(d) if r.endswith(".html")}


def files(d):
    """The files compared (relative paths)."""
    out = set()
    for root, _, fs in os.walk(d):
        out |= {os.path.relpath(os.path.join(root, f), d) for f in fs}
    return {r for r in out if not _skipped(r)}


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit("usage: same_outputs.py DIR_A DIR_B")
    found = diffs(sys.argv[1], sys.argv[2])
    for rel, problems in found.items():
        print(f"DIFF {rel}: {'; '.join(problems)[:300]}")
    print(f"{len(files(sys.argv[1]))} files compared, {len(found)} differ")
    sys.exit(1 if found else 0)
