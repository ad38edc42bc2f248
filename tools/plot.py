#!/usr/bin/python3
"""Charts for cullide: `cullide plot INPUT... -o DIR` (PNG and SVG of each chart), and
`cullide report STUDY... -o DIR` (--report: DIR/report.html, one self-contained page).

Inputs, recognised by content:
  - study results (`cullide study`, .csv or .jsonl; the .jsonl beside a .csv is read for the
    per-call statistics): speed vs accuracy with the Pareto front (one panel per scene), time vs
    triangle count of generated scenes swept at several sizes (the paper's Figure 8), per-call
    time and triangles rendered (Figures 9-10) and accumulated % pruned vs accumulated % time
    (Figure 11) from the runs of one method (--method, default modified) with several calls,
    false prunes by cause;
  - stability sweeps (`cullide study --stability`, .csv with a `sweep` column);
  - `cullide prune --json` output: Figures 9-11 per frame;
  - Google Benchmark JSON (`cullide_bench --benchmark_format=json`): time per benchmark, and time
    vs `tris` where the names carry it.
Study charts: one colour per method, one marker per combination of the other axes that vary,
scenes by name ("bunny 5k", a file's name), a legend instead of per-point labels, log axes where
values span a decade or more.
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


SAVE = {"formats": ("png", "svg"), "print": True}  # the report wants PNGs only, and no paths printed


def save(fig, out, name):
    for ext in SAVE["formats"]:
        path = os.path.join(out, f"{name}.{ext}")
        fig.savefig(path, dpi=120, bbox_inches="tight")
        if SAVE["print"]:
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


# --- Study charts -------------------------------------------------------------------------------
# Encodings shared by every study chart: one colour per method, one marker per combination of the
# other axes that vary (resolution, depth, ...), scenes by name (scene_name), one panel per scene
# where a study has several. Labels go into legends, never next to points, so none can collide.

METHOD_COLORS = {"original": "tab:blue", "modified": "tab:orange", "reliable": "tab:green"}
OTHER_COLORS = ["tab:purple", "tab:brown", "tab:pink", "tab:olive", "tab:cyan", "tab:red"]
MARKERS = ["o", "s", "^", "D", "v", "P", "X", "*", "<", ">", "h", "p"]
# The axes of a configuration, in the sweep's order (cullide/study/study.h), scene and frame apart.
AXES = ["method", "resolution", "depth", "directions", "views", "hierarchy", "leaf_size", "exact_switch", "backend",
        "threads"]
GENERATORS = {"bunny": "bunny", "cows": "two cows", "twist": "twisted bunny", "cylinders": "cylinders"}
METHOD = {"name": "modified", "chosen": False}  # the per-call charts' method (--method)


def method_color(m, methods):
    if m in METHOD_COLORS:
        return METHOD_COLORS[m]
    others = [x for x in methods if x not in METHOD_COLORS]
    return OTHER_COLORS[others.index(m) % len(OTHER_COLORS)] if m in others else "tab:gray"


def count_text(n):
    """5000 -> 5k, 269824 -> 270k, 600 -> 600."""
    n = int(n)
    return f"{n / 1000:.3g}k" if n >= 1000 else str(n)


def scene_name(scene):
    """A scene as a reader names it: "bunny:5000" -> "bunny 5k", "data/scenes/two_cows.json" ->
    "two cows" (file name without folder and extension), "@K" -> "frame K"."""
    s = str(scene)
    base, _, frame = s.partition("@")
    parts = base.split(":")
    if parts[0] in GENERATORS and len(parts) >= 2 and parts[1].isdigit():
        name = f"{GENERATORS[parts[0]]} {count_text(parts[1])}"
        if len(parts) > 2:
            name += f" x{parts[2]}"
    else:
        name = os.path.splitext(os.path.basename(base))[0].replace("_", " ")
    return name + (f" frame {frame}" if frame and frame != "all" else "")


def family(scene):
    """Generated scenes of one generator form a family (several sizes); a file is its own."""
    s = str(scene).partition("@")[0]
    head = s.split(":")[0]
    return head if head in GENERATORS and ":" in s else s


def axis_text(axis, v):
    v = str(v)
    if axis == "resolution":
        return f"{v} px"
    if axis == "directions":
        return v if v == "axes" else f"{v} dirs"
    if axis == "leaf_size":
        return f"leaf {v}"
    if axis == "views":
        return f"{v} views"
    if axis == "exact_switch":
        return f"exact switch {v}"
    if axis == "threads":
        return "all threads" if v == "0" else f"{v} threads"
    return v


def varying_axes(rows):
    return [a for a in AXES if len({str(r.get(a)) for r in rows}) > 1]


def config_of(r):
    return tuple(str(r.get(a)) for a in AXES)


def config_text(r, axes):
    """The configuration named by the axes that vary in the study only (others are in the title)."""
    return " ".join(axis_text(a, r.get(a)) for a in axes) or "one configuration"


def common_text(rows, skip=()):
    """What every run shares (the axes that do not vary), for titles."""
    fixed = [a for a in AXES if a not in varying_axes(rows) and a not in ("backend", "threads", "hierarchy") + skip
             and rows[0].get(a) not in (None, "")]  # a study from before the axis has no such column
    return ", ".join(axis_text(a, rows[0].get(a)) for a in fixed)


def ordered(values):
    seen = []
    for v in values:
        if v not in seen:
            seen.append(v)
    return seen


def grid(n, max_cols=3):
    cols = min(n, max_cols)
    return cols, math.ceil(n / cols)


def spans_decades(values, ratio=10.0):
    pos = [v for v in values if v is not None and v > 0]
    return len(pos) > 1 and max(pos) / min(pos) >= ratio


def log_if_spread(ax, axis, values):
    """Log scale where the values span a decade or more; symlog when some are zero."""
    if not spans_decades(values):
        return
    pos = [v for v in values if v is not None and v > 0]
    set_scale = ax.set_xscale if axis == "x" else ax.set_yscale
    if any(v == 0 for v in values):
        set_scale("symlog", linthresh=min(pos), linscale=0.5)
        (ax.set_xlim if axis == "x" else ax.set_ylim)(0, max(pos) * 2)
    else:
        set_scale("log")
    fmt = matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}")
    (ax.xaxis if axis == "x" else ax.yaxis).set_major_formatter(fmt)


def scene_configs(rows):
    """{scene: {config: summary}}, frames of a file scene summed (an animation is one scene)."""
    out = defaultdict(dict)
    for r in rows:
        c = config_of(r)
        g = out[str(r["scene"])].get(c)
        if g is None:
            g = out[str(r["scene"])][c] = {"row": r, "time_ms": 0.0, "false_prunes": 0.0, "colliding": 0.0,
                                           "pcs": 0.0, "false_positives": 0.0, "frames": 0, "measured": True,
                                           "causes": {c: 0.0 for c in CAUSES}}
        g["time_ms"] += num(r.get("time_ms")) or 0.0
        for c in CAUSES:
            g["causes"][c] += num(r.get(f"fp_{c}")) or 0.0
        g["frames"] += 1
        for k in ("false_prunes", "colliding", "pcs", "false_positives"):
            v = num(r.get(k))
            if v is None and k != "pcs":
                g["measured"] = False
            g[k] += v or 0.0
    for confs in out.values():
        for g in confs.values():
            g["rate"] = 100.0 * g["false_prunes"] / g["colliding"] if g["colliding"] else 0.0
    return out


def pareto(points):
    """Indices of the points (time, false prunes) no other point beats on both (ties kept)."""
    keep = []
    for i, (t, f) in enumerate(points):
        if not any((t2 <= t and f2 <= f) and (t2 < t or f2 < f) for t2, f2 in points):
            keep.append(i)
    return keep


def legend_handles(methods, combos, combo_axes, ring=True):
    from matplotlib.lines import Line2D
    hm = [Line2D([], [], ls="", marker="o", ms=8, color=method_color(m, methods), label=m) for m in methods]
    hc = [Line2D([], [], ls="", marker=MARKERS[i % len(MARKERS)], ms=7, color="0.35",
                 label=" ".join(axis_text(a, v) for a, v in zip(combo_axes, c))) for i, c in enumerate(combos)]
    if ring:
        hc.append(Line2D([], [], ls="-", marker="o", ms=11, mfc="none", mec="k", color="0.5",
                         label="Pareto-optimal (front)"))
    return hm, hc


def speed_vs_accuracy(rows, out):
    """Time against false-prune rate, one panel per scene, the Pareto front of each marked."""
    rows = [r for r in rows if num(r.get("colliding")) is not None]
    if not rows:
        return None
    by_scene = scene_configs(rows)
    if all(len(c) < 2 for c in by_scene.values()):
        print("speed_vs_accuracy: one configuration per scene, nothing to trade off: not drawn", file=sys.stderr)
        return None
    methods = ordered(str(r["method"]) for r in rows)
    combo_axes = [a for a in varying_axes(rows) if a != "method"]
    combos = ordered(tuple(str(r.get(a)) for a in combo_axes) for r in rows)
    scenes = ordered(str(r["scene"]) for r in rows)
    cols, nrows = grid(len(scenes))
    fig, axes = plt.subplots(nrows, cols, figsize=(4.8 * cols, 3.9 * nrows), squeeze=False)
    for ax, scene in zip(axes.flat, scenes):
        confs = list(by_scene[scene].values())
        pts = [(g["time_ms"], g["false_prunes"]) for g in confs]
        front = pareto(pts)
        for i, g in enumerate(confs):
            r = g["row"]
            marker = MARKERS[combos.index(tuple(str(r.get(a)) for a in combo_axes)) % len(MARKERS)]
            # Not clipped: a point at 0 % sits on the axis, whole.
            ax.scatter(g["time_ms"], g["rate"], s=42, marker=marker, color=method_color(str(r["method"]), methods),
                       edgecolors="white", linewidths=0.5, zorder=3, clip_on=False)
            if i in front:
                ax.scatter(g["time_ms"], g["rate"], s=150, facecolors="none", edgecolors="k", linewidths=1.2,
                           zorder=4, clip_on=False)
        fr = sorted((confs[i]["time_ms"], confs[i]["rate"]) for i in front)
        ax.step([p[0] for p in fr], [p[1] for p in fr], where="post", color="0.5", lw=1, zorder=2)
        log_if_spread(ax, "x", [g["time_ms"] for g in confs])
        log_if_spread(ax, "y", [g["rate"] for g in confs])
        colliding = int(confs[0]["colliding"])
        ax.set_title(f"{scene_name(scene)} ({colliding:,} colliding triangles)", fontsize=10)
        ax.grid(alpha=0.3, which="both")
        ax.set_xlabel("time (ms, median)")
        ax.set_ylabel("false prunes (% of colliding)")
    for ax in list(axes.flat)[len(scenes):]:
        ax.set_visible(False)
    hm, hc = legend_handles(methods, combos, combo_axes)
    leg = fig.legend(handles=hm, title="method (colour)", loc="upper left", bbox_to_anchor=(1.0, 0.95),
                     frameon=False)
    fig.add_artist(leg)
    fig.legend(handles=hc, title=(" / ".join(a.replace("_", " ") for a in combo_axes) + " (marker)")
               if combo_axes else None, loc="upper left", bbox_to_anchor=(1.0, 0.95 - 0.06 * (len(hm) + 2) / nrows),
               frameon=False)
    common = common_text(rows)
    fig.suptitle("Speed against accuracy" + (f" ({common})" if common else "") +
                 ": lower left is better; ringed: no configuration is both faster and more accurate", fontsize=11)
    fig.tight_layout()
    save(fig, out, "speed_vs_accuracy")
    return "speed_vs_accuracy"


def figure8(rows, out, paper=True):
    """Time against triangle count, for generated scenes with several sizes (the paper's Figure 8)."""
    series = defaultdict(list)
    for r in rows:
        fam = family(r["scene"])
        if fam not in GENERATORS:
            continue
        series[(fam,) + config_of(r)].append(r)
    series = {k: v for k, v in series.items() if len({str(r["scene"]) for r in v}) > 1}
    if not series:
        return None
    all_rows = [r for v in series.values() for r in v]
    axes_shown = varying_axes(all_rows)
    fig, ax = plt.subplots(figsize=(7.5, 4.8))
    families = ordered(k[0] for k in series)
    styles = ["-", "--", ":", "-."]
    configs = ordered(k[1:] for k in series)
    methods = ordered(str(r["method"]) for r in all_rows)
    for key, pts in series.items():
        pts.sort(key=lambda r: num(r["triangles"]))
        x = [num(p["triangles"]) for p in pts]
        y = [num(p["time_ms"]) for p in pts]
        lo = [max(0.0, v - (num(p.get("time_min_ms")) or v)) for v, p in zip(y, pts)]
        hi = [max(0.0, (num(p.get("time_max_ms")) or v) - v) for v, p in zip(y, pts)]
        fam_i = families.index(key[0])
        ci = configs.index(key[1:])
        color = method_color(str(pts[0]["method"]), methods) if len(configs) > 1 else f"C{fam_i}"
        label = GENERATORS[key[0]] + (" · " + config_text(pts[0], axes_shown) if axes_shown else "")
        ax.errorbar(x, y, yerr=[lo, hi], marker=MARKERS[(fam_i if len(configs) == 1 else ci) % len(MARKERS)],
                    ls=styles[fam_i % len(styles)], color=color, capsize=3, label=label)
    if paper and {"bunny", "cows"} & set(families):
        ax.plot([5e3, 270e3], [20, 600], color="k", ls=(0, (5, 3)), alpha=0.45, lw=1,
                label="paper, bunny: 20-600 ms (GeForce FX 5900)")
        ax.plot([3e3, 270e3], [35, 1000], color="k", ls=(0, (1, 2)), alpha=0.45, lw=1,
                label="paper, two cows: 35-1000 ms (GeForce FX 5900)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    from matplotlib.ticker import FuncFormatter
    ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: count_text(v)))
    ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    common = common_text(all_rows)
    ax.set_xlabel("triangles (log)")
    ax.set_ylabel("pruning time, ms (log; bars: min-max)")
    ax.set_title("Time against triangle count (the paper's Figure 8)" + (f"\ncullide CPU reference, {common}"
                                                                         if common else ""), fontsize=11)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0) if len(series) > 3 else None, frameon=False)
    fig.tight_layout()
    save(fig, out, "figure8_time_vs_triangles")
    return "figure8_time_vs_triangles"


