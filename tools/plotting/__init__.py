"""Charts for cullide: `cullide plot INPUT... -o DIR` (PNG and SVG of each chart), and
`cullide report STUDY... -o DIR` (--report: DIR/report.html, one self-contained page).

Inputs, recognised by content:
  - study results (`cullide study`, .csv or .jsonl; the .jsonl beside a .csv is read for the
    per-call statistics): speed vs accuracy with the Pareto front (one panel per scene), time vs
    triangle count of generated scenes swept at several sizes (the paper's Figure 8), per-call
    time and triangles rendered (Figures 9-10) and accumulated % pruned vs accumulated % time
    (Figure 11) from the runs of one method (--method, default modified) with several calls,
    false prunes by cause; for studies with every method's columns (family, time_to_pairs_ms, ...),
    every method's time to exact pairs against pairs missed and spurious, and per frame;
  - stability sweeps (`cullide study --stability`, .csv with a `sweep` column);
  - `cullide prune --json` output: Figures 9-11 per frame;
  - Google Benchmark JSON (`cullide_bench --benchmark_format=json`): time per benchmark, and time
    vs `tris` where the names carry it.
Study charts: one colour per method, one marker per combination of the other axes that vary,
scenes by name ("bunny 5k", a file's name), a legend instead of per-point labels, log axes where
values span a decade or more.
Every input is read and checked first (inputs): one that is none of these, or a record whose
numbers are not numbers, is `cullide: error: FILE: CAUSE` and exit status 2, nothing drawn.
Needs matplotlib and numpy (Debian: /usr/bin/python3 with python3-matplotlib).
"""
# The modules: load (reading files: text, CSV, JSON lines, JSON), inputs (what each input must
# hold, checked), output (saving a chart, the lines on stdout), encodings (the study charts'
# colours, markers, scene names and per-scene summaries), study_charts, paper_figures (Figures 8-11),
# sequence_charts (per frame), method_charts (every method: image-space, exact, peers),
# stability_charts, bench_charts, report (`cullide report`'s page), view3d (its 3D view) and cli
# (the command line).
