#!/usr/bin/env python3
"""The performance table of docs/performance.md, from cullide_bench's JSON output.

    build/bench/cullide_bench --benchmark_filter="$(python3 tools/bench_table.py --filter)" \\
        --benchmark_repetitions=3 --benchmark_format=json > bench.json
    python3 tools/bench_table.py bench.json                            # the table on stdout
    python3 tools/bench_table.py bench.json --write docs/performance.md  # between its markers

Each row shows our figure, the peer's figure measured in the same run (CGAL, llvmpipe, the
tiled path, or the 0.1.0 reference build's hierarchy build) and their ratio, so that a noisy
machine moves both sides alike. Where the peer cannot run in the same process, the ratio is
against a recorded figure of bench/baseline.json and is marked "recorded". With repetitions,
the medians are used. Above the table: the run's provenance (date, host, CPU model, CPU count
and MHz from Google Benchmark's context; the cullide version, git commit and compiler that
bench/bench_main.cpp adds). Standard library only.
"""

import argparse
import json
import os
import re
import sys

BEGIN = "<!-- bench_table.py: begin (generated; do not edit by hand) -->"
END = "<!-- bench_table.py: end -->"
HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT_BASELINE = os.path.join(HERE, "..", "bench", "baseline.json")

# (what, benchmark name without "/iterations:N" and "/real_time", kind). Kinds say where our figure, the peer's and
# the ratio come from (see row()).
ROWS = [
    ("`prune` bunny_through_cow (middle frame), CPU reference vs llvmpipe",
     "BM_CpuVsGl_Prune/scene:0", "gl"),
    ("`oracle` vs CGAL `self_intersections`, the cow (5,804 triangles), one thread",
     "BM_OracleInterleaved/mesh:3/workspace:0/threads:1", "cgal"),
    ("`oracle` vs CGAL `self_intersections`, two subdivided cows (46,432 triangles), one thread",
     "BM_OracleInterleaved/mesh:7/workspace:0/threads:1", "cgal"),
    ("connectivity hierarchy, bunny 270k, vs the 0.1.0 build's (same process, same hierarchy)",
     "BM_Hierarchy/kind:0/tris:270000", "hierarchy"),
    ("~1 px triangles, 500 px, one thread: the direct path vs the tiles",
     "BM_Triangles/leg:1/W:500/threads:1/direct:1", "tiles"),
    ("`prune` bunny 270k, modified, one thread (CPU time)",
     "BM_Prune/scene:0/tris:270000/method:1/threads:1", "recorded"),
]


def filter_regex():
    """The --benchmark_filter that runs the table's rows (and the rows their ratios need)."""
    names = [name for _, name, _ in ROWS]
    names.append("BM_Triangles/leg:1/W:500/threads:1/direct:0")  # x_tiles reads its rate
    return "^(" + "|".join(re.escape(n) for n in names) + ")(/iterations:[0-9]+)?(/real_time)?$"


def runs_by_name(report):
    """name (without /iterations:N and /real_time) -> the run to report: the median aggregate if any, else the last."""
    chosen = {}
    for b in report.get("benchmarks", []):
        name = b.get("run_name", b["name"])
        name = re.sub(r"(/iterations:[0-9]+)?(/real_time)?$", "", name)
        if b.get("run_type") == "aggregate":
            if b.get("aggregate_name") == "median":
                chosen[name] = b
        elif name not in chosen or chosen[name].get("run_type") != "aggregate":
            chosen[name] = b
    return chosen


def fmt(value, unit=""):
    if value is None:
        return "-"
    if value >= 100:
        text = f"{value:,.0f}"
    elif value >= 10:
        text = f"{value:.1f}"
    else:
        text = f"{value:.2f}"
    return text + (" " + unit if unit else "")


def ratio(value):
    return "-" if value is None else fmt(value) + "x"


def time_ms(run, which="real_time"):
    scale = {"ns": 1e-6, "us": 1e-3, "ms": 1.0, "s": 1e3}[run.get("time_unit", "ns")]
    return run[which] * scale


def recorded(baseline, name):
    for f in baseline.get("figures", []):
        if f["benchmark"] == name:
            return f
    return None


