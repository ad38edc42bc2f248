"""What `cullide plot` and `cullide report` accept, and the checks that make an input one of them:
study outputs (docs/studies.md: the CSV's columns, or the JSON lines beside it), stability sweeps,
`prune --json` files and Google Benchmark JSON. Anything else, or a record whose numbers are not
numbers, raises InputError naming the file and the line, so that no chart is drawn from it."""
import math
import os
import re

from .load import InputError, csv_header, read_csv, read_json, read_jsonl

# The causes of false prunes (docs/studies.md), in the charts' order.
CAUSES = ["depth_rounding", "sampling", "edge_on", "untested", "unexplained"]
# The columns every study run writes (its configuration, times and counts) ...
STUDY_TEXT = ["scene", "method"]
STUDY_NUMBERS = ["index", "frame", "triangles", "objects", "direction_count", "leaf_size", "branching", "threads",
                 "repeats", "time_ms", "time_min_ms", "time_max_ms", "hierarchy_ms", "calls", "levels",
                 "triangles_rendered", "queries", "pcs"]
STUDY_REQUIRED = STUDY_TEXT + ["triangles", "time_ms", "calls", "pcs"]
# ... and those it leaves empty (null) without the oracle (--no-oracle), or, for
# switched_at_level, when the run never switched to exact pairs.
STUDY_MAYBE_EMPTY = (["oracle_pairs", "oracle_crossing", "oracle_touching", "colliding", "false_prunes",
                      "fp_crossing", "fp_touching"] + ["fp_" + c for c in CAUSES] +
                     ["missed_pairs", "mp_crossing", "mp_touching"] + ["mp_" + c for c in CAUSES] +
                     ["false_positives", "efficiency", "attribution_ms", "switched_at_level", "exact_ms",
                      "time_to_exact_ms", "near_distance", "near_contacts", "near_contacts_self"])
# Every method's measures against the oracle (docs/studies.md): a study from before the peers lacks
# them; a run without the oracle leaves the pair counts empty, an image-space run the causes.
FAMILIES = ["image-space", "exact", "peer"]
MISSED_CAUSES = ["untested", "shared_edge", "shared_vertex", "coplanar", "touching", "within_tolerance", "unexplained"]
SPURIOUS_CAUSES = ["degenerate", "shared_edge", "shared_vertex", "coplanar", "within_tolerance", "behind_face",
                   "unexplained"]
METHOD_MAYBE_EMPTY = (["time_to_pairs_ms", "pairs_found", "pairs_missed", "pairs_spurious", "tolerance"] +
                      ["missed_" + c for c in MISSED_CAUSES] + ["spurious_" + c for c in SPURIOUS_CAUSES])
# What only the image-space methods have: the exact method and the peers leave these empty.
IMAGE_SPACE_ONLY = ["direction_count", "leaf_size", "branching", "time_ms", "time_min_ms", "time_max_ms",
                    "hierarchy_ms", "calls", "levels", "triangles_rendered", "queries", "pcs"]
PASS_NUMBERS = ["seconds", "triangles_in", "triangles_out", "triangles_rendered"]
PASS_OPTIONAL = ["width", "height", "tiles", "views"]
# Stability sweeps: each sweep's columns (text, then numbers), and the numbers any of them has
# (`sampled_steps` is empty where the penetration was not sampled).
SWEEPS = {"penetration": (["method", "depth"], ["factor", "detected"]),
          "tilt": (["method", "directions"], ["angle", "detected"]),
          "overlap": (["method", "depth"], ["size", "detected"]),
          "jitter": (["scene", "method", "kind"], ["magnitude", "pcs", "false_prunes"])}
STABILITY_NUMBERS = (["resolution", "factor", "angle", "size", "magnitude", "trial", "delta_steps", "detected",
                      "pcs", "oracle_pairs", "false_prunes"] + ["fp_" + c for c in CAUSES])
JITTER_KINDS = {"none", "perturb", "rotation"}
DECIMAL = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?")


