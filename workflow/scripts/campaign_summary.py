#!/usr/bin/python3
"""A campaign's key figures in one table and one plot (issue 24).

Reads every study's summary.csv (written by `tomograin run`'s `summary`
step: one row per comparison of experiment and DEM) and writes
  campaign.csv  every row of every study, a first column `study` added; the
                columns are the union of the studies' columns, in order of
                first appearance (a study without a column leaves it empty);
  campaign.png  one panel per key figure (D50, Cu, % broken, yield, KS
                distances: every numeric column whose name holds one of
                KEY_FIGURES), one bar per row, grouped by study.

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


def plot(columns, rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figures = [c for c in columns if c != "study" and any(k in c.lower() for k in KEY_FIGURES)
               and any(number(r.get(c)) is not None for r in rows)]
    labels = [r["study"] + (f"\n{r[columns[1]]}" if columns[1] != "study" and number(r.get(columns[1])) is None
                             else "") for r in rows]
    n = max(len(figures), 1)
    ncol = min(n, 3)
    nrow = (n + ncol - 1) // ncol
    fig, axes = plt.subplots(nrow, ncol, figsize=(4.2 * ncol, 3.2 * nrow + 0.6 * (len(rows) > 6)), squeeze=False)
    studies = sorted({r["study"] for r in rows}, key=[r["study"] for r in rows].index)
    colours = {s: plt.cm.tab10(i % 10) for i, s in enumerate(studies)}
    for ax, c in zip(axes.flat, figures):
        vals = [number(r.get(c)) for r in rows]
        ax.bar(range(len(rows)), [v if v is not None else 0.0 for v in vals],
               color=[colours[r["study"]] for r in rows])
        ax.set_title(c, fontsize=9)
        ax.set_xticks(range(len(rows)))
        ax.set_xticklabels(labels, rotation=90, fontsize=6)
    for ax in list(axes.flat)[len(figures):]:
        ax.axis("off")
    if not figures:
        axes.flat[0].text(0.5, 0.5, "no key figures in the summaries", ha="center", va="center")
    fig.suptitle(f"campaign: {len(studies)} studies, {len(rows)} comparisons", fontsize=10)
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
