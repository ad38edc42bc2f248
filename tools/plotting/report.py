"""`cullide report`: one HTML page with nothing outside it (charts as data: URIs, styles inline; no
scripts but the 3D view's, inlined with three.js when one is asked for: view3d), well-formed
(every element closed, text escaped), so that it can be mailed, archived and parsed by a test."""
import os
from collections import defaultdict

from .encodings import AXES, ordered, pareto, scene_configs, scene_name
from .load import num
from .output import SAVE, make_folder, say
from .study_charts import image_space_rows, plot_study_rows


REPORT_CSS = """
body { font-family: sans-serif; max-width: 72em; margin: 1.5em auto; padding: 0 1em; color: #222; }
h1 { font-size: 1.5em; } h2 { font-size: 1.2em; border-bottom: 1px solid #ccc; margin-top: 1.6em; }
h3 { font-size: 1.05em; margin-bottom: 0.3em; }
table { border-collapse: collapse; margin: 0.5em 0 1em; font-size: 0.9em; }
th, td { border: 1px solid #ccc; padding: 0.2em 0.6em; text-align: left; }
td.n { text-align: right; font-variant-numeric: tabular-nums; }
th { background: #f2f2f2; }
pre { background: #f6f6f6; padding: 0.6em; white-space: pre-wrap; word-break: break-all; }
figure { margin: 1em 0 2em; } figure img { max-width: 100%; height: auto; border: 1px solid #eee; }
figcaption { font-size: 0.9em; color: #444; max-width: 60em; }
.note { color: #555; font-size: 0.9em; }
"""


CAPTIONS = {
    "speed_vs_accuracy": "Time (median of the timed runs) against false prunes (% of the triangles the oracle finds "
                         "colliding), one panel per scene. Colour: method; marker: the other axes that vary. Ringed "
                         "points are Pareto-optimal: no other configuration is both faster and prunes fewer.",
    "figure8_time_vs_triangles": "Pruning time against triangle count for the generated scenes swept at several "
                                 "sizes (bars: min-max of the timed runs), with the paper's measured ranges.",
    "false_prunes_by_cause": "False-pruned triangles by cause (Section 5 of the paper): depth rounding, sampling, "
                             "edge-on; 'untested' are pairs the method never tests (the original method's self "
                             "pairs). Labels: false prunes / colliding triangles.",
    "figure9_10_passes": "Per reducePCS call: time (blue, left axis) and triangles rendered (orange, right axis), "
                         "for one run per scene of the chosen method (the paper's Figures 9 and 10).",
    "methods": "Every method on one chart, one panel per scene: the time to exact pairs per frame (a peer's refit "
               "included, its one build per sequence not) against the pairs missed (top) and the pairs reported "
               "that the oracle does not hold (bottom), as % of the oracle's pairs. Colour: family (image-space blue, exact black, peers red and "
               "orange); marker: method. Dashed: 1 %.",
    "frame_times": "Time to exact pairs per frame along each animated scene, every method (image-space: prune and "
                   "exact stage; peers: refit and query, the build once per sequence not counted).",
    "figure11_accumulated": "Accumulated share of the triangles pruned against the accumulated share of the time, "
                            "per call (the paper's Figure 11): a curve above the diagonal spends its time before "
                            "it prunes.",
}


def esc(v):
    import html
    return html.escape(str(v), quote=True)


def cell(v, numeric=False):
    return f'<td class="n">{esc(v)}</td>' if numeric else f"<td>{esc(v)}</td>"


def fmt(v, digits=1):
    return "" if v is None else (f"{v:,.{digits}f}" if digits else f"{int(round(v)):,}")


def html_table(headers, rows, cls=None, attrs=""):
    head = "".join(f"<th>{esc(h)}</th>" for h in headers)
    body = "".join("<tr>" + "".join(r) + "</tr>\n" for r in rows)
    c = f' class="{cls}"' if cls else ""
    return f"<table{c}{attrs}>\n<thead><tr>{head}</tr></thead>\n<tbody>\n{body}</tbody>\n</table>\n"


def config_cells(r):
    return [cell(r.get("method")), cell(r.get("resolution")), cell(r.get("depth")), cell(r.get("directions")),
            cell(f"{r.get('hierarchy')}/{r.get('leaf_size')}"), cell(f"{r.get('backend')} x{r.get('threads')}")]