def number_problem(v, may_be_empty=False, signed=False):
    """None when v is a finite number (a JSON number or decimal text), >= 0 unless signed, else
    what it is."""
    if v is None or v == "":
        return None if may_be_empty else "empty"
    if isinstance(v, bool) or not isinstance(v, (int, float, str)):
        return f"{v!r}, not a number"
    if isinstance(v, str) and not DECIMAL.fullmatch(v):
        return f"{v!r}, not a number"
    x = float(v)
    if not math.isfinite(x):
        return f"{v!r}, not a finite number"
    return f"{v!r}, below 0" if x < 0 and not signed else None


def at(r):
    """Where a record is, for messages: its line, or its place in a JSON file."""
    return r.line if isinstance(r.line, str) else f"line {r.line}"


def check_numbers(path, r, names, may_be_empty=False, signed=False):
    for k in names:
        if k in r:
            problem = number_problem(r[k], may_be_empty, signed)
            if problem:
                raise InputError(path, f"{at(r)}: {k} is {problem}")


def check_text(path, r, names):
    for k in names:
        if not isinstance(r.get(k), str) or not r[k]:
            raise InputError(path, f"{at(r)}: {k} is {'empty' if r.get(k) in (None, '') else repr(r[k])}, "
                                   "not a name")


def check_passes(path, r):
    """A JSON line's per-call statistics: a list of objects with their counts and seconds."""
    passes = r.get("passes")
    if passes is None:
        return
    if not isinstance(passes, list) or not all(isinstance(p, dict) for p in passes):
        raise InputError(path, f"{at(r)}: passes is not a list of objects")
    for i, p in enumerate(passes):
        missing = [k for k in PASS_NUMBERS if k not in p]
        if missing:
            raise InputError(path, f"{at(r)}: passes[{i}] has no {', '.join(missing)}")
        for k in PASS_NUMBERS + PASS_OPTIONAL:
            problem = number_problem(p.get(k), may_be_empty=k in PASS_OPTIONAL and k not in p)
            if problem:
                raise InputError(path, f"{at(r)}: passes[{i}].{k} is {problem}")


def check_study(path, rows, header=None):
    """Study records as docs/studies.md describes them (an output from before a column was added
    lacks it, and is read without it)."""
    if header is not None:
        missing = [c for c in STUDY_REQUIRED if c not in header]
        if missing:
            raise InputError(path, f"not a study output: it has no column {', '.join(missing)}")
    if not rows:
        raise InputError(path, "no study records" + (" (a header only)" if header is not None else ""))
    for r in rows:
        missing = [c for c in STUDY_REQUIRED if c not in r]
        if missing:
            raise InputError(path, f"line {r.line}: not a study record: it has no {', '.join(missing)}")
        check_text(path, r, STUDY_TEXT)
        family = r.get("family")
        if family not in (None, "") and family not in FAMILIES:
            raise InputError(path, f"{at(r)}: family is {family!r}: {', '.join(FAMILIES)}")
        image_space = family in (None, "", "image-space")
        check_numbers(path, r, [c for c in STUDY_NUMBERS if image_space or c not in IMAGE_SPACE_ONLY])
        check_numbers(path, r, STUDY_MAYBE_EMPTY + METHOD_MAYBE_EMPTY +
                      ([] if image_space else IMAGE_SPACE_ONLY), may_be_empty=True)
        check_passes(path, r)
    return rows


def check_stability(path, header, rows):
    if not rows:
        raise InputError(path, "no stability trials (a header only)")
    sweep = rows[0]["sweep"]
    if sweep not in SWEEPS:
        raise InputError(path, f"line {rows[0].line}: sweep is {sweep!r}: {', '.join(SWEEPS)}")
    text, numbers = SWEEPS[sweep]
    missing = [c for c in text + numbers if c not in header]
    if missing:
        raise InputError(path, f"not a {sweep} sweep: it has no column {', '.join(missing)}")
    for r in rows:
        if r["sweep"] != sweep:
            raise InputError(path, f"line {r.line}: a {r['sweep']!r} trial in a {sweep} sweep")
        check_text(path, r, text)
        check_numbers(path, r, STABILITY_NUMBERS, signed=True)
        check_numbers(path, r, ["sampled_steps"], may_be_empty=True, signed=True)
        if sweep == "jitter" and r["kind"] not in JITTER_KINDS:
            raise InputError(path, f"line {r.line}: kind is {r['kind']!r}: {', '.join(sorted(JITTER_KINDS))}")
    return rows