def draw_passes(ax, passes, title):
    """Figures 9-10 in one panel: time (bars, left axis) and triangles rendered (right axis) per call."""
    ms = [1e3 * p["seconds"] for p in passes]
    rendered = [p["triangles_rendered"] for p in passes]
    idx = list(range(1, len(passes) + 1))
    ax.bar([i - 0.2 for i in idx], ms, width=0.4, color="tab:blue")
    ax.set_ylabel("time (ms)", color="tab:blue")
    ax.tick_params(axis="y", colors="tab:blue")
    ax2 = ax.twinx()
    ax2.bar([i + 0.2 for i in idx], rendered, width=0.4, color="tab:orange")
    ax2.set_ylabel("triangles rendered", color="tab:orange")
    ax2.tick_params(axis="y", colors="tab:orange")
    ax2.yaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _: count_text(v)))
    ax.set_xlim(0.3, len(passes) + 0.7)
    ax.set_xlabel("reducePCS call")
    # Each call's viewport, where they differ (--resolution auto chooses one per call), above its
    # bars; "xN": drawn in N tiles (a backend's viewport limit).
    sizes = [(p.get("width"), p.get("height")) for p in passes]
    pad = 6
    if None not in {s for wh in sizes for s in wh} and len(set(sizes)) > 1:
        import matplotlib.transforms as mtransforms
        at = mtransforms.blended_transform_factory(ax.transData, ax.transAxes)
        for i, (p, (w, h)) in zip(idx, zip(passes, sizes)):
            tiles = p.get("tiles", p.get("views", 1))
            views = p.get("views", 1)
            text = f"{w}x{h}" + (f" x{tiles // max(views, 1)}" if tiles > views else "")
            ax.text(i, 1.02, text, transform=at, rotation=90, fontsize=6, ha="center", va="bottom", color="0.3")
        pad = 6 + 4.2 * max(len(f"{w}x{h}") for w, h in sizes)
    ax.set_title(title + ("\n(each call's viewport above its bars)" if pad > 6 else ""), fontsize=10, pad=pad)


