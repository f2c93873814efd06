#!/usr/bin/python3
"""Plots and the HTML page of a tomograin comparison report.

Usage: /usr/bin/python3 make_report.py REPORT_DIR

Reads what `tomograin compare` (compare/comparison.cpp) wrote into REPORT_DIR
(report.json, summary.csv, psd.csv, shape_classes.csv, distances.csv,
stress_strain.csv, broken.csv, fabric.csv, normals.csv, coordination_by_size.csv,
slices/*.npy) and writes one PNG per plot plus
index.html, which embeds every PNG as base64 so it opens offline on its own.
Needs Debian's python3-numpy and python3-matplotlib (Agg backend, no display).
"""
import base64
import csv
import html
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

SERIES_STYLE = {
    "experiment": dict(color="black", ls="-", marker="o", label="experiment (XCT)"),
    "dem_ideal": dict(color="tab:blue", ls="--", marker="s", label="DEM ideal (truth labels)"),
    "dem_imaged": dict(color="tab:red", ls="-.", marker="^", label="DEM imaged (segmented)"),
}
# The reference study's published figures (shared/reference/zeolite-xct-dem-paper.md: text
# of its Figs. 9-14), drawn as markers beside this report's numbers: yield near 2 MPa;
# 20 grains / 300 bonds broken before yield and 280 / 10 000 when the stress reaches
# 4 MPa (DEM); % of intact grains broken at 15.48 % strain (DEM 35, experiment ~70);
# at the end, particles with FR 0.9-1.0 (experiment 81 %, DEM 78 %) and AR 1-2 (71 %, 80 %).
STUDY = dict(yield_mpa=2.0, broken_at_mpa=[(2.0, 20, 300), (4.0, 280, 10000)], end_strain=0.1548,
             pct_intact_broken_end=dict(dem=35.0, experiment=70.0),
             fr_top_class_end=dict(experiment=81.0, dem=78.0), ar_first_class_end=dict(experiment=71.0, dem=80.0))
STUDY_STYLE = dict(color="tab:purple", ls="none", marker="*", ms=11)

# The contact tables add the DEM's own contacts, from its spheres; the shape classes its
# particles' shapes from their spheres, every particle however small (the study's DEM count).
CONTACT_STYLE = dict(SERIES_STYLE, dem_exact=dict(color="tab:green", ls=":", marker="d",
                                                 label="DEM exact (its sphere contacts)"))
CLASS_STYLE = dict(SERIES_STYLE, dem_exact=dict(color="tab:green", ls=":", marker="d",
                                               label="DEM exact (every particle, from its spheres)"))


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def fnum(v):
    try:
        return float(v)
    except (TypeError, ValueError):
        return float("nan")


def fmt(v, digits=3):
    if v is None:
        return "–"
    v = fnum(v)
    return "–" if v != v else f"{v:.{digits}g}"


def save(fig, out, name):
    path = os.path.join(out, name)
    fig.savefig(path, dpi=90, bbox_inches="tight")
    plt.close(fig)
    return name


def stage_panels(stages):
    """One panel per stage, three to a row."""
    cols = min(len(stages), 3)
    rows = (len(stages) + cols - 1) // cols
    return plt.subplots(rows, cols, figsize=(4.2 * cols, 3.4 * rows), squeeze=False)


def plot_psd(out, stages, psd):
    fig, axes = stage_panels(stages)
    for ax, st in zip(axes.flat, stages):
        for series, style in SERIES_STYLE.items():
            pts = [(fnum(r["sieve_mm"]), fnum(r["passing_pct"])) for r in psd
                   if r["stage"] == st["name"] and r["series"] == series]
            if pts:
                x, y = zip(*pts)
                ax.semilogx(x, y, ms=3, **style)
        ax.set_title(st["name"], fontsize=9)
        ax.set_xlabel("Dmed (mm)")
        ax.set_ylabel("passing by mass (%)")
        ax.grid(True, which="both", alpha=0.3)
        ax.set_ylim(-2, 102)
    for ax in list(axes.flat)[len(stages):]:
        ax.axis("off")
    axes.flat[0].legend(fontsize=7)
    fig.suptitle("Particle size distribution by mass (Dmed)")
    return save(fig, out, "psd.png")


