#!/usr/bin/python3
"""A campaign's key figures in one table and one plot (issue 24).

Reads every study's summary.csv (written by `tomograin run`'s `summary`
step: one row per comparison of experiment and DEM) and writes
  campaign.csv  every row of every study, a first column `study` added; the
                columns are the union of the studies' columns, in order of
                first appearance (a study without a column leaves it empty);
  campaign.png  one panel per key figure (every numeric column whose name
                holds one of KEY_FIGURES: D50, Cu, % broken, yield, KS
                distances), the experiment's and the DEM's value side by
                side, one group of bars per row (study / variant).

Usage: campaign_summary.py -o campaign.csv [--plot campaign.png] NAME=SUMMARY_CSV ...
Bad input (a missing or empty summary.csv, rows longer than the header): one
line naming the file and the problem, exit 2, nothing written.
"""
import argparse
import csv
import os
import sys
import tempfile

# Key figures by the words their column names hold (case-insensitive).
KEY_FIGURES = ("d50", "cu", "broken", "yield", "ks")


def fail(msg):
    print(f"campaign_summary: {msg}", file=sys.stderr)
    sys.exit(2)


def read_summary(name, path):
    try:
        with open(path, newline="") as f:
            rows = list(csv.reader(f))
    except OSError as e:
        fail(f"{path}: {e.strerror}")
    if not rows or not rows[0]:
        fail(f"{path}: empty (no header)")
    header = rows[0]
    out = []
    for i, r in enumerate(rows[1:], start=2):
        if len(r) != len(header):
            fail(f"{path}: line {i} has {len(r)} cells, the header {len(header)}")
        out.append(dict(zip(header, r), study=name))
    return header, out


def number(cell):
    try:
        return float(cell)
    except (TypeError, ValueError):
        return None


def write_atomic(path, write):
    """write(tmp_path) then rename: an error never leaves a half-written file."""
    d = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(dir=d, prefix=".tmp_", suffix=os.path.splitext(path)[1])
    os.close(fd)
    try:
        write(tmp)
        os.replace(tmp, path)
    except BaseException:
        os.unlink(tmp)
        raise


def panels(columns, rows):
    """Key-figure columns grouped into panels: the experiment's and the DEM's
    value of a quantity side by side (d50_mm_experiment, d50_mm_dem -> d50_mm),
    the KS distances together. {title: [columns]} in column order."""
    out = {}
    for c in columns:
        if c == "study" or not any(k in c.lower() for k in KEY_FIGURES):
            continue
        if not any(number(r.get(c)) is not None for r in rows):
            continue
        if c.lower().endswith("_ks"):
            title = "KS distance, experiment vs DEM"
        else:
            title = c.removesuffix("_experiment").removesuffix("_dem")
        out.setdefault(title, []).append(c)
    return out


def plot(columns, rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    groups = panels(columns, rows)
    labels = [r["study"] + (f" / {r['variant']}" if r.get("variant") else "") for r in rows]
    n = max(len(groups), 1)
    ncol = min(n, 3)
    nrow = (n + ncol - 1) // ncol
    fig, axes = plt.subplots(nrow, ncol, figsize=(4.5 * ncol, 3.4 * nrow), squeeze=False)
    x = range(len(rows))
    for ax, (title, cols) in zip(axes.flat, groups.items()):
        width = 0.8 / len(cols)
        for i, c in enumerate(cols):
            # A missing value (no DEM, no fit) is NaN: no bar.
            vals = [number(r.get(c)) for r in rows]
            vals = [v if v is not None else float("nan") for v in vals]
            ax.bar([k - 0.4 + width * (i + 0.5) for k in x], vals, width,
                   label=c.removeprefix(title).strip("_") or c)
        ax.set_title(title, fontsize=9)
        ax.set_xticks(list(x))
        ax.set_xticklabels(labels, rotation=90, fontsize=6)
        if len(cols) > 1:
            ax.legend(fontsize=6)
    for ax in list(axes.flat)[len(groups):]:
        ax.axis("off")
    if not groups:
        axes.flat[0].text(0.5, 0.5, "no key figures in the summaries", ha="center", va="center")
    studies = len({r["study"] for r in rows})
    fig.suptitle(f"campaign: {studies} studies, {len(rows)} rows", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110, format="png")
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("-o", required=True, help="campaign.csv")
    ap.add_argument("--plot", help="campaign.png")
    ap.add_argument("studies", nargs="+", metavar="NAME=SUMMARY_CSV")
    a = ap.parse_args()
    columns, rows = ["study"], []
    for s in a.studies:
        name, sep, path = s.partition("=")
        if not sep or not name:
            fail(f"'{s}': expected NAME=SUMMARY_CSV")
        header, r = read_summary(name, path)
        columns += [c for c in header if c not in columns]
        rows += r

    def write_csv(tmp):
        with open(tmp, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=columns, restval="", lineterminator="\n")
            w.writeheader()
            w.writerows(rows)

    # The plot first: if it fails, neither file is written.
    if a.plot:
        write_atomic(a.plot, lambda tmp: plot(columns, rows, tmp))
    write_atomic(a.o, write_csv)
    print(f"campaign_summary: {len(rows)} rows from {len(a.studies)} studies -> {a.o}"
          + (f", {a.plot}" if a.plot else ""))


main()