def accumulated(passes):
    """Figure 11's curve: accumulated % pruned (x) against accumulated % time (y)."""
    ms = [1e3 * p["seconds"] for p in passes]
    pruned = [p["triangles_in"] - p["triangles_out"] for p in passes]
    tp, tt = sum(pruned), sum(ms)
    if tp <= 0 or tt <= 0:
        return None
    accp, acct, x, y = 0, 0, [0.0], [0.0]
    for p, t in zip(pruned, ms):
        accp += p
        acct += t
        x.append(100.0 * accp / tp)
        y.append(100.0 * acct / tt)
    return x, y


def passes_figure(items, out, name, suptitle):
    """Small multiples of draw_passes, one row per (title, passes) item."""
    if not items:
        return None
    from matplotlib.patches import Patch
    height = 2.6 * len(items) + 1.0
    fig, axes = plt.subplots(len(items), 1, figsize=(8, height), squeeze=False)
    for ax, (title, passes) in zip(axes[:, 0], items):
        draw_passes(ax, passes, title)
    # Room for the title and the legend in inches, whatever the figure's height (a figure text, not
    # a suptitle, which tight_layout makes room for in some versions and not others).
    fig.text(0.5, 1 - 0.08 / height, suptitle, fontsize=11, ha="center", va="top")
    fig.tight_layout(rect=(0, 0.3 / height, 1, 1 - 0.4 / height))
    fig.legend(handles=[Patch(color="tab:blue", label="time (ms), left axis"),
                        Patch(color="tab:orange", label="triangles rendered, right axis")],
               loc="lower center", bbox_to_anchor=(0.5, 0.0), ncol=2, frameon=False, fontsize=9)
    save(fig, out, name)
    return name