def plot_classes(out, stages, rows_, metric, classes, title):
    fig, ax = plt.subplots(figsize=(max(6, 2.4 * len(stages)), 3.6))
    series = [s for s in CLASS_STYLE if any(r["series"] == s for r in rows_)]
    width = 0.8 / (len(series) * len(classes))
    x0 = np.arange(len(stages))
    for si, s in enumerate(series):
        for ci, c in enumerate(classes):
            vals = []
            for st in stages:
                v = [fnum(r["percent"]) for r in rows_ if r["stage"] == st["name"] and r["series"] == s
                     and r["metric"] == metric and r["class"] == c]
                vals.append(v[0] if v else np.nan)
            off = (si * len(classes) + ci) * width - 0.4 + width / 2
            ax.bar(x0 + off, vals, width, color=CLASS_STYLE[s]["color"], alpha=0.35 + 0.65 * (ci + 1) / len(classes),
                   label=f"{CLASS_STYLE[s]['label']}: {metric.upper()} {c}")
            # The study's end-of-test share of the class it reports (FR 0.9-1.0, AR 1-2), over the
            # last stage's bar of the same series when that stage is at the study's end strain
            # (within 1 %): experiment beside the scan, DEM beside both DEM series.
            study = STUDY["fr_top_class_end"] if metric == "fr" else STUDY["ar_first_class_end"]
            last = stages[-1] if stages else {}
            e = fnum((last.get("experiment" if s == "experiment" else "dem") or {}).get("strain"))
            if abs(e - STUDY["end_strain"]) <= 0.01 and ci == (len(classes) - 1 if metric == "fr" else 0):
                ax.plot([x0[-1] + off], [study["experiment" if s == "experiment" else "dem"]], **STUDY_STYLE,
                        label="study, end of test" if si == 0 else None)
    ax.set_xticks(x0)
    ax.set_xticklabels([st["name"] for st in stages], fontsize=8)
    ax.set_ylabel("particles (%)")
    ax.set_title(title)
    ax.legend(fontsize=6, ncol=len(series), loc="upper center", bbox_to_anchor=(0.5, -0.15))
    return save(fig, out, f"{metric}.png")


def save_strain_plot(fig, ax, out, ylabel, title, name):
    """The frame shared by the plots against axial strain (stress, broken grains), then save()."""
    ax.set_xlabel("axial strain (%)")
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(title)
    return save(fig, out, name)


def plot_stress(out, ss, yld):
    """Linear and e–log σ (strain against log σ, as the study's Fig. 9), yield by report.json's rule."""
    fig, (ax, lx) = plt.subplots(1, 2, figsize=(11, 3.8))
    any_ = False
    for series, style in [("dem", dict(color="tab:red", label="DEM (history.csv)")),
                          ("experiment", dict(color="black", label="experiment"))]:
        pts = [(fnum(r["axial_strain"]), fnum(r["stress_mpa"])) for r in ss if r["series"] == series]
        if pts:
            any_ = True
            x, y = map(np.array, zip(*pts))
            ax.plot(100 * x, y, **style)
            pos = y > 0
            lx.semilogx(y[pos], 100 * x[pos], **style)
            v = fnum(yld.get(f"{series}_mpa"))
            if v == v:
                lx.axvline(v, color=style["color"], ls=":", lw=1.2, label=f"{series} yield {v:.2f} MPa")
    if not any_:
        ax.text(0.5, 0.5, "no stress–strain data given", ha="center", va="center", transform=ax.transAxes)
    lx.axvline(STUDY["yield_mpa"], color=STUDY_STYLE["color"], ls="--", lw=1, label="study: yield ≈ 2 MPa")
    lx.invert_yaxis()
    lx.set_xlabel("axial stress (MPa, log)")
    lx.set_ylabel("axial strain (%) — void ratio falls downward")
    lx.grid(True, which="both", alpha=0.3)
    lx.legend(fontsize=7)
    lx.set_title("e–log σ form" + (f" (yield: {yld['rule']})" if yld.get("rule") else ""), fontsize=8)
    return save_strain_plot(fig, ax, out, "axial stress (MPa)", "Stress–strain", "stress_strain.png")