def check_prune_json(path, j):
    frames = j["frames"]
    if not isinstance(frames, list) or not all(isinstance(f, dict) for f in frames):
        raise InputError(path, "frames is not a list of objects")
    for i, f in enumerate(frames):
        if f.get("passes") is None:
            continue
        if "frame" not in f or number_problem(f.get("triangles")):
            raise InputError(path, f"frames[{i}]: no frame number or triangle count")
        check_passes(path, _Located(f, f"frames[{i}]"))
    if not any(f.get("passes") for f in frames):
        raise InputError(path, "nothing to draw: no frame has per-call statistics (passes)")
    return j


class _Located(dict):
    """A JSON object checked as a record, located by its path in the file instead of a line."""

    def __init__(self, d, where):
        super().__init__(d)
        self.line = where


def check_benchmark_json(path, j):
    benches = j["benchmarks"]
    if not isinstance(benches, list) or not all(isinstance(b, dict) for b in benches):
        raise InputError(path, "benchmarks is not a list of objects")
    timed = [b for b in benches if b.get("run_type", "iteration") == "iteration"]
    for i, b in enumerate(timed):
        if not isinstance(b.get("name"), str) or not isinstance(b.get("time_unit", "ns"), str):
            raise InputError(path, f"benchmark {i + 1}: no name or time_unit as Google Benchmark writes them")
        problem = number_problem(b.get("real_time"))
        if problem:
            raise InputError(path, f"benchmark {i + 1} ({b['name']}): real_time is {problem}")
    if not timed:
        raise InputError(path, "no benchmark runs (run_type iteration)")
    return j


def read_study(path):
    """A study's checked records: its JSON lines (the .jsonl beside a .csv where there is one: they
    carry the per-call statistics and provenance), else its CSV rows."""
    base, ext = os.path.splitext(path)
    if ext not in (".csv", ".jsonl"):
        raise InputError(path, "a study output is a .csv or .jsonl file")
    jsonl = base + ".jsonl"
    if ext == ".jsonl" or os.path.exists(jsonl):
        return check_study(jsonl, read_jsonl(jsonl))
    header, rows = read_csv(path)
    return check_study(path, rows, header)


def read_report_inputs(paths):
    """The records of the studies a report is made of, checked."""
    rows = []
    for path in paths:
        if not (path.endswith(".csv") or path.endswith(".jsonl")):
            raise InputError(path, "a report is made of study outputs (.csv or .jsonl)")
        if path.endswith(".csv") and "sweep" in csv_header(path):
            raise InputError(path, "a stability sweep, not a study output")
        rows += read_study(path)
    return rows


def read_input(path):
    """(kind, data) of a `cullide plot` input, checked: ("study", records), ("stability", rows),
    ("prune", JSON) or ("benchmark", JSON)."""
    if path.endswith(".json"):
        j = read_json(path)
        if isinstance(j, dict) and "benchmarks" in j:
            return "benchmark", check_benchmark_json(path, j)
        if isinstance(j, dict) and "frames" in j:
            return "prune", check_prune_json(path, j)
        what = "a JSON object without 'frames' or 'benchmarks'" if isinstance(j, dict) else \
            f"a JSON {type(j).__name__}"
        raise InputError(path, f"{what}: not a prune --json or Google Benchmark file")
    if path.endswith(".csv") and "sweep" in csv_header(path):
        header, rows = read_csv(path)
        return "stability", check_stability(path, header, rows)
    if path.endswith(".csv") or path.endswith(".jsonl"):
        return "study", read_study(path)
    raise InputError(path, "expected a study or stability .csv, a study .jsonl, or a .json file")