def figure11(curves, out, subtitle=""):
    if not curves:
        return None
    fig, ax = plt.subplots(figsize=(6.5, 4.8))
    ax.plot([0, 100], [0, 100], color="0.6", ls=":", lw=1, label="time in proportion to pruning")
    for i, (label, (x, y)) in enumerate(curves):
        ax.plot(x, y, marker=".", ms=4, color=f"C{i % 10}", label=label)
    ax.set_xlim(0, 100)
    ax.set_ylim(0, 100)
    ax.set_xlabel("accumulated % of the triangles pruned")
    ax.set_ylabel("accumulated % of the time")
    ax.set_title("Relative pruning performance (the paper's Figure 11)" + (f"\n{subtitle}" if subtitle else ""),
                 fontsize=11)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    fig.tight_layout()
    save(fig, out, "figure11_accumulated")
    return "figure11_accumulated"


def pick_run(runs):
    """The run of a scene's per-call chart: the smallest scene of a family (the paper's Figures 9
    and 10: bunny 5k, cows 3k), then the paper's configuration (500 px, D24, axes) if swept, else
    the first in sweep order."""
    def key(r):
        paperish = (str(r["resolution"]), str(r["depth"]), str(r["directions"])) == ("500", "D24", "axes")
        return (num(r["triangles"]), not paperish, num(r.get("index")) or 0)
    return min(runs, key=key)


