"""Plots of a shadowbench results folder (see scripts/plot).

Per scene: frame time against path progress, stage-stacked, one panel per
run; shadow draw calls against progress (layered against per-cascade); the
median stage breakdown per run as stacked bars. Over all scenes: median frame
time against err_rate with each scene's Pareto front.
"""
import csv
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

COLORS = {"zpass": "#8da0cb", "minmax": "#e78ac3", "cascade": "#fc8d62", "volumes": "#a6d854",
          "rays": "#ffd92f", "final": "#66c2a5"}


def stage_names(root):
    """The stages, from the results set's own column table (columns.csv: the
    per-frame columns flagged stage_time), in table order."""
    path = os.path.join(root, "columns.csv")
    if os.path.exists(path):
        names = [r["name"][:-3] for r in csv.DictReader(open(path))
                 if r["scope"] == "frame" and r["flags"] == "stage_time"]
        if names:
            return names
    return list(COLORS)  # results written before columns.csv existed


def num(s):
    try:
        v = float(s)
        return v if math.isfinite(v) else None
    except (TypeError, ValueError):
        return None


def label(r):
    p = dict(kv.split("=", 1) for kv in r["params"].split(":") if "=" in kv)
    keys = [k for k in ("res", "cascades", "layered", "filter", "splits", "partition") if k in p]
    return r["technique"] + ("" if not keys else " " + " ".join(f"{k}={p[k]}" for k in keys))


def main(root):
    STAGES = stage_names(root)
    for i, st in enumerate(STAGES):
        COLORS.setdefault(st, plt.cm.tab10(i % 10))
    runs = [r for r in csv.DictReader(open(os.path.join(root, "summary.csv"))) if r["status"] == "ok"]
    out = os.path.join(root, "plots")
    os.makedirs(out, exist_ok=True)
    written = []
    frames = {}
    for r in runs:
        path = os.path.join(root, r["run_id"] + ".csv")
        if os.path.exists(path):
            frames[r["run_id"]] = [f for f in csv.DictReader(open(path)) if f.get("repeat", "0") in ("0", "")]
    scenes = sorted({r["scene"] for r in runs})
    for scene in scenes:
        rs = [r for r in runs if r["scene"] == scene and r["run_id"] in frames]
        if not rs:
            continue
        # frame time against progress, stage-stacked
        cols = 4
        rows = math.ceil(len(rs) / cols)
        fig, axes = plt.subplots(rows, cols, figsize=(4 * cols, 2.6 * rows), squeeze=False, sharex=True)
        for ax, r in zip(axes.flat, rs):
            fr = frames[r["run_id"]]
            x = [num(f["progress"]) for f in fr]
            ys, names = [], []
            for st in STAGES:
                v = [num(f.get(st + "_ms")) for f in fr]
                if any(a is not None for a in v):
                    ys.append([a or 0 for a in v])
                    names.append(st)
            if ys:
                ax.stackplot(x, ys, labels=names, colors=[COLORS[n] for n in names])
            ax.set_title(label(r), fontsize=8)
            ax.set_ylabel("ms", fontsize=7)
            ax.tick_params(labelsize=7)
        for ax in list(axes.flat)[len(rs):]:
            ax.axis("off")
        handles = [plt.Rectangle((0, 0), 1, 1, color=COLORS[s]) for s in STAGES]
        fig.legend(handles, STAGES, loc="upper right", fontsize=7)
        fig.suptitle(f"{scene}: frame time along the path (stages stacked)")
        fig.tight_layout()
        p = os.path.join(out, f"{scene}-frame-time.png")
        fig.savefig(p, dpi=90)
        plt.close(fig)
        written.append(p)

        # draw calls against progress: layered against per-cascade
        cascaded = [r for r in rs if "layered=" in r["params"]]
        if cascaded:
            fig, ax = plt.subplots(figsize=(9, 4.5))
            for r in cascaded:
                fr = frames[r["run_id"]]
                style = "-" if "layered=off" in r["params"] else "--"
                ax.plot([num(f["progress"]) for f in fr], [num(f["shadow_draw_calls"]) for f in fr], style,
                        label=label(r), linewidth=1.2)
            ax.set_xlabel("progress along the path")
            ax.set_ylabel("shadow draw calls")
            ax.set_title(f"{scene}: shadow draw calls, per-cascade (solid) against layered (dashed)")
            ax.legend(fontsize=7)
            fig.tight_layout()
            p = os.path.join(out, f"{scene}-draw-calls.png")
            fig.savefig(p, dpi=90)
            plt.close(fig)
            written.append(p)

        # stage breakdown bars (medians)
        fig, ax = plt.subplots(figsize=(max(6, 0.7 * len(rs) + 2), 4.5))
        bottom = [0.0] * len(rs)
        for st in STAGES:
            v = [num(r.get(st + "_ms_median")) or 0 for r in rs]
            if any(v):
                ax.bar(range(len(rs)), v, bottom=bottom, color=COLORS[st], label=st)
                bottom = [a + b for a, b in zip(bottom, v)]
        ax.set_xticks(range(len(rs)))
        ax.set_xticklabels([label(r) for r in rs], rotation=60, ha="right", fontsize=7)
        ax.set_ylabel("median ms per frame")
        ax.set_title(f"{scene}: stage breakdown")
        ax.legend(fontsize=7)
        fig.tight_layout()
        p = os.path.join(out, f"{scene}-stages.png")
        fig.savefig(p, dpi=90)
        plt.close(fig)
        written.append(p)

    # time against error, with each scene's Pareto front
    pts = [(r["scene"], num(r.get("gpu_ms_median")), num(r.get("err_rate_mean")), label(r)) for r in runs]
    pts = [p for p in pts if p[1] is not None and p[2] is not None]
    if pts:
        fig, ax = plt.subplots(figsize=(9, 6))
        for i, scene in enumerate(scenes):
            sp = sorted([p for p in pts if p[0] == scene], key=lambda p: (p[1], p[2]))
            if not sp:
                continue
            c = plt.cm.tab10(i % 10)
            ax.scatter([p[1] for p in sp], [p[2] for p in sp], color=c, label=scene, s=18)
            front, best = [], float("inf")
            for p in sp:
                if p[2] < best:
                    front.append(p)
                    best = p[2]
            ax.step([p[1] for p in front], [p[2] for p in front], where="post", color=c, linewidth=1)
            for p in front:
                ax.annotate(p[3], (p[1], p[2]), fontsize=6, color=c)
        ax.set_xscale("log")
        ax.set_yscale("symlog", linthresh=1e-4)
        ax.set_ylim(bottom=0)
        ax.set_xlabel("median frame time, ms (gpu_ms)")
        ax.set_ylabel("err_rate (mean over evaluated frames)")
        ax.set_title("time against error: Pareto front per scene")
        ax.legend(fontsize=8)
        fig.tight_layout()
        p = os.path.join(out, "pareto.png")
        fig.savefig(p, dpi=90)
        plt.close(fig)
        written.append(p)
    for p in written:
        print(p)


if __name__ == "__main__":
    main(sys.argv[1])