def plot_broken_counts(out, br, ss):
    """Grains and bonds broken against the stress reached (running maximum of the DEM's σ_top),
    so that the study's counts at yield and at 4 MPa (its Fig. 10 text) sit on the same axis."""
    hist = [r for r in br if r["series"] == "dem_history"]
    curve = [fnum(r["stress_mpa"]) for r in ss if r["series"] == "dem"]
    if not hist or len(curve) != len(hist):
        return None
    reached = np.maximum.accumulate(np.nan_to_num(np.array(curve), nan=0.0))
    grains = np.array([fnum(r.get("grains_broken")) for r in hist])
    bonds = np.array([fnum(r.get("bonds_broken")) for r in hist])
    fig, ax = plt.subplots(figsize=(5.8, 3.8))
    pos = reached > 0
    ax.semilogx(reached[pos], grains[pos], color="tab:red", label="DEM grains broken")
    bx = ax.twinx()
    if np.isfinite(bonds).any():
        bx.semilogx(reached[pos], bonds[pos], color="tab:orange", ls="--", label="DEM bonds broken")
    for k, (mpa, g, b) in enumerate(STUDY["broken_at_mpa"]):
        ax.plot([mpa], [g], label="study: grains" if k == 0 else None, **STUDY_STYLE)
        bx.plot([mpa], [b], color=STUDY_STYLE["color"], ls="none", marker="P", ms=9,
                label="study: bonds" if k == 0 else None)
    ax.set_xlabel("axial stress reached (MPa, log)")
    ax.set_ylabel("grains broken")
    bx.set_ylabel("bonds broken")
    ax.grid(True, which="both", alpha=0.3)
    h1, l1 = ax.get_legend_handles_labels()
    h2, l2 = bx.get_legend_handles_labels()
    ax.legend(h1 + h2, l1 + l2, fontsize=7, loc="upper left")
    ax.set_title("Broken grains and bonds (study's Fig. 10: markers at yield and at 4 MPa)", fontsize=9)
    return save(fig, out, "broken_counts.png")


def plot_height(out, lin):
    """Grains broken per fifth of the height at the last tracked stage, per series (study's Fig. 11)."""
    if not lin:
        return None
    last = lin[-1]["stage"]  # rows in stage order
    rows_ = [r for r in lin if r["stage"] == last]
    fig, ax = plt.subplots(figsize=(5.8, 3.6))
    width = 0.8 / len(rows_)
    colors = dict(experiment="black", dem_exact="tab:green", dem_imaged="tab:red")
    for k, r in enumerate(rows_):
        vals = [fnum(r[f"pct_broken_band{b}"]) for b in range(1, 6)]
        ax.bar(np.arange(1, 6) - 0.4 + width * (k + 0.5), vals, width, color=colors.get(r["series"], "grey"),
               alpha=0.8, label=r["series"])
    ax.set_xticks(range(1, 6))
    ax.set_xticklabels(["1 bottom", "2", "3", "4", "5 top (moving)"], fontsize=8)
    ax.set_xlabel("fifth of the specimen height")
    ax.set_ylabel("intact grains broken (%)")
    ax.legend(fontsize=7)
    ax.set_title(f"Breakage by height, {last} (study: more near the platens)", fontsize=9)
    return save(fig, out, "breakage_by_height.png")