def per_call_charts(rows, out):
    """Figures 9-11 from the runs of one method with several reducePCS calls, one per scene family."""
    if not rows or "passes" not in rows[0]:
        return []
    multi = [r for r in rows if len(r.get("passes") or []) > 1]
    methods = ordered(str(r["method"]) for r in multi)
    method = METHOD["name"]
    if method not in methods:
        if METHOD["chosen"] or not methods:
            print(f"figures 9-11: no run of method '{method}' has several reducePCS calls"
                  + (f" (methods with several: {', '.join(methods)})" if methods else "") + ": not drawn",
                  file=sys.stderr)
            return []
        print(f"figures 9-11: no run of method '{method}' has several calls; drawing '{methods[0]}'",
              file=sys.stderr)
        method = methods[0]
    runs = [r for r in multi if str(r["method"]) == method]
    axes_shown = [a for a in varying_axes(rows) if a != "method"]
    items, curves = [], []
    for fam in ordered(family(r["scene"]) for r in runs):
        r = pick_run([x for x in runs if family(x["scene"]) == fam])
        frame = f" frame {r['frame']}" if len({str(x.get('frame')) for x in runs if x['scene'] == r['scene']}) > 1 \
            else ""
        conf = config_text(r, axes_shown) if axes_shown else ""
        label = f"{scene_name(r['scene'])}{frame}" + (f" · {conf}" if conf else "")
        items.append((f"{label} ({len(r['passes'])} calls, {int(num(r['triangles'])):,} triangles)", r["passes"]))
        c = accumulated(r["passes"])
        if c:
            curves.append((label, c))
    common = common_text(runs, skip=("method",))
    sub = f"method {method}" + (f", {common}" if common else "")
    made = [passes_figure(items, out, "figure9_10_passes",
                          f"Time and triangles rendered per call (the paper's Figures 9-10), {sub}"),
            figure11(curves, out, sub)]
    return [m for m in made if m]


def causes_chart(rows, out):
    """False prunes by cause: one panel per scene (rows: configurations), or, when each scene has
    one configuration, one panel whose rows are the scenes."""
    rows = [r for r in rows if num(r.get("false_prunes")) is not None]
    if not rows:
        return None
    by_scene = scene_configs(rows)
    scenes = ordered(str(r["scene"]) for r in rows)
    methods = ordered(str(r["method"]) for r in rows)
    axes_shown = varying_axes(rows)
    causes = [c for c in CAUSES if any(num(r.get(f"fp_{c}")) for r in rows)] or CAUSES[:1]
    colors = {"depth_rounding": "tab:purple", "sampling": "tab:blue", "edge_on": "tab:orange",
              "untested": "0.6", "unexplained": "tab:red"}

    def sums(confs):
        return [(g["row"], g["causes"], g) for g in confs]

    if all(len(by_scene[s]) == 1 for s in scenes):
        panels = [("", [(scene_name(s), *sums(by_scene[s].values())[0]) for s in scenes])]
        ylabel_color = False
    else:
        panels = [(scene_name(s), [(config_text(r, [a for a in axes_shown]), r, v, g)
                                   for r, v, g in sums(by_scene[s].values())]) for s in scenes]
        ylabel_color = "method" in axes_shown
    n = len(panels)
    cols, nrows = grid(n, 2)
    longest = max(len(p[1]) for p in panels)
    fig, axs = plt.subplots(nrows, cols, figsize=(5.6 * cols, (0.24 * longest + 1.3) * nrows), squeeze=False)
    for ax, (title, items) in zip(axs.flat, panels):
        left = [0.0] * len(items)
        for c in causes:
            v = [it[2][c] for it in items]
            ax.barh(range(len(items)), v, left=left, color=colors[c], label=c.replace("_", " "))
            left = [a + b for a, b in zip(left, v)]
        top = max(left) if left and max(left) > 0 else 1.0
        for i, (total, it) in enumerate(zip(left, items)):
            col = int(it[3]["colliding"])
            ax.annotate(f"{int(total):,} / {col:,}", (total, i), xytext=(3, 0), textcoords="offset points",
                        va="center", fontsize=7, color="0.25")
        ax.set_xlim(0, top * 1.3)
        ax.set_yticks(range(len(items)))
        ax.set_yticklabels([it[0] for it in items], fontsize=8)
        if ylabel_color:
            for lab, it in zip(ax.get_yticklabels(), items):
                lab.set_color(method_color(str(it[1]["method"]), methods))
        ax.invert_yaxis()
        ax.set_xlabel("false-pruned triangles (label: false prunes / colliding)")
        ax.grid(alpha=0.3, axis="x")
        if title:
            ax.set_title(title, fontsize=10)
    for ax in list(axs.flat)[n:]:
        ax.set_visible(False)
    handles, labels = axs.flat[0].get_legend_handles_labels()
    fig.legend(handles, labels, title="cause", loc="upper left", bbox_to_anchor=(1.0, 0.95), frameon=False,
               fontsize=9)
    common = common_text(rows)
    fig.suptitle("False prunes by cause (the paper's Section 5)" + (f", {common}" if common else ""), fontsize=11)
    fig.tight_layout()
    save(fig, out, "false_prunes_by_cause")
    return "false_prunes_by_cause"