CONFIG_HEADERS = ["method", "resolution", "depth", "directions", "hierarchy/leaf", "backend x threads"]


def pareto_section(rows):
    parts = []
    by_scene = scene_configs(rows)
    for scene in ordered(str(r["scene"]) for r in rows):
        confs = list(by_scene[scene].values())
        measured = all(g["measured"] for g in confs)
        if measured:
            front = pareto([(g["time_ms"], g["false_prunes"]) for g in confs])
        else:  # no oracle: the fastest only
            best = min(g["time_ms"] for g in confs)
            front = [i for i, g in enumerate(confs) if g["time_ms"] == best]
        chosen = sorted((confs[i] for i in front), key=lambda g: g["time_ms"])
        frames = confs[0]["frames"]
        table_rows = []
        for g in chosen:
            r = g["row"]
            table_rows.append(config_cells(r) + [
                cell(fmt(g["time_ms"]), True), cell(fmt(g["false_prunes"], 0) if measured else "n/a", True),
                cell(f"{g['rate']:.2f}" if measured else "n/a", True), cell(fmt(g["pcs"], 0), True),
                cell(fmt(g["false_positives"], 0) if measured else "n/a", True)])
        colliding = int(confs[0]["colliding"])
        parts.append(f'<h3>{esc(scene_name(scene))} <span class="note">({esc(scene)}'
                     + (f", {frames} frames summed" if frames > 1 else "")
                     + (f", {colliding:,} colliding triangles" if measured else ", no oracle")
                     + f"; {len(chosen)} of {len(confs)} configurations)</span></h3>\n")
        parts.append(html_table(CONFIG_HEADERS + ["time ms", "false prunes", "% of colliding", "PCS",
                                                  "false positives"], table_rows, "pareto",
                                f' data-scene="{esc(scene)}"'))
    return "".join(parts)


def pareto_part(rows):
    image = image_space_rows(rows)
    return pareto_section(image) if image else '<p class="note">No image-space runs.</p>\n'


def provenance_section(rows, inputs):
    keys = ["cullide_version", "git_commit", "compiler", "cpu_model", "threads", "drivers"]
    values = defaultdict(list)
    dates = []
    for r in rows:
        p = r.get("provenance") if isinstance(r, dict) else None
        if not isinstance(p, dict):
            continue
        for k in keys:
            if k in p:
                v = ", ".join(map(str, p[k])) if isinstance(p[k], list) else str(p[k])
                if v not in values[k]:
                    values[k].append(v)
        if "date" in p:
            dates.append(str(p["date"]))
    table_rows = [[cell(k.replace("_", " ")), cell("; ".join(values[k]))] for k in keys if values[k]]
    if dates:
        table_rows.append([cell("dates (UTC)"), cell(f"{min(dates)} to {max(dates)}")])
    table_rows.append([cell("input files"), cell("; ".join(inputs))])
    table_rows.append([cell("runs"), cell(str(len(rows)))])
    if not any(values.values()):
        return ('<p class="note">No provenance: the input has no JSON lines (the .jsonl beside the .csv); '
                "only its CSV columns were read.</p>\n" + html_table(["", ""], table_rows, "provenance"))
    return html_table(["what", "value"], table_rows, "provenance")


def command_section(rows):
    commands = defaultdict(int)
    for r in rows:
        c = r.get("command") if isinstance(r, dict) else None
        if isinstance(c, str) and c:
            commands[c] += 1
    if not commands:
        return ('<p class="note" id="no-command">The command is not recorded in these results (a study output '
                "from before cullide recorded it, or a CSV without its .jsonl).</p>\n")
    text = "".join(f"<pre class=\"command\">{esc(c)}</pre>\n" + (f'<p class="note">{n} run(s)</p>\n'
                                                               if len(commands) > 1 else "")
                   for c, n in commands.items())
    return text + '<p class="note">Run from the folder the study ran in; runs already in the output are skipped.</p>\n'


def axes_section(rows):
    table_rows = []
    scenes = ordered(str(r["scene"]) for r in rows)
    table_rows.append([cell("scenes"), cell("; ".join(f"{scene_name(s)} ({s})" for s in scenes))])
    for a in AXES:
        table_rows.append([cell(a.replace("_", " ")), cell(", ".join(ordered(str(r.get(a)) for r in rows)))])
    return html_table(["axis", "values"], table_rows, "axes")


