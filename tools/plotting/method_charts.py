"""Every method on one chart: the image-space methods, cullide's exact pipeline and the peers (the
libraries a user would pick instead), each judged by the oracle on the same frames. `methods`:
time to exact pairs against the pairs missed and the pairs reported spuriously; `frame_times`:
the time to pairs of every method along an animated scene. Both need the columns a study writes
since it runs peers (family, time_to_pairs_ms, pairs_missed, pairs_spurious); an older study is
skipped with a note."""
import sys
from collections import defaultdict

import matplotlib.ticker

from .encodings import config_of, grid, log_if_spread, ordered, scene_name
from .load import num
from .output import plt, save

FAMILIES = ["image-space", "exact", "peer"]
# One hue per family; the methods of a family are shades of it, told apart by their markers.
FAMILY_SHADES = {"image-space": ["#1f5fa8", "#4a90d9", "#8cbcea", "#0b3a6e"],
                 "exact": ["#111111", "#555555"],
                 "peer": ["#c62828", "#ef6c00", "#8e1b1b", "#f28b82", "#d84315", "#5d0f0f"]}
METHOD_MARKERS = ["o", "s", "^", "D", "v", "P", "X", "*", "<", ">", "h", "p"]
# The share of the oracle's pairs a method may miss and still give the answer.
QUALIFY_PERCENT = 1.0
# A scene needs this many frames for a line to say more than its points.
MIN_FRAMES = 3


def has_method_columns(rows, chart):
    """Whether the rows carry the columns of every-method studies; says why not on stderr."""
    if any(num(r.get("time_to_pairs_ms")) is not None for r in rows):
        return True
    print(f"{chart}: no time_to_pairs_ms in the study (a study from before peers and the exact method were "
          "measured): not drawn", file=sys.stderr)
    return False


def family_of(r):
    f = r.get("family")
    return f if f in FAMILIES else "image-space"


class Style:
    """Colour (family shade) and marker of each method of the rows, stable across charts."""

    def __init__(self, rows):
        self.families = {}
        for r in rows:
            self.families.setdefault(str(r["method"]), family_of(r))
        self.methods = sorted(self.families, key=lambda m: (FAMILIES.index(self.families[m]),
                                                            list(self.families).index(m)))

    def color(self, m):
        fam = self.families[m]
        same = [x for x in self.methods if self.families[x] == fam]
        shades = FAMILY_SHADES[fam]
        return shades[same.index(m) % len(shades)]

    def marker(self, m):
        return METHOD_MARKERS[self.methods.index(m) % len(METHOD_MARKERS)]

    def legend(self, fig, anchor=(1.0, 0.95)):
        from matplotlib.lines import Line2D
        handles = [Line2D([], [], ls="", marker=self.marker(m), ms=8, color=self.color(m),
                          label=f"{m} ({self.families[m]})") for m in self.methods]
        fig.legend(handles=handles, title="method (family: colour)", loc="upper left", bbox_to_anchor=anchor,
                   frameon=False)


def summaries(rows):
    """{scene: [summary per configuration]}: time to pairs per frame (mean over the frames), and
    the missed and spurious pairs as shares of the oracle's, frames summed."""
    groups = defaultdict(dict)
    for r in rows:
        t = num(r.get("time_to_pairs_ms"))
        if t is None:
            continue
        g = groups[str(r["scene"])].setdefault(config_of(r), {"method": str(r["method"]), "time": 0.0, "frames": 0,
                                                             "missed": 0.0, "spurious": 0.0, "oracle": 0.0})
        g["time"] += t
        g["frames"] += 1
        for key, column in (("missed", "pairs_missed"), ("spurious", "pairs_spurious"), ("oracle", "oracle_pairs")):
            g[key] += num(r.get(column)) or 0.0
    out = {}
    for scene, confs in groups.items():
        out[scene] = []
        for g in confs.values():
            g["time"] /= g["frames"]
            base = max(g["oracle"], 1.0)
            g["missed_pct"], g["spurious_pct"] = 100.0 * g["missed"] / base, 100.0 * g["spurious"] / base
            out[scene].append(g)
    return out


def _readable_log(ax, axis):
    """Ticks at 1, 2, 5 of each decade, written as plain numbers, on a log axis."""
    a = ax.xaxis if axis == "x" else ax.yaxis
    if (ax.get_xscale() if axis == "x" else ax.get_yscale()) == "log":
        a.set_major_locator(matplotlib.ticker.LogLocator(subs=(1, 2, 5)))
        a.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}"))
        a.set_minor_formatter(matplotlib.ticker.NullFormatter())


def _accuracy_axis(ax, values, label):
    top = max(values + [QUALIFY_PERCENT * 2])
    ax.set_yscale("symlog", linthresh=0.1, linscale=0.5)
    ax.set_ylim(0, top * 2)
    ax.yaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}"))
    ax.axhline(QUALIFY_PERCENT, color="0.55", ls="--", lw=0.9, zorder=1)
    ax.set_ylabel(label)
    ax.grid(alpha=0.3, which="both")