def plot_study_rows(rows, out):
    made = [speed_vs_accuracy(rows, out), figure8(rows, out), causes_chart(rows, out)]
    made += per_call_charts(rows, out)
    return [m for m in made if m]


def plot_study(path, out):
    rows = read_study(path)
    if not rows:
        print(f"{path}: no records", file=sys.stderr)
        return []
    return plot_study_rows(rows, out)


# --- Report -------------------------------------------------------------------------------------
# `cullide report`: one HTML page with nothing outside it (charts as data: URIs, styles inline, no
# scripts), well-formed (every element closed, text escaped), so that it can be mailed, archived
# and parsed by a test.

REPORT_CSS = """
body { font-family: sans-serif; max-width: 72em; margin: 1.5em auto; padding: 0 1em; color: #222; }
h1 { font-size: 1.5em; } h2 { font-size: 1.2em; border-bottom: 1px solid #ccc; margin-top: 1.6em; }
h3 { font-size: 1.05em; margin-bottom: 0.3em; }
table { border-collapse: collapse; margin: 0.5em 0 1em; font-size: 0.9em; }
th, td { border: 1px solid #ccc; padding: 0.2em 0.6em; text-align: left; }
td.n { text-align: right; font-variant-numeric: tabular-nums; }
th { background: #f2f2f2; }
pre { background: #f6f6f6; padding: 0.6em; white-space: pre-wrap; word-break: break-all; }
figure { margin: 1em 0 2em; } figure img { max-width: 100%; height: auto; border: 1px solid #eee; }
figcaption { font-size: 0.9em; color: #444; max-width: 60em; }
.note { color: #555; font-size: 0.9em; }
"""

CAPTIONS = {
    "speed_vs_accuracy": "Time (median of the timed runs) against false prunes (% of the triangles the oracle finds "
                         "colliding), one panel per scene. Colour: method; marker: the other axes that vary. Ringed "
                         "points are Pareto-optimal: no other configuration is both faster and prunes fewer.",
    "figure8_time_vs_triangles": "Pruning time against triangle count for the generated scenes swept at several "
                                 "sizes (bars: min-max of the timed runs), with the paper's measured ranges.",
    "false_prunes_by_cause": "False-pruned triangles by cause (Section 5 of the paper): depth rounding, sampling, "
                             "edge-on; 'untested' are pairs the method never tests (the original method's self "
                             "pairs). Labels: false prunes / colliding triangles.",
    "figure9_10_passes": "Per reducePCS call: time (blue, left axis) and triangles rendered (orange, right axis), "
                         "for one run per scene of the chosen method (the paper's Figures 9 and 10).",
    "figure11_accumulated": "Accumulated share of the triangles pruned against the accumulated share of the time, "
                            "per call (the paper's Figure 11): a curve above the diagonal spends its time before "
                            "it prunes.",
}


def esc(v):
    import html
    return html.escape(str(v), quote=True)


def cell(v, numeric=False):
    return f'<td class="n">{esc(v)}</td>' if numeric else f"<td>{esc(v)}</td>"


def fmt(v, digits=1):
    return "" if v is None else (f"{v:,.{digits}f}" if digits else f"{int(round(v)):,}")


def html_table(headers, rows, cls=None, attrs=""):
    head = "".join(f"<th>{esc(h)}</th>" for h in headers)
    body = "".join("<tr>" + "".join(r) + "</tr>\n" for r in rows)
    c = f' class="{cls}"' if cls else ""
    return f"<table{c}{attrs}>\n<thead><tr>{head}</tr></thead>\n<tbody>\n{body}</tbody>\n</table>\n"


