"""The command line of `cullide plot` and `cullide report` (tools/plot.py runs main): each input
drawn by the charts its content calls for, or (--report) the report page."""
import argparse
import json
import os
import sys

from . import __doc__ as DESCRIPTION
from .bench_charts import plot_benchmark
from .encodings import METHOD
from .load import read_csv
from .paper_figures import plot_prune_json
from .report import write_report
from .stability_charts import plot_stability
from .study_charts import plot_study


def main():
    ap = argparse.ArgumentParser(description=DESCRIPTION, formatter_class=argparse.RawDescriptionHelpFormatter)
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
