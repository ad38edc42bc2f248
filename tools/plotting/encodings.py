"""Encodings shared by every study chart: one colour per method, one marker per combination of the
other axes that vary (resolution, depth, ...), scenes by name (scene_name), one panel per scene
where a study has several. Labels go into legends, never next to points, so none can collide.
Also the per-scene summaries (scene_configs) and Pareto fronts the charts and the report share."""
import math
import os
from collections import defaultdict

import matplotlib.ticker

from .inputs import CAUSES
from .load import num

METHOD_COLORS = {"original": "tab:blue", "modified": "tab:orange", "reliable": "tab:green"}
OTHER_COLORS = ["tab:purple", "tab:brown", "tab:pink", "tab:olive", "tab:cyan", "tab:red"]
MARKERS = ["o", "s", "^", "D", "v", "P", "X", "*", "<", ">", "h", "p"]
# The axes of a configuration, in the sweep's order (cullide/study/study.h), scene and frame apart.
AXES = ["method", "resolution", "depth", "directions", "views", "hierarchy", "leaf_size", "exact_switch", "backend",
        "threads"]
GENERATORS = {"bunny": "bunny", "cows": "two cows", "twist": "twisted bunny", "cylinders": "cylinders",
              "cloth": "cloth", "nbody": "N-body"}
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