def row(what, name, kind, run, runs, baseline):
    """One table row: what, benchmark, ours, peer, ratio (the peer's time over ours: above 1, ours is faster)."""
    c = run
    counter = baseline.get("counter", "")
    if kind == "gl":
        note = "" if c.get("pcs_equal", 1) == 1 else " (PCS differs!)"
        return [what, name, fmt(c.get("cpu_ms"), "ms"), fmt(c.get("gl_ms"), "ms") + " llvmpipe",
                ratio(c.get("speedup")) + note]
    if kind == "cgal":
        return [what, name, fmt(c.get("ours_ms"), "ms"), fmt(c.get("cgal_ms"), "ms") + " CGAL",
                ratio(c.get("vs_cgal_median")) + " (median of call pairs)"]
    if kind == "hierarchy":
        ours = time_ms(run)
        x = c.get(counter)
        same = c.get(baseline.get("same_counter", ""), 0) == 1
        peer = fmt(ours * x, "ms") + " 0.1.0 build" if x else "-"
        ratio_text = ratio(x)
        return [what, name, fmt(ours, "ms"), peer,
                ratio_text + ("" if same else " (hierarchy differs!)")]
    if kind == "tiles":
        tiles = runs.get(name.replace("direct:1", "direct:0"))
        peer = fmt(tiles.get("Mtri/s"), "M tris/s") + " tiles" if tiles else "-"  # the counter is in M/s
        return [what, name, fmt(c.get("Mtri/s"), "M tris/s"), peer, ratio(c.get("x_tiles"))]
    if kind == "recorded":
        ours = time_ms(run, "cpu_time")
        ref = recorded(baseline, name)
        x = c.get(counter)
        peer = f"{fmt(ref['value'], 'ms')} 0.1.0 build (recorded)" if ref else "-"
        return [what, name, fmt(ours, "ms"), peer, ratio(x) + " (recorded)" if x else "-"]
    raise ValueError(kind)


def provenance(report, cpuinfo="/proc/cpuinfo"):
    ctx = report.get("context", {})
    model = ctx.get("cpu_model", "unknown")
    if model == "unknown" and os.path.exists(cpuinfo):
        with open(cpuinfo) as f:
            for line in f:
                if line.startswith("model name"):
                    model = line.split(":", 1)[1].strip()
                    break
    load = ctx.get("load_avg")
    load = f", load average {load[0]:.1f} at the start" if load else ""
    return (f"Run of {ctx.get('date', '?')} on host `{ctx.get('host_name', '?')}`: {model}, "
            f"{ctx.get('num_cpus', '?')} CPUs at {ctx.get('mhz_per_cpu', '?')} MHz{load}; "
            f"cullide {ctx.get('cullide_version', '?')} at commit `{ctx.get('git_commit', '?')}`, "
            f"{ctx.get('compiler', '?')}.")


def table(report, baseline):
    runs = runs_by_name(report)
    lines = [provenance(report), "",
             "| what | benchmark | ours | peer | ratio |", "|---|---|---|---|---|"]
    missing = []
    for what, name, kind in ROWS:
        run = runs.get(name)
        if run is None:
            missing.append(name)
            continue
        cells = row(what, name, kind, run, runs, baseline)
        cells[1] = f"`{name}`"
        lines.append("| " + " | ".join(cells) + " |")
    if missing:
        lines += ["", "Not in this run: " + ", ".join(f"`{m}`" for m in missing) + "."]
    return "\n".join(lines) + "\n"


def write_between_markers(path, text):
    with open(path) as f:
        doc = f.read()
    start, stop = doc.find(BEGIN), doc.find(END)
    if start < 0 or stop < start:
        raise SystemExit(f"bench_table.py: {path} has no '{BEGIN}' ... '{END}' markers")
    doc = doc[:start + len(BEGIN)] + "\n" + text + doc[stop:]
    with open(path, "w") as f:
        f.write(doc)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("json", nargs="?", help="cullide_bench --benchmark_format=json output")
    p.add_argument("--baseline", default=DEFAULT_BASELINE, help="recorded figures (bench/baseline.json)")
    p.add_argument("--write", metavar="DOC", help="replace the table between the markers of DOC")
    p.add_argument("--filter", action="store_true", help="print the --benchmark_filter for the rows")
    a = p.parse_args(argv)
    if a.filter:
        print(filter_regex())
        return 0
    if not a.json:
        p.error("the benchmark JSON is required")
    try:
        with open(a.json) as f:
            report = json.load(f)
        with open(a.baseline) as f:
            baseline = json.load(f)
    except (OSError, json.JSONDecodeError) as e:
        print(f"bench_table.py: {e}", file=sys.stderr)
        return 2
    text = table(report, baseline)
    if a.write:
        write_between_markers(a.write, text)
    else:
        sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