def methods_chart(rows, out):
    """Per scene (a column), time to exact pairs per frame (log) against the pairs missed (top) and
    the spurious pairs (bottom), as % of the oracle's pairs, every method of every family."""
    if not has_method_columns(rows, "methods"):
        return None
    rows = [r for r in rows if num(r.get("oracle_pairs")) is not None and num(r.get("time_to_pairs_ms")) is not None]
    if not rows:
        print("methods: no run was judged by the oracle (--no-oracle): not drawn", file=sys.stderr)
        return None
    by_scene = summaries(rows)
    style = Style(rows)
    scenes = [s for s in ordered(str(r["scene"]) for r in rows) if s in by_scene]
    cols, blocks = grid(len(scenes), 4)
    fig, axes = plt.subplots(2 * blocks, cols, figsize=(4.4 * cols, 6.4 * blocks), squeeze=False)
    for i, scene in enumerate(scenes):
        top, bottom = axes[2 * (i // cols)][i % cols], axes[2 * (i // cols) + 1][i % cols]
        confs = by_scene[scene]
        oracle = int(confs[0]["oracle"] / max(1, confs[0]["frames"]))
        for ax, key in ((top, "missed_pct"), (bottom, "spurious_pct")):
            for g in confs:
                # Not clipped: a point at 0 % sits on the axis, whole.
                ax.scatter(g["time"], g[key], s=70, marker=style.marker(g["method"]), color=style.color(g["method"]),
                           edgecolors="white", linewidths=0.6, zorder=3, clip_on=False)
            log_if_spread(ax, "x", [g["time"] for g in confs])
            _readable_log(ax, "x")
            ax.set_xlabel("time to exact pairs per frame (ms)")
        _accuracy_axis(top, [g["missed_pct"] for g in confs], "pairs missed (% of oracle's)")
        _accuracy_axis(bottom, [g["spurious_pct"] for g in confs], "pairs spurious (% of oracle's)")
        frames = confs[0]["frames"]
        top.set_title(f"{scene_name(scene)}: {oracle:,} oracle pairs" + (" per frame" if frames > 1 else ""),
                      fontsize=10)
    for k, ax in enumerate(axes.flat):
        if (k // cols) // 2 * cols + k % cols >= len(scenes):
            ax.set_visible(False)
    style.legend(fig)
    fig.suptitle("Every method: time to exact pairs against pairs missed (top) and spurious (bottom); lower left is "
                 f"better, dashed: {QUALIFY_PERCENT:g} %", fontsize=11)
    fig.tight_layout()
    save(fig, out, "methods")
    return "methods"


def frame_times_chart(rows, out):
    """Per file scene swept over every frame: each method's time to exact pairs per frame (its first
    configuration), every family."""
    if not has_method_columns(rows, "frame_times"):
        return None
    times, firsts = defaultdict(lambda: defaultdict(dict)), {}
    for r in rows:
        scene, frame, t = str(r["scene"]), num(r.get("frame")), num(r.get("time_to_pairs_ms"))
        if "@" in scene or frame is None or t is None:
            continue
        method = str(r["method"])
        if firsts.setdefault((scene, method), config_of(r)) == config_of(r):
            times[scene][method].setdefault(int(frame), t)
    scenes = [s for s in times if len({f for m in times[s].values() for f in m}) >= MIN_FRAMES]
    if not scenes:
        return None
    style = Style([r for r in rows if str(r["scene"]) in scenes])
    cols, nrows = grid(len(scenes))
    fig, axes = plt.subplots(nrows, cols, figsize=(6.4 * cols, 4.2 * nrows), squeeze=False)
    for ax, scene in zip(axes.flat, scenes):
        values = []
        for m in style.methods:
            if m not in times[scene]:
                continue
            frames = sorted(times[scene][m])
            ys = [times[scene][m][f] for f in frames]
            values += ys
            ax.plot(frames, ys, color=style.color(m), marker=style.marker(m), ms=4, lw=1.4, label=m)
        log_if_spread(ax, "y", values)
        _readable_log(ax, "y")
        ax.xaxis.set_major_locator(matplotlib.ticker.MaxNLocator(integer=True))
        ax.set_xlabel("frame")
        ax.set_ylabel("time to exact pairs (ms)")
        ax.set_title(scene_name(scene), fontsize=10)
        ax.grid(alpha=0.3, which="both")
    for ax in list(axes.flat)[len(scenes):]:
        ax.set_visible(False)
    style.legend(fig)
    fig.suptitle("Time to exact pairs per frame, every method (a peer's refit included, its one build not)", fontsize=11)
    fig.tight_layout()
    save(fig, out, "frame_times")
    return "frame_times"
