"""The paper's figures: time against triangle count (Figure 8), time and triangles rendered per
reducePCS call (Figures 9-10) and accumulated % pruned against accumulated % time (Figure 11), from
a study's runs or from `cullide prune --json`."""
import os
import sys
from collections import defaultdict

import matplotlib.ticker

from .encodings import (GENERATORS, MARKERS, METHOD, common_text, config_of, config_text, count_text, family,
                        method_color, ordered, scene_name, varying_axes)
from .load import num
from .output import plt, save


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
