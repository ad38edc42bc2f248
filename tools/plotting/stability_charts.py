"""Charts of stability sweeps (`cullide study --stability`): detection rate against penetration,
tilt and overlap size, and PCS and false prunes under jitter."""
from collections import defaultdict

from .load import num
from .output import finish, plt, save


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
