"""The study charts: speed against accuracy with the Pareto fronts, false prunes by cause, and
all of a study's charts (with the paper's figures, paper_figures, and every method's,
method_charts)."""
import sys

from .encodings import (CAUSES, MARKERS, common_text, config_text, grid, legend_handles, log_if_spread,
                        method_color, ordered, pareto, scene_configs, scene_name, varying_axes)
from .load import num
from .output import plt, save
from .method_charts import family_of, frame_times_chart, methods_chart
from .paper_figures import figure8, per_call_charts
from .sequence_charts import frames_chart


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


def image_space_rows(rows):
    """The runs of the image-space methods: the charts of PCS, false prunes and reducePCS calls
    are theirs (the exact method and the peers have none)."""
    return [r for r in rows if family_of(r) == "image-space"]


def plot_study_rows(rows, out):
    image = image_space_rows(rows)
    made = [speed_vs_accuracy(image, out), figure8(image, out), causes_chart(image, out), frames_chart(rows, out)]
    made += per_call_charts(image, out)
    made += [methods_chart(rows, out), frame_times_chart(rows, out)]
    return [m for m in made if m]