def runs_section(rows):
    table_rows = []
    for r in rows:
        table_rows.append([cell(scene_name(r["scene"])), cell(r.get("frame"))] + config_cells(r) + [
            cell(fmt(num(r.get("time_ms"))), True), cell(r.get("calls"), True), cell(r.get("pcs"), True),
            cell("" if num(r.get("colliding")) is None else r.get("colliding"), True),
            cell("" if num(r.get("false_prunes")) is None else r.get("false_prunes"), True)])
    return html_table(["scene", "frame"] + CONFIG_HEADERS + ["time ms", "calls", "PCS", "colliding",
                                                             "false prunes"], table_rows, "runs")


def view_part(view):
    """The 3D view's section and its contents entry, or nothing when none was asked for."""
    if not view or not view.get("frame"):
        return "", ""
    from .view3d import view_section
    section = view_section(view["frame"], view.get("audit"), view.get("method"))
    return '<h2 id="view">3D view of a frame</h2>\n' + section, '<a href="#view">3D view</a>, '


def write_report(rows, inputs, out, view=None):
    """OUT/report.html of the records `rows` (inputs.read_report_inputs) read from `inputs`, with
    the 3D view of `view` ({"frame", "audit", "method"}: view3d) when given."""
    import base64
    import datetime
    import tempfile
    view_html, view_link = view_part(view)  # its inputs checked before any chart is drawn
    SAVE.update(formats=("png",), print=False)
    with tempfile.TemporaryDirectory() as tmp:
        made = plot_study_rows(rows, tmp)
        figures = []
        for name in made:
            with open(os.path.join(tmp, name + ".png"), "rb") as f:
                data = base64.b64encode(f.read()).decode("ascii")
            figures.append(f'<figure id="{esc(name)}"><img src="data:image/png;base64,{data}" '
                           f'alt="{esc(name.replace("_", " "))}" />\n<figcaption>{esc(CAPTIONS.get(name, ""))}'
                           "</figcaption></figure>\n")
    scenes = ordered(str(r["scene"]) for r in rows)
    now = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    page = (
        '<!DOCTYPE html>\n<html lang="en">\n<head>\n<meta charset="utf-8" />\n'
        f"<title>cullide study report: {len(rows)} runs, {len(scenes)} scene(s)</title>\n"
        f"<style>{REPORT_CSS}</style>\n</head>\n<body>\n"
        f"<h1>cullide study: {len(rows)} runs over {len(scenes)} scene(s)</h1>\n"
        '<p class="note">Made by <code>cullide report</code> at ' + esc(now) + ". Contents: "
        '<a href="#command">command</a>, <a href="#provenance">provenance</a>, <a href="#pareto">Pareto-optimal '
        'configurations</a>, <a href="#charts">charts</a>, ' + view_link + '<a href="#runs">all runs</a>.</p>\n'
        '<h2 id="command">The command that produced the data</h2>\n' + command_section(rows) +
        '<h2 id="provenance">Provenance</h2>\n' + provenance_section(rows, inputs) +
        '<h2 id="axes">The sweep</h2>\n' + axes_section(rows) +
        '<h2 id="pareto">Pareto-optimal configurations, per scene</h2>\n'
        '<p class="note">Configurations that no other of the same scene beats on both time and false prunes '
        "(frames of an animation summed), fastest first.</p>\n" + pareto_part(rows) +
        '<h2 id="charts">Charts</h2>\n' + ("".join(figures) or '<p class="note">No charts.</p>\n') + view_html +
        '<h2 id="runs">All runs</h2>\n<details><summary>' + f"{len(rows)} runs" + "</summary>\n" +
        runs_section(rows) + "</details>\n</body>\n</html>\n")
    make_folder(out)
    path = os.path.join(out, "report.html")
    try:  # the page whole or not at all
        with open(path + ".tmp", "w", encoding="utf-8") as f:
            f.write(page)
        os.replace(path + ".tmp", path)
    except OSError:
        if os.path.exists(path + ".tmp"):
            os.remove(path + ".tmp")
        raise
    say(path)
    return 0