def study_table(stages, cls, br, ss, yld, fr_classes, ar_classes):
    """This report's DEM and experiment beside the study's published figures."""
    rows_ = [["yield stress (MPa)", fmt(yld.get("experiment_mpa")), fmt(yld.get("dem_mpa")), "≈ 2 (both)"]]
    hist = [r for r in br if r["series"] == "dem_history"]
    curve = [fnum(r["stress_mpa"]) for r in ss if r["series"] == "dem"]
    if hist and len(curve) == len(hist):
        reached = np.maximum.accumulate(np.nan_to_num(np.array(curve), nan=0.0))
        for mpa, g, b in STUDY["broken_at_mpa"]:
            i = int(np.argmax(reached >= mpa)) if (reached >= mpa).any() else None
            dem = "not reached" if i is None else f"{fmt(hist[i]['grains_broken'])} / {fmt(hist[i]['bonds_broken'])}"
            rows_.append([f"grains / bonds broken when σ first reaches {mpa:g} MPa", "–", dem, f"{g} / {b} (DEM)"])
    end = stages[-1]["name"]

    def cls_pct(series, metric, name):
        v = [r["percent"] for r in cls if r["stage"] == end and r["series"] == series and r["metric"] == metric
             and r["class"] == name]
        return fmt(v[0]) if v else "–"
    # DEM: imaged at the scan's voxel size (resolved particles) / every particle from its spheres.
    rows_.append([f"particles with FR {fr_classes[-1]} at {end} (%)", cls_pct("experiment", "fr", fr_classes[-1]),
                  f'{cls_pct("dem_ideal", "fr", fr_classes[-1])} / {cls_pct("dem_exact", "fr", fr_classes[-1])}',
                  f"{STUDY['fr_top_class_end']['experiment']:g} / {STUDY['fr_top_class_end']['dem']:g} (FR 0.9–1.0)"])
    rows_.append([f"particles with AR {ar_classes[0]} at {end} (%)", cls_pct("experiment", "ar", ar_classes[0]),
                  f'{cls_pct("dem_ideal", "ar", ar_classes[0])} / {cls_pct("dem_exact", "ar", ar_classes[0])}',
                  f"{STUDY['ar_first_class_end']['experiment']:g} / {STUDY['ar_first_class_end']['dem']:g} (AR 1–2)"])
    return table(["quantity", "experiment (this report)",
                  "DEM (this report; shape classes: imaged, resolved particles / every particle from its spheres)",
                  "study: experiment / DEM"], rows_)


def plot_broken(out, br):
    fig, ax = plt.subplots(figsize=(5.5, 3.8))
    for series, style in [("dem_history", dict(color="tab:red", ls="-", label="DEM history")),
                          ("dem", dict(color="tab:red", ls="none", marker="^", label="DEM at compared stages")),
                          ("experiment", dict(color="black", ls="none", marker="o", label="experiment stages"))]:
        pts = [(fnum(r["axial_strain"]), fnum(r["broken_fraction"])) for r in br if r["series"] == series]
        pts = [p for p in pts if p[0] == p[0] and p[1] == p[1]]
        if pts:
            x, y = zip(*pts)
            ax.plot(100 * np.array(x), 100 * np.array(y), **style)
    for series, mark in [("experiment", "*"), ("dem", "P")]:
        ax.plot([100 * STUDY["end_strain"]], [STUDY["pct_intact_broken_end"][series]], color=STUDY_STYLE["color"],
                ls="none", marker=mark, ms=10, label=f"study: {series} at 15.48 %")
    return save_strain_plot(fig, ax, out, "grains broken (%)", "Broken grains vs strain", "broken.png")


def plot_distances(out, stages, dist):
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.4))
    pairs = [("experiment_vs_dem_imaged", "tab:red"), ("experiment_vs_dem_ideal", "tab:blue"),
             ("dem_ideal_vs_dem_imaged", "tab:gray")]
    x0 = np.arange(len(stages))
    for ax, (col, lab) in zip(axes, [("psd_ks", "PSD (Dmed by mass)"), ("fr_ks", "FR"), ("ar_ks", "AR")]):
        for pi, (p, c) in enumerate(pairs):
            vals = []
            for st in stages:
                v = [fnum(r[col]) for r in dist if r["stage"] == st["name"] and r["pair"] == p]
                vals.append(v[0] if v else np.nan)
            ax.bar(x0 + (pi - 1) * 0.27, vals, 0.27, color=c, label=p.replace("_", " "))
        ax.set_xticks(x0)
        ax.set_xticklabels([f"stage {st['index']}" for st in stages], fontsize=8)
        ax.set_title(f"KS distance, {lab}", fontsize=9)
        ax.set_ylim(0, 1)
    axes[0].legend(fontsize=7)
    return save(fig, out, "distances.png")


