"""Charts of Google Benchmark JSON (`cullide_bench --benchmark_format=json`): time per benchmark,
and time against `tris` where the names carry it."""
import os
import re
from collections import defaultdict

from .output import plt, save


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