def config_cells(r):
    return [cell(r.get("method")), cell(r.get("resolution")), cell(r.get("depth")), cell(r.get("directions")),
            cell(f"{r.get('hierarchy')}/{r.get('leaf_size')}"), cell(f"{r.get('backend')} x{r.get('threads')}")]


CONFIG_HEADERS = ["method", "resolution", "depth", "directions", "hierarchy/leaf", "backend x threads"]


def pareto_section(rows):
    parts = []
    by_scene = scene_configs(rows)
    for scene in ordered(str(r["scene"]) for r in rows):
        confs = list(by_scene[scene].values())
        measured = all(g["measured"] for g in confs)
        if measured:
            front = pareto([(g["time_ms"], g["false_prunes"]) for g in confs])
        else:  # no oracle: the fastest only
            best = min(g["time_ms"] for g in confs)
            front = [i for i, g in enumerate(confs) if g["time_ms"] == best]
        chosen = sorted((confs[i] for i in front), key=lambda g: g["time_ms"])
        frames = confs[0]["frames"]
        table_rows = []
        for g in chosen:
            r = g["row"]
            table_rows.append(config_cells(r) + [
                cell(fmt(g["time_ms"]), True), cell(fmt(g["false_prunes"], 0) if measured else "n/a", True),
                cell(f"{g['rate']:.2f}" if measured else "n/a", True), cell(fmt(g["pcs"], 0), True),
                cell(fmt(g["false_positives"], 0) if measured else "n/a", True)])
        colliding = int(confs[0]["colliding"])
        parts.append(f'<h3>{esc(scene_name(scene))} <span class="note">({esc(scene)}'
                     + (f", {frames} frames summed" if frames > 1 else "")
                     + (f", {colliding:,} colliding triangles" if measured else ", no oracle")
                     + f"; {len(chosen)} of {len(confs)} configurations)</span></h3>\n")
        parts.append(html_table(CONFIG_HEADERS + ["time ms", "false prunes", "% of colliding", "PCS",
                                                  "false positives"], table_rows, "pareto",
                                f' data-scene="{esc(scene)}"'))
    return "".join(parts)


def provenance_section(rows, inputs):
    keys = ["cullide_version", "git_commit", "compiler", "cpu_model", "threads", "drivers"]
    values = defaultdict(list)
    dates = []
    for r in rows:
        p = r.get("provenance") if isinstance(r, dict) else None
        if not isinstance(p, dict):
            continue
        for k in keys:
            if k in p:
                v = ", ".join(p[k]) if isinstance(p[k], list) else str(p[k])
                if v not in values[k]:
                    values[k].append(v)
        if "date" in p:
            dates.append(p["date"])
    table_rows = [[cell(k.replace("_", " ")), cell("; ".join(values[k]))] for k in keys if values[k]]
    if dates:
        table_rows.append([cell("dates (UTC)"), cell(f"{min(dates)} to {max(dates)}")])
    table_rows.append([cell("input files"), cell("; ".join(inputs))])
    table_rows.append([cell("runs"), cell(str(len(rows)))])
    if not any(values.values()):
        return ('<p class="note">No provenance: the input has no JSON lines (the .jsonl beside the .csv); '
                "only its CSV columns were read.</p>\n" + html_table(["", ""], table_rows, "provenance"))
    return html_table(["what", "value"], table_rows, "provenance")


def command_section(rows):
    commands = defaultdict(int)
    for r in rows:
        c = r.get("command") if isinstance(r, dict) else None
        if c:
            commands[c] += 1
    if not commands:
        return ('<p class="note" id="no-command">The command is not recorded in these results (a study output '
                "from before cullide recorded it, or a CSV without its .jsonl).</p>\n")
    text = "".join(f"<pre class=\"command\">{esc(c)}</pre>\n" + (f'<p class="note">{n} run(s)</p>\n'
                                                               if len(commands) > 1 else "")
                   for c, n in commands.items())
    return text + '<p class="note">Run from the folder the study ran in; runs already in the output are skipped.</p>\n'


def axes_section(rows):
    table_rows = []
    scenes = ordered(str(r["scene"]) for r in rows)
    table_rows.append([cell("scenes"), cell("; ".join(f"{scene_name(s)} ({s})" for s in scenes))])
    for a in AXES:
        table_rows.append([cell(a.replace("_", " ")), cell(", ".join(ordered(str(r.get(a)) for r in rows)))])
    return html_table(["axis", "values"], table_rows, "axes")


