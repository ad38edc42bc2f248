#!/usr/bin/python3
"""Charts for cullide: `cullide plot INPUT... -o DIR` (PNG and SVG of each chart).

Inputs, recognised by content:
  - study results (`cullide study`, .csv or .jsonl; the .jsonl beside a .csv is read for the
    per-call statistics): speed vs accuracy with the Pareto front, time vs triangle count of the
    paper's two scenes (its Figure 8), per-call time and triangles rendered (Figures 9-10),
    accumulated % pruned vs accumulated % time (Figure 11), false prunes by cause;
  - stability sweeps (`cullide study --stability`, .csv with a `sweep` column);
  - `cullide prune --json` output: Figures 9-11 per frame;
  - Google Benchmark JSON (`cullide_bench --benchmark_format=json`): time per benchmark, and time
    vs `tris` where the names carry it.
Needs matplotlib and numpy (Debian: /usr/bin/python3 with python3-matplotlib).
"""
import argparse
import csv
import json
import math
import os
import re
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

CAUSES = ["depth_rounding", "sampling", "edge_on", "untested", "unexplained"]


def finish(fig, ax, out, name, xlabel, ylabel, title, legend_size=None):
    """Axis labels, title, grid and legend of a chart, then save it."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=legend_size)
    save(fig, out, name)


def save(fig, out, name):
    for ext in ("png", "svg"):
        path = os.path.join(out, f"{name}.{ext}")
        fig.savefig(path, dpi=120, bbox_inches="tight")
        print(path)
    plt.close(fig)


def num(v):
    try:
        return float(v)
    except (TypeError, ValueError):
        return None


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def read_study(path):
    base, ext = os.path.splitext(path)
    jsonl = base + ".jsonl"
    if os.path.exists(jsonl):
        rows = []
        with open(jsonl) as f:
            for line in f:
                try:
                    rows.append(json.loads(line))
                except json.JSONDecodeError:
                    pass
        return rows
    return read_csv(path)


def config_label(r):
    return (f"{r['method']} {r['resolution']} {r['depth']} {r['directions']} "
            f"{r['hierarchy'][:4]}/{r['leaf_size']} {r['backend']}x{r['threads']}")


def speed_vs_accuracy(rows, out):
    groups = defaultdict(lambda: [0.0, 0.0, 0.0])  # time, false prunes, colliding
    for r in rows:
        if num(r.get("colliding")) is None:
            continue
        g = groups[config_label(r)]
        g[0] += num(r["time_ms"])
        g[1] += num(r["false_prunes"])
        g[2] += num(r["colliding"])
    if not groups:
        return
    pts = [(t, 100.0 * fp / c if c else 0.0, k) for k, (t, fp, c) in groups.items()]
    fig, ax = plt.subplots(figsize=(8, 5.5))
    ax.scatter([p[0] for p in pts], [p[1] for p in pts], s=22, color="tab:blue", zorder=3)
    for t, rate, k in pts:
        ax.annotate(k, (t, rate), fontsize=6, alpha=0.7, xytext=(3, 3), textcoords="offset points")
    front, best = [], math.inf
    for t, rate, k in sorted(pts):
        if rate < best:
            front.append((t, rate))
            best = rate
    ax.step([p[0] for p in front], [p[1] for p in front], where="post", color="tab:red", label="Pareto front", zorder=2)
    ax.scatter([p[0] for p in front], [p[1] for p in front], s=40, facecolors="none", edgecolors="tab:red", zorder=4)
    ax.set_xscale("log")
    finish(fig, ax, out, "speed_vs_accuracy", "time per configuration (ms, sum of medians over scenes)",
           "false prunes (% of colliding triangles)", "Speed against accuracy")


def figure8(rows, out, paper=True):
    series = defaultdict(list)
    for r in rows:
        scene = str(r["scene"])
        kind = scene.split(":")[0]
        if kind not in ("bunny", "cows"):
            continue
        series[(kind, r["method"], r["depth"], str(r["resolution"]))].append(
            (num(r["triangles"]), num(r["time_ms"]), num(r.get("time_min_ms")), num(r.get("time_max_ms"))))
    if not series:
        return
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for (kind, method, depth, res), pts in sorted(series.items()):
        pts.sort()
        x = [p[0] / 1000 for p in pts]
        y = [p[1] for p in pts]
        lo = [p[1] - (p[2] if p[2] is not None else p[1]) for p in pts]
        hi = [(p[3] if p[3] is not None else p[1]) - p[1] for p in pts]
        name = "bunny" if kind == "bunny" else "two cows"
        ax.errorbar(x, y, yerr=[lo, hi], marker="o", capsize=3, label=f"{name} ({method}, {res}, {depth}), cullide CPU")
    if paper:
        ax.plot([5, 270], [20, 600], "k--", alpha=0.5, label="paper: bunny 20-600 ms (FX 5900 Ultra)")
        ax.plot([3, 270], [35, 1000], "k:", alpha=0.5, label="paper: cows 35-1000 ms (FX 5900 Ultra)")
    finish(fig, ax, out, "figure8_time_vs_triangles", "triangles (thousands)", "pruning time (ms)",
           "Time vs triangle count (the paper's Figure 8)", legend_size=7)


def pass_charts(passes, total, title, out, name):
    """Figures 9-10 (per-call time and triangles rendered) and 11 (accumulated)."""
    if not passes:
        return None
    ms = [1e3 * p["seconds"] for p in passes]
    rendered = [p["triangles_rendered"] for p in passes]
    fig, ax = plt.subplots(figsize=(7, 4))
    idx = list(range(1, len(passes) + 1))
    ax.bar([i - 0.2 for i in idx], ms, width=0.4, color="tab:blue", label="time (ms)")
    ax.set_xlabel("reducePCS call")
    ax.set_ylabel("time (ms)", color="tab:blue")
    ax2 = ax.twinx()
    ax2.bar([i + 0.2 for i in idx], rendered, width=0.4, color="tab:orange", label="triangles rendered")
    ax2.set_ylabel("triangles rendered", color="tab:orange")
    ax.set_title(f"{title}: time and triangles rendered per call (Figures 9-10)")
    save(fig, out, f"{name}_passes")
    pruned = [p["triangles_in"] - p["triangles_out"] for p in passes]
    tp, tt = sum(pruned), sum(ms)
    if tp <= 0 or tt <= 0:
        return None
    accp, acct, x, y = 0, 0, [], []
    for p, t in zip(pruned, ms):
        accp += p
        acct += t
        x.append(100.0 * accp / tp)
        y.append(100.0 * acct / tt)
    return x, y


def figure11(curves, out):
    if not curves:
        return
    fig, ax = plt.subplots(figsize=(6, 4.5))
    for label, (x, y) in curves:
        ax.plot(x, y, marker=".", label=label)
    finish(fig, ax, out, "figure11_accumulated", "accumulated % of the triangles pruned", "accumulated % of the time",
           "Relative pruning performance (the paper's Figure 11)", legend_size=8)


def causes_chart(rows, out):
    rows = [r for r in rows if num(r.get("false_prunes")) is not None]
    if not rows:
        return
    labels = [f"{r['scene']} {config_label(r)}" for r in rows]
    fig, ax = plt.subplots(figsize=(8, max(2.5, 0.22 * len(rows) + 1)))
    left = [0.0] * len(rows)
    for c in CAUSES:
        v = [num(r[f"fp_{c}"]) or 0 for r in rows]
        ax.barh(range(len(rows)), v, left=left, label=c.replace("_", " "))
        left = [a + b for a, b in zip(left, v)]
    ax.set_yticks(range(len(rows)))
    ax.set_yticklabels(labels, fontsize=6)
    ax.invert_yaxis()
    ax.set_xlabel("false-pruned triangles")
    ax.set_title("False prunes by cause (paper Section 5)")
    ax.legend(fontsize=7)
    save(fig, out, "false_prunes_by_cause")


def plot_study(path, out):
    rows = read_study(path)
    if not rows:
        print(f"{path}: no records", file=sys.stderr)
        return
    speed_vs_accuracy(rows, out)
    figure8(rows, out)
    causes_chart(rows, out)
    curves = []
    if isinstance(rows[0], dict) and "passes" in rows[0]:
        for kind in ("bunny", "cows"):
            runs = [r for r in rows if str(r["scene"]).startswith(kind + ":") and r["passes"]]
            if not runs:
                continue
            small = min(runs, key=lambda r: r["triangles"])
            c = pass_charts(small["passes"], small["triangles"], f"{small['scene']} ({small['method']})", out,
                            f"figure9_10_{kind}")
            if c:
                curves.append((f"{small['scene']} ({small['method']})", c))
    figure11(curves, out)


def rate_chart(rows, xkey, groupkeys, title, xlabel, name, out, logx=False, vlines=()):
    groups = defaultdict(lambda: defaultdict(list))
    for r in rows:
        groups[tuple(r[k] for k in groupkeys)][num(r[xkey])].append(num(r["detected"]))
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for key, pts in sorted(groups.items()):
        xs = sorted(pts)
        ax.plot(xs, [100.0 * sum(pts[x]) / len(pts[x]) for x in xs], marker="o", label=" ".join(key))
    for v, lab in vlines:
        ax.axvline(v, color="k", ls=":", alpha=0.6)
        ax.annotate(lab, (v, 50), rotation=90, fontsize=7, xytext=(3, 0), textcoords="offset points")
    if logx:
        ax.set_xscale("log")
    ax.set_ylim(-3, 103)
    finish(fig, ax, out, name, xlabel, "trials with no false prune (%)", title, legend_size=7)


def plot_stability(rows, out):
    sweep = rows[0]["sweep"]
    if sweep == "penetration":
        rate_chart(rows, "factor", ["method", "depth"], "Penetration depth: detection rate (Section 5, Figure 5(a))",
                   "penetration / ((far-near)/2^n)", "stability_penetration", out, logx=True,
                   vlines=[(1.0, "paper bound (far-near)/2^n")])
    elif sweep == "tilt":
        rate_chart(rows, "angle", ["method", "directions"], "Tilt towards edge-on: detection rate",
                   "angle between the triangle's normal and +z (deg; 90 = edge-on)", "stability_tilt", out)
    elif sweep == "overlap":
        rate_chart(rows, "size", ["method", "depth"], "Overlap size: detection rate (Section 5, Figure 5(b))",
                   "inscribed diameter of the overlap / pixel diagonal", "stability_overlap", out, logx=True,
                   vlines=[(1.0, "one pixel diagonal")])
    elif sweep == "jitter":
        import numpy as np
        fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
        groups = defaultdict(lambda: defaultdict(list))
        base = {}
        for r in rows:
            key = (r["scene"], r["method"])
            if r["kind"] == "none":
                base[key] = (num(r["pcs"]), num(r["false_prunes"]))
            elif r["kind"] == "perturb":
                groups[key][num(r["magnitude"])].append((num(r["pcs"]), num(r["false_prunes"])))
            else:
                groups[key]["rotation"].append((num(r["pcs"]), num(r["false_prunes"])))
        for key, pts in sorted(groups.items()):
            mags = sorted(m for m in pts if m != "rotation")
            for ax, i, what in ((axes[0], 0, "PCS triangles"), (axes[1], 1, "false-pruned triangles")):
                mean = [np.mean([p[i] for p in pts[m]]) for m in mags]
                sd = [np.std([p[i] for p in pts[m]]) for m in mags]
                line = ax.errorbar(mags, mean, yerr=sd, marker="o", capsize=3, label=" ".join(key))
                if key in base:
                    ax.axhline(base[key][i], color=line[0].get_color(), ls=":", alpha=0.6)
                if "rotation" in pts:
                    rot = [p[i] for p in pts["rotation"]]
                    ax.errorbar([mags[-1] * 4 if mags else 1], [np.mean(rot)], yerr=[np.std(rot)], marker="s",
                                color=line[0].get_color(), capsize=3)
                ax.set_xscale("log")
                ax.set_xlabel("perturbation / bounding-box diagonal (square: random rotation)")
                ax.set_ylabel(what + " (mean, sd; dotted: unjittered)")
                ax.grid(alpha=0.3)
        axes[0].legend(fontsize=7)
        fig.suptitle("Jitter of the paper's scenes")
        save(fig, out, "stability_jitter")


def plot_prune_json(j, path, out):
    curves = []
    stem = os.path.splitext(os.path.basename(path))[0]
    for fr in j.get("frames", []):
        c = pass_charts(fr["passes"], fr["triangles"], f"{stem} frame {fr['frame']}", out, f"{stem}_frame{fr['frame']}")
        if c:
            curves.append((f"{stem} frame {fr['frame']}", c))
    figure11(curves, out)


def plot_benchmark(j, path, out):
    benches = [b for b in j.get("benchmarks", []) if b.get("run_type", "iteration") == "iteration"]
    if not benches:
        return
    stem = os.path.splitext(os.path.basename(path))[0]
    unit = benches[0].get("time_unit", "ns")
    fig, ax = plt.subplots(figsize=(8, max(2.5, 0.22 * len(benches) + 1)))
    ax.barh(range(len(benches)), [b["real_time"] for b in benches], color="tab:blue")
    ax.set_yticks(range(len(benches)))
    ax.set_yticklabels([b["name"] for b in benches], fontsize=6)
    ax.invert_yaxis()
    ax.set_xscale("log")
    ax.set_xlabel(f"real time ({unit})")
    ax.set_title("Google Benchmark: " + stem)
    save(fig, out, f"bench_{stem}")
    # Time against the `tris` argument, one line per the other arguments.
    series = defaultdict(list)
    for b in benches:
        m = re.search(r"/tris:(\d+)", b["name"])
        if m:
            series[b["name"].replace(m.group(0), "")].append((int(m.group(1)), b["real_time"]))
    if series:
        fig, ax = plt.subplots(figsize=(7, 4.5))
        for k, pts in sorted(series.items()):
            pts.sort()
            ax.plot([p[0] for p in pts], [p[1] for p in pts], marker="o", label=k)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("triangles")
        ax.set_ylabel(f"real time ({unit})")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=6)
        save(fig, out, f"bench_{stem}_vs_triangles")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("inputs", nargs="+")
    ap.add_argument("-o", "--out", default="figures")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    for path in a.inputs:
        if path.endswith(".json"):
            with open(path) as f:
                j = json.load(f)
            if "benchmarks" in j:
                plot_benchmark(j, path, a.out)
            elif "frames" in j:
                plot_prune_json(j, path, a.out)
            else:
                print(f"{path}: not a prune --json or Google Benchmark file", file=sys.stderr)
                return 2
        elif path.endswith(".csv") or path.endswith(".jsonl"):
            head = read_csv(path)[:1] if path.endswith(".csv") else []
            if head and "sweep" in head[0]:
                plot_stability(read_csv(path), a.out)
            else:
                plot_study(path, a.out)
        else:
            print(f"{path}: expected .csv, .jsonl or .json", file=sys.stderr)
            return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