def plot_normals(out, stages, nor):
    """One panel per stage: density of the contact normals' polar angle (from z), the series as lines."""
    fig, axes = stage_panels(stages)
    for ax, st in zip(axes.flat, stages):
        for series, style in CONTACT_STYLE.items():
            r = [x for x in nor if x["stage"] == st["name"] and x["series"] == series]
            if r:
                mid = [(fnum(x["theta_from_deg"]) + fnum(x["theta_to_deg"])) / 2 for x in r]
                ax.plot(mid, [fnum(x["density"]) for x in r], ms=3, **style)
        ax.axhline(1.0, color="gray", lw=0.8, alpha=0.6)
        ax.set_title(st["name"], fontsize=9)
        ax.set_xlabel("angle of the contact normal from z (deg)")
        ax.set_ylabel("density (1 = isotropic)")
        ax.set_xlim(0, 90)
        ax.grid(True, alpha=0.3)
    for ax in list(axes.flat)[len(stages):]:
        ax.axis("off")
    axes.flat[0].legend(fontsize=7)
    fig.suptitle("Contact normals: angle from the loading axis (bands of equal solid angle)")
    return save(fig, out, "normals.png")


def overlay(ax, grey, labels, title):
    if grey is not None:
        ax.imshow(grey, cmap="gray", interpolation="nearest")
    else:
        ax.imshow(np.zeros(labels.shape), cmap="gray", vmin=0, vmax=1)
    if labels is not None:
        rng = np.random.default_rng(7)
        lut = rng.uniform(0.2, 1.0, size=(int(labels.max()) + 1, 3))
        rgba = np.zeros(labels.shape + (4,))
        rgba[..., :3] = lut[labels]
        rgba[..., 3] = np.where(labels > 0, 0.45, 0.0)
        ax.imshow(rgba, interpolation="nearest")
    ax.set_title(title, fontsize=8)
    ax.set_xticks([])
    ax.set_yticks([])


def load(out, stem):
    p = os.path.join(out, "slices", stem + ".npy")
    return np.load(p) if os.path.exists(p) else None


def plot_slices(out, st):
    stem = st["slices"]
    cols = [("experiment", "_experiment_grey", "_experiment_labels"),
            ("DEM imaged (segmented)", "_dem_grey", "_dem_imaged_labels"),
            ("DEM ideal (truth labels)", "_dem_grey", "_dem_ideal_labels")]
    cols = [c for c in cols if load(out, stem + c[2] + "_z") is not None]
    fig, axes = plt.subplots(3, len(cols), figsize=(3.2 * len(cols), 9.0), squeeze=False)
    for ci, (title, g, l) in enumerate(cols):
        for ri, ax_name in enumerate(["z", "y", "x"]):
            overlay(axes[ri][ci], load(out, stem + g + "_" + ax_name), load(out, stem + l + "_" + ax_name),
                    f"{title}\nmid-slice normal to {ax_name}")
    fig.suptitle(st["name"], fontsize=10)
    return save(fig, out, f"slices_{stem}.png")


def img_tag(out, name, alt):
    with open(os.path.join(out, name), "rb") as f:
        data = base64.b64encode(f.read()).decode("ascii")
    return f'<figure><img src="data:image/png;base64,{data}" alt="{html.escape(alt)}">' \
           f'<figcaption>{html.escape(alt)} (<a href="{name}">{name}</a>)</figcaption></figure>'