def runs_section(rows):
    table_rows = []
    for r in rows:
        table_rows.append([cell(scene_name(r["scene"])), cell(r.get("frame"))] + config_cells(r) + [
            cell(fmt(num(r.get("time_ms"))), True), cell(r.get("calls"), True), cell(r.get("pcs"), True),
            cell("" if num(r.get("colliding")) is None else r.get("colliding"), True),
            cell("" if num(r.get("false_prunes")) is None else r.get("false_prunes"), True)])
    return html_table(["scene", "frame"] + CONFIG_HEADERS + ["time ms", "calls", "PCS", "colliding",
                                                             "false prunes"], table_rows, "runs")


def write_report(inputs, out):
    import base64
    import datetime
    import tempfile
    rows = []
    for path in inputs:
        if not (path.endswith(".csv") or path.endswith(".jsonl")):
            print(f"cullide: error: {path}: a report is made of study outputs (.csv or .jsonl)", file=sys.stderr)
            return 2
        head = read_csv(path)[:1] if path.endswith(".csv") else []
        if head and "sweep" in head[0]:
            print(f"cullide: error: {path}: a stability sweep, not a study output", file=sys.stderr)
            return 2
        got = read_study(path)
        if not got or "scene" not in got[0] or "method" not in got[0]:
            print(f"cullide: error: {path}: no study records", file=sys.stderr)
            return 2
        rows += got
    SAVE.update(formats=("png",), print=False)
    with tempfile.TemporaryDirectory() as tmp:
        made = plot_study_rows(rows, tmp)
        figures = []
        for name in made:
            with open(os.path.join(tmp, name + ".png"), "rb") as f:
                data = base64.b64encode(f.read()).decode("ascii")
            figures.append(f'<figure id="{esc(name)}"><img src="data:image/png;base64,{data}" '
                           f'alt="{esc(name.replace("_", " "))}" />\n<figcaption>{esc(CAPTIONS.get(name, ""))}'
                           "</figcaption></figure>\n")
    scenes = ordered(str(r["scene"]) for r in rows)
    now = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    page = (
        '<!DOCTYPE html>\n<html lang="en">\n<head>\n<meta charset="utf-8" />\n'
        f"<title>cullide study report: {len(rows)} runs, {len(scenes)} scene(s)</title>\n"
        f"<style>{REPORT_CSS}</style>\n</head>\n<body>\n"
        f"<h1>cullide study: {len(rows)} runs over {len(scenes)} scene(s)</h1>\n"
        '<p class="note">Made by <code>cullide report</code> at ' + esc(now) + ". Contents: "
        '<a href="#command">command</a>, <a href="#provenance">provenance</a>, <a href="#pareto">Pareto-optimal '
        'configurations</a>, <a href="#charts">charts</a>, <a href="#runs">all runs</a>.</p>\n'
        '<h2 id="command">The command that produced the data</h2>\n' + command_section(rows) +
        '<h2 id="provenance">Provenance</h2>\n' + provenance_section(rows, inputs) +
        '<h2 id="axes">The sweep</h2>\n' + axes_section(rows) +
        '<h2 id="pareto">Pareto-optimal configurations, per scene</h2>\n'
        '<p class="note">Configurations that no other of the same scene beats on both time and false prunes '
        "(frames of an animation summed), fastest first.</p>\n" + pareto_section(rows) +
        '<h2 id="charts">Charts</h2>\n' + ("".join(figures) or '<p class="note">No charts.</p>\n') +
        '<h2 id="runs">All runs</h2>\n<details><summary>' + f"{len(rows)} runs" + "</summary>\n" +
        runs_section(rows) + "</details>\n</body>\n</html>\n")
    os.makedirs(out, exist_ok=True)
    path = os.path.join(out, "report.html")
    with open(path + ".tmp", "w", encoding="utf-8") as f:
        f.write(page)
    os.replace(path + ".tmp", path)
    print(path)
    return 0


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
    stem = os.path.splitext(os.path.basename(path))[0]
    items, curves = [], []
    for fr in j.get("frames", []):
        if not fr.get("passes"):
            continue
        items.append((f"frame {fr['frame']} ({len(fr['passes'])} calls, {fr['triangles']:,} triangles)",
                      fr["passes"]))
        c = accumulated(fr["passes"])
        if c:
            curves.append((f"frame {fr['frame']}", c))
    passes_figure(items, out, f"{stem}_passes", f"{stem}: time and triangles rendered per call (Figures 9-10)")
    figure11(curves, out, stem)


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
    ap.add_argument("--method", help="method of the per-call charts (Figures 9-11; default: modified)")
    ap.add_argument("--report", action="store_true", help="write OUT/report.html instead of the charts")
    a = ap.parse_args()
    if a.method:
        METHOD.update(name=a.method, chosen=True)
    if a.report:
        return write_report(a.inputs, a.out)
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
