"""The command line of `cullide plot` and `cullide report` (tools/plot.py runs main): each input
drawn by the charts its content calls for, or (--report) the report page. An input that is none
of those the package reads, or an output that cannot be written, is `cullide: error: PATH: CAUSE`
on stderr and exit status 2, as for every cullide command. Every input is read and checked
before matplotlib is loaded and anything is written: bad input is refused at once."""
import argparse
import sys

from . import __doc__ as DESCRIPTION
from .inputs import read_input, read_report_inputs
from .load import InputError


def charts(method):
    """The chart modules (matplotlib), the per-call charts' method set."""
    from . import bench_charts, encodings, output, paper_figures, stability_charts, study_charts
    if method:
        encodings.METHOD.update(name=method, chosen=True)
    return bench_charts, output, paper_figures, stability_charts, study_charts


def plot(inputs, out, method):
    read = [(path, *read_input(path)) for path in inputs]
    bench_charts, output, paper_figures, stability_charts, study_charts = charts(method)
    output.make_folder(out)
    for path, kind, data in read:
        if kind == "study":
            study_charts.plot_study_rows(data, out)
        elif kind == "stability":
            stability_charts.plot_stability(data, out)
        elif kind == "prune":
            paper_figures.plot_prune_json(data, path, out)
        else:
            bench_charts.plot_benchmark(data, path, out)
    return 0


def report(inputs, out, method, view=None):
    rows = read_report_inputs(inputs)
    charts(method)
    from .report import write_report
    return write_report(rows, inputs, out, view)


def main():
    ap = argparse.ArgumentParser(description=DESCRIPTION, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("inputs", nargs="+")
    ap.add_argument("-o", "--out", default="figures")
    ap.add_argument("--method", help="method of the per-call charts (Figures 9-11; default: modified)")
    ap.add_argument("--report", action="store_true", help="write OUT/report.html instead of the charts")
    ap.add_argument("--view", help="the report's 3D view: a frame written by `cullide report --view-scene`")
    ap.add_argument("--view-audit", help="the 3D view's missed and spurious pairs: `cullide audit --json` output")
    ap.add_argument("--view-method", help="the name of the audited method, for the 3D view's captions")
    a = ap.parse_args()
    try:
        if a.report:
            view = {"frame": a.view, "audit": a.view_audit, "method": a.view_method}
            return report(a.inputs, a.out, a.method, view)
        return plot(a.inputs, a.out, a.method)
    except InputError as e:
        message = str(e)
    except OSError as e:  # an output (or input) the system refuses, named by the path it gave
        message = f"{e.filename if e.filename is not None else 'plot'}: {e.strerror or e}"
    print(f"cullide: error: {message}", file=sys.stderr)
    return 2