def table(headers, rows):
    h = "".join(f"<th>{html.escape(x)}</th>" for x in headers)
    body = "".join("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in r) + "</tr>" for r in rows)
    return f"<table><tr>{h}</tr>{body}</table>"


def main():
    if len(sys.argv) != 2:
        sys.exit("usage: make_report.py REPORT_DIR")
    out = sys.argv[1]
    meta = json.load(open(os.path.join(out, "report.json")))
    stages = meta["stages"]
    summary = read_csv(os.path.join(out, "summary.csv"))
    psd = read_csv(os.path.join(out, "psd.csv"))
    cls = read_csv(os.path.join(out, "shape_classes.csv"))
    dist = read_csv(os.path.join(out, "distances.csv"))
    ss = read_csv(os.path.join(out, "stress_strain.csv"))
    br = read_csv(os.path.join(out, "broken.csv"))
    fab = read_csv(os.path.join(out, "fabric.csv"))
    nor = read_csv(os.path.join(out, "normals.csv"))
    bysize = read_csv(os.path.join(out, "coordination_by_size.csv"))
    lineage_csv = os.path.join(out, "lineage.csv")
    lin = read_csv(lineage_csv) if os.path.exists(lineage_csv) else []
    yld = meta.get("yield") or {}

    figs = [
        (plot_psd(out, stages, psd), "PSD by mass on Dmed, per stage"),
        (plot_classes(out, stages, cls, "fr", meta["fr_classes"], "Flatness ratio FR = Dmin/Dmed (study's classes)"),
         "FR classes per stage"),
        (plot_classes(out, stages, cls, "ar", meta["ar_classes"], "Aspect ratio AR = Dmax/Dmin (study's classes)"),
         "AR classes per stage"),
        (plot_stress(out, ss, yld), "Axial stress vs axial strain, linear and e–log σ"),
        (plot_broken(out, br), "Fraction of grains broken vs axial strain"),
        (plot_broken_counts(out, br, ss), "Grains and bonds broken vs the stress reached"),
        (plot_height(out, lin), "Grains broken per fifth of the height"),
        (plot_distances(out, stages, dist), "KS distances per stage"),
        (plot_normals(out, stages, nor), "Distribution of the contact normals' angle from the loading axis"),
    ]
    slice_figs = [(plot_slices(out, st), f"Orthogonal slices, {st['name']}: experiment and simulation")
                  for st in stages]

    synthetic = [st for st in stages if st["experiment"].get("synthetic")]
    parts = ["<!DOCTYPE html><html><head><meta charset='utf-8'>",
             f"<title>{html.escape(meta['title'])}</title>",
             "<style>body{font-family:sans-serif;max-width:1250px;margin:auto;padding:1em}"
             "table{border-collapse:collapse;font-size:12px;margin:0.5em 0}td,th{border:1px solid #bbb;padding:2px 6px}"
             "img{max-width:100%}figure{margin:1em 0}.warn{background:#fff3cd;padding:0.6em;border:1px solid #e0c36c}"
             "</style></head><body>",
             f"<h1>{html.escape(meta['title'])}</h1>"]
    if synthetic:
        parts.append("<p class='warn'><b>Synthetic inputs.</b> The experiment series of "
                     + ", ".join(html.escape(st["name"]) for st in synthetic)
                     + " comes from synthetic scans (tomograin synth), not from a scanner.</p>")
    if meta.get("notes"):
        parts.append(f"<p>{html.escape(meta['notes'])}</p>")
    parts.append(f"<p>Sizing: {html.escape(meta['sizing'])}. DEM run: {html.escape(meta['dem_run'])}. "
                 f"Compute time: {meta['compute_seconds']:.1f} s. Two DEM paths: <i>ideal</i> measures the voxelised "
                 "truth labels; <i>imaged</i> segments the voxelised grey scan with the same segment() as the "
                 "experiment. Their distance is the segmentation bias.</p>")
    parts.append("<h2>Stages</h2>")
    parts.append(table(
        ["stage", "experiment input", "synthetic", "XCT strain", "DEM snapshot", "DEM strain",
         "particles exp / ideal / imaged", "DEM coordination from its spheres", "time (s)"],
        [[st["name"], st["experiment"]["source"], "yes" if st["experiment"].get("synthetic") else "no",
          fmt(st["experiment"]["strain"]), os.path.basename(st["dem"]["snapshot"]), fmt(st["dem"]["strain"]),
          f"{st['experiment']['particles']} / {st['dem']['particles_ideal']} / {st['dem']['particles_imaged']}",
          fmt(st["dem"]["ideal"].get("exact_coordination")), f"{st['seconds']:.1f}"] for st in stages]))
    parts.append("<h2>Gradings, breakage</h2>")
    parts.append(table(["stage", "series", "strain", "particles", "D10 (mm)", "D50 (mm)", "Cu", "Hardin Br",
                        "broken", "broken from", "coordination (interior)"],
                       [[r["stage"], r["series"], fmt(r["axial_strain"]), r["particles"], fmt(r["d10_mm"]),
                         fmt(r["d50_mm"]), fmt(r["cu"]), fmt(r["hardin_br"]), fmt(r["broken_fraction"]),
                         r["broken_method"], fmt(r.get("coordination_interior", ""))] for r in summary]))
    parts.append("<h2>Beside the study's published figures</h2>")
    parts.append(study_table(stages, cls, br, ss, yld, meta["fr_classes"], meta["ar_classes"]))
    parts.append("<p>Study: the reference paper's text (its Figs. 9–14); its DEM counts are for its 910-grain "
                 "specimen. DEM (this report): the ideal path's classes (truth labels).</p>")
    if lin:  # lineages (track/): events by type, breakage by height fifth, per series
        parts.append("<h2>Breakage events by type and by height: experiment beside DEM</h2>")
        parts.append(table(["stage", "series", "particles", "intact grains broken (%)", "split", "fragmentation",
                            "chipping", "chips", "lost", "new"] + [f"broken, fifth {b} (%)" for b in range(1, 6)],
                           [[r["stage"], r["series"], r["particles"], fmt(r["pct_intact_broken"]), r["split"],
                             r["fragmentation"], r["chipping"], r["chips"], r["lost"], r["new"]]
                            + [fmt(r[f"pct_broken_band{b}"]) for b in range(1, 6)] for r in lin]))
        parts.append("<p><i>experiment</i>: the XCT stages tracked (<a href='tracking/'>tracking/</a>); "
                     "<i>dem_exact</i>: the DEM's own lineage, mother to fragments, from its snapshots "
                     "(<a href='dem_lineage/'>dem_lineage/</a>); <i>dem_imaged</i>: the same tracker run on the "
                     "segmented DEM scans (<a href='dem_imaged_tracking/'>dem_imaged_tracking/</a>). Same event "
                     "definitions for all three. Fifths of the specimen's height, 1 = bottom platen, 5 = top "
                     "(moving) platen.</p>")
    if isinstance(meta.get("tracking"), str) and meta["tracking"] and not meta["tracking"].startswith("tracking/"):
        parts.append(f"<p>No tracking of the experiment: {html.escape(meta['tracking'])}</p>")
    dl = meta.get("dem_lineage") or {}
    if dl.get("note"):
        parts.append(f"<p>DEM lineage: {html.escape(dl['note'])}</p>")
    bias_csv = os.path.join(out, "tracker_bias.csv")
    if os.path.exists(bias_csv):
        bias = read_csv(bias_csv)
        parts.append("<h3>The tracker's bias on DEM data</h3>")
        parts.append("<p>The tracker on the imaged DEM path scored against the DEM's exact lineage "
                     "(track/evaluate): share of tracked particles given the right parent and the right stage-0 "
                     "grain, recall and precision of each event type (count = exact events for recall, tracked "
                     "events for precision), and % of intact grains broken, tracked minus exact. Read the "
                     "experiment's tracked numbers with this bias in mind.</p>")
        parts.append(table(["stage", "quantity", "value", "count"],
                           [[r["stage"], r["quantity"], fmt(r["value"]), r["count"]] for r in bias]))
    parts.append("<h2>Contact fabric</h2>")
    parts.append("<p>Fabric tensor N = ⟨n⊗n⟩ of the contact normals (z = loading axis), anisotropy a = "
                 "sqrt(3/2 F:F) with F = 15/2 (N − I/3) (0 = isotropic, 7.5 = all along one axis; as "
                 "<code>tomograin contacts</code>), share of normals within 30° of z (isotropic: 0.134), tilt "
                 "of N's major axis from z. Contacts from the labels for the experiment and the two DEM paths; "
                 "<i>DEM exact</i> lists the DEM's own sphere–sphere contacts (normal = centre to centre), "
                 "against which the image method's bias reads: the labels also count surfaces closer than about "
                 "one voxel as touching, so they list more contacts and a flatter fabric than the DEM "
                 "(measured in docs/compare.md); compare the experiment with <i>DEM imaged</i>.</p>")
    parts.append(table(["stage", "series", "contacts", "N_zz", "N_yy", "N_xx", "N_zy", "N_zx", "N_yx",
                        "anisotropy a", "within 30° of z", "major axis tilt (°)"],
                       [[r["stage"], r["series"], r["n_contacts"], fmt(r["N_zz"]), fmt(r["N_yy"]), fmt(r["N_xx"]),
                         fmt(r["N_zy"], 2), fmt(r["N_zx"], 2), fmt(r["N_yx"], 2), fmt(r["anisotropy"]),
                         fmt(r["near_axis_share"]), fmt(r["major_axis_tilt_deg"], 2)] for r in fab]))
    parts.append("<h3>Coordination by size quartile</h3><p>Particles sorted by equal-volume diameter d_eq and "
                 "cut into four classes of equal count (each series its own quartiles); interior particles only "
                 "for the labels, every particle for DEM exact (d_eq from its spheres).</p>")
    parts.append(table(["stage", "series", "quartile", "d_eq from (mm)", "d_eq to (mm)", "particles",
                        "mean coordination"],
                       [[r["stage"], r["series"], r["size_class"], fmt(r["d_eq_from_mm"]), fmt(r["d_eq_to_mm"]),
                         r["particles"], fmt(r["coordination_mean"])] for r in bysize]))
    parts.append("<h2>Distances (Kolmogorov–Smirnov, Wasserstein-1)</h2>")
    parts.append(table(["stage", "pair", "PSD KS", "PSD W1 (mm)", "FR KS", "FR W1", "AR KS", "AR W1"],
                       [[r["stage"], r["pair"], fmt(r["psd_ks"]), fmt(r["psd_w1_mm"]), fmt(r["fr_ks"]),
                         fmt(r["fr_w1"]), fmt(r["ar_ks"]), fmt(r["ar_w1"])] for r in dist]))
    parts.append("<h2>Plots</h2>")
    for name, alt in figs:
        if name:  # a plot without data (no bonds, no lineage) is left out
            parts.append(img_tag(out, name, alt))
    parts.append("<h2>Slices (labels overlaid)</h2>")
    for name, alt in slice_figs:
        parts.append(img_tag(out, name, alt))
    parts.append("<h2>Imaging of the DEM snapshots</h2>")
    parts.append(table(["stage", "voxel (µm)", "grid", "void grey", "solid grey", "noise σ", "PSF σ (vox)", "from"],
                       [[st["name"], fmt(st["dem"]["ideal"]["voxelise"]["voxel_um"], 4),
                         "×".join(str(v) for v in st["dem"]["ideal"]["voxelise"]["shape"]),
                         fmt(st["dem"]["ideal"]["voxelise"]["void_grey"], 5),
                         fmt(st["dem"]["ideal"]["voxelise"]["solid_grey"], 5),
                         fmt(st["dem"]["ideal"]["voxelise"]["noise_sigma"], 4),
                         fmt(st["dem"]["ideal"]["voxelise"]["psf_sigma_vox"]),
                         st["dem"]["ideal"]["voxelise"]["imaging_from"]] for st in stages]))
    parts.append("<h2>Data files</h2><p>Every number behind every plot: "
                 + ", ".join(f"<a href='{f}'>{f}</a>" for f in
                             ["report.json", "summary.csv", "psd.csv", "shape_classes.csv", "distances.csv",
                              "stress_strain.csv", "broken.csv", "fabric.csv", "normals.csv",
                              "coordination_by_size.csv", "contacts/", "particles/", "slices/"])
                 + ".</p></body></html>")
    tmp = os.path.join(out, "index.html.tmp")
    with open(tmp, "w", encoding="utf-8") as f:
        f.write("\n".join(parts))
    os.replace(tmp, os.path.join(out, "index.html"))


if __name__ == "__main__":
    main()
