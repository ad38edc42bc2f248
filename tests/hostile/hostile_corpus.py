#!/usr/bin/env python3
"""The hostile-input corpus: generates bad input for every surface of the `cullide` command (and
the Python module when it is importable) and checks that each is refused as the README promises:
exit status 2, a message naming the file or option, no signal, within the time limit; or, where
the input is legal, the correct result.

    python3 tests/hostile/hostile_corpus.py --cullide build/tools/cullide [--keep DIR] [-k NAME]

The corpus is written into a fresh temporary folder (or DIR with --keep) on every run, so the
files are always those this script describes. Exit status 0 when every case holds, 1 otherwise;
one line per case.
"""

import argparse
import json
import os
import shutil
import signal
import stat
import struct
import subprocess
import sys
import tempfile
import time

LIMIT_S = float(os.environ.get("CULLIDE_HOSTILE_LIMIT_S", "10"))

CUBE_OFF = """OFF
8 12 0
0 0 0
1 0 0
1 1 0
0 1 0
0 0 1
1 0 1
1 1 1
0 1 1
3 0 2 1
3 0 3 2
3 4 5 6
3 4 6 7
3 0 1 5
3 0 5 4
3 2 3 7
3 2 7 6
3 1 2 6
3 1 6 5
3 0 4 7
3 0 7 3
"""


class Case:
    """One command and what it must do: `rc` the exit status (a set when more than one answer is
    correct), `names` strings stderr must contain (the file or option), `check` an extra test of
    the folder afterwards (returns an error message or None)."""

    def __init__(self, name, argv, rc=2, names=(), stdout=None, check=None, limit_s=None):
        self.name, self.argv, self.names, self.stdout, self.check = name, argv, names, stdout, check
        self.rc = rc if isinstance(rc, (set, frozenset)) else {rc}
        self.limit_s = limit_s or LIMIT_S


def deep(n, open_="[", close="]", inner="0"):
    return open_ * n + inner + close * n


def write(d, name, text, mode="w"):
    path = os.path.join(d, name)
    with open(path, mode) as f:
        f.write(text)
    return path


def scene(objects, frames=None):
    s = {"objects": objects}
    if frames is not None:
        s["animation"] = {"frames": frames}
    return json.dumps(s)


def rewrite_trace_header(src, dst, edit):
    """Copies the trace at src to dst with its JSON header changed by edit(header), re-padded."""
    with open(src, "rb") as f:
        data = f.read()
    (length,) = struct.unpack("<Q", data[8:16])
    header = json.loads(data[16:16 + length])
    edit(header)
    text = json.dumps(header).encode()
    text += b" " * ((8 - (16 + len(text)) % 8) % 8)
    with open(dst, "wb") as f:
        f.write(data[:8] + struct.pack("<Q", len(text)) + text + data[16 + length:])


def leaves_nothing(d, *names):
    def check():
        left = [n for n in names if os.path.exists(os.path.join(d, n))]
        stray = [n for n in os.listdir(d) if ".tmp" in n]
        if left or stray:
            return "left behind: " + ", ".join(left + stray)
        return None
    return check


def mesh_cases(d):
    write(d, "cube.off", CUBE_OFF)
    fifo = os.path.join(d, "fifo.off")
    os.mkfifo(fifo)
    os.symlink("/dev/zero", os.path.join(d, "zero.off"))
    os.symlink("loop_b.off", os.path.join(d, "loop_a.off"))
    os.symlink("loop_a.off", os.path.join(d, "loop_b.off"))
    os.mkdir(os.path.join(d, "folder.off"))
    write(d, "nul_mesh.json", scene([{"name": "a", "mesh": "cu\u0000be.off"}]))
    write(d, "fifo_mesh.json", scene([{"name": "a", "mesh": "fifo.off"}]))
    write(d, "flat.off", "OFF\n3 1 0\n1 1 1\n1 1 1\n1 1 1\n3 0 1 2\n")
    return [
        Case("mesh: a FIFO", ["info", "fifo.off"], names=["fifo.off"]),
        Case("mesh: /dev/zero", ["info", "zero.off"], names=["zero.off"]),
        Case("mesh: a symlink loop", ["info", "loop_a.off"], names=["loop_a.off", "symbolic link"]),
        Case("mesh: a folder", ["info", "folder.off"], names=["folder.off"]),
        Case("scene: mesh path with a NUL", ["info", "nul_mesh.json"], names=["nul_mesh.json", "NUL"]),
        Case("scene: mesh that is a FIFO", ["prune", "fifo_mesh.json"], names=["fifo.off"]),
        Case("make-scene: mesh of zero extent", ["make-scene", "bunny", "--mesh", "flat.off", "-o", "flat_scene.json"],
             names=["flat.off"], check=leaves_nothing(d, "flat_scene.json")),
    ]


def scene_cases(d):
    cube = {"name": "a", "mesh": "cube.off"}
    write(d, "nested_scene.json", '{"objects": ' + deep(100000) + "}")
    write(d, "nested_object.json", '{"objects": [{"name": "a", "mesh": "cube.off", "x": ' + deep(100000) + "}]}")
    write(d, "dup_key.json", '{"objects": [{"name": "a", "name": "b", "mesh": "cube.off"}]}')
    write(d, "overflow.json", scene([dict(cube, transform={"scale": 1e38, "translate": [3e38, 0, 0]})]))
    write(d, "overflow_frame.json", scene([cube], frames=[{}, {"objects": {"a": {"transform": {"scale": 1e38, "translate": [3e38, 0, 0]}}}}]))
    write(d, "many_objects.json", scene([{"name": "o%d" % i, "mesh": "cube.off",
                                          "transform": {"translate": [2 * i, 0, 0]}} for i in range(100000)]))
    write(d, "empty_name.json", scene([{"name": "", "mesh": "cube.off"}]))
    write(d, "dup_name.json", scene([cube, cube]))
    return [
        Case("scene: nested 10^5 deep", ["info", "nested_scene.json"], names=["nested_scene.json", "deep"]),
        Case("scene: nested 10^5 deep in an object", ["prune", "nested_object.json"], names=["nested_object.json", "deep"]),
        Case("scene: a duplicate key", ["info", "dup_key.json"], names=["dup_key.json", "name"]),
        Case("scene: transform overflows float", ["info", "overflow.json"], names=["overflow.json"]),
        Case("scene: frame transform overflows float", ["prune", "overflow_frame.json"], names=["overflow_frame.json"]),
        Case("scene: 10^5 objects parse in time", ["info", "many_objects.json"], rc=0),
        Case("scene: an empty object name", ["info", "empty_name.json"], names=["empty_name.json"]),
        Case("scene: a duplicate object name", ["info", "dup_name.json"], names=["dup_name.json"]),
    ]


def positions_file(frames, vertices=8, magic=b"CULVERTS", nan_at=None):
    """A positions file (docs/scene-format.md) of the cube's vertices moved up by f in frame f; a NaN
    at frame nan_at when given."""
    data = magic + struct.pack("<IIQQ", 1, vertices, frames, 0)
    corners = [[float(c) for c in line.split()] for line in CUBE_OFF.splitlines()[2:2 + vertices]]
    for f in range(frames):
        for v, (x, y, z) in enumerate(corners):
            data += struct.pack("<3f", x, float("nan") if (f, v) == (nan_at, 3) else y, z + f)
    return data


def positions_cases(d):
    """Scenes whose deforming object's frames come from a positions file that is not what it says."""
    good = positions_file(3)
    write(d, "cut.pos", good[:-7], mode="wb")
    write(d, "magic.pos", positions_file(3, magic=b"CULTRACE"), mode="wb")
    write(d, "nan_later.pos", positions_file(3, nan_at=2), mode="wb")
    write(d, "seven.pos", positions_file(3, vertices=7), mode="wb")
    os.mkfifo(os.path.join(d, "fifo.pos"))
    for name in ["cut", "magic", "nan_later", "seven", "fifo"]:
        write(d, "pos_%s.json" % name, json.dumps({"objects": [{"name": "a", "mesh": "cube.off"}],
                                                   "animation": {"positions": {"a": name + ".pos"}}}))
    return [
        Case("positions file: truncated", ["info", "pos_cut.json"], names=["pos_cut.json", "cut.pos", "truncated"]),
        Case("positions file: wrong magic", ["info", "pos_magic.json"], names=["magic.pos", "wrong magic"]),
        Case("positions file: wrong vertex count", ["prune", "pos_seven.json"], names=["seven.pos", "vertex count"]),
        Case("positions file: NaN in a later frame", ["prune", "pos_nan_later.json", "--resolution", "16",
                                                      "--json", "pos_nan_out.json"],
             names=["nan_later.pos", "frame 2"], check=leaves_nothing(d, "pos_nan_out.json")),
        Case("positions file: NaN in a later frame, oracle", ["oracle", "pos_nan_later.json", "--frame", "2"],
             names=["nan_later.pos", "frame 2"]),
        Case("positions file: NaN in a later frame, info", ["info", "pos_nan_later.json", "--all-frames"],
             names=["nan_later.pos", "frame 2"]),
        Case("positions file: a FIFO", ["info", "pos_fifo.json"], names=["fifo.pos", "FIFO"]),
    ]


def trace_cases(d, cullide):
    write(d, "pair.json", scene([{"name": "a", "mesh": "cube.off"},
                                 {"name": "b", "mesh": "cube.off", "transform": {"translate": [0.5, 0.5, 0.5]}}]))
    subprocess.run([cullide, "trace", "record", "pair.json", "-o", "pair.trace", "--resolution", "32"], cwd=d,
                   check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, timeout=60)
    subprocess.run([cullide, "trace", "replay", "pair.trace", "--backend", "cpu", "-o", "answers.json"], cwd=d,
                   check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, timeout=60)
    src = os.path.join(d, "pair.trace")

    def no_frames(h):
        h["frames"] = []

    def wrong_summary(h):
        h["summary"]["queries"] += 1

    def deep_header(h):
        h["workload"]["x"] = json.loads(deep(200))  # valid JSON; the file is then made deeper below

    rewrite_trace_header(src, os.path.join(d, "no_frames.trace"), no_frames)
    rewrite_trace_header(src, os.path.join(d, "wrong_summary.trace"), wrong_summary)
    rewrite_trace_header(src, os.path.join(d, "nested.trace"), deep_header)
    with open(os.path.join(d, "nested.trace"), "rb") as f:
        data = f.read()
    (length,) = struct.unpack("<Q", data[8:16])
    header = data[16:16 + length].rstrip().replace(deep(200).encode(), deep(100000).encode())
    header += b" " * ((8 - (16 + len(header)) % 8) % 8)
    with open(os.path.join(d, "nested.trace"), "wb") as f:
        f.write(data[:8] + struct.pack("<Q", len(header)) + header + data[16 + length:])
    write(d, "nested_answers.json", '{"backend": "cpu", "results": ' + deep(100000) + "}")
    return [
        Case("trace: frames emptied, info", ["trace", "info", "no_frames.trace"], names=["no_frames.trace"]),
        Case("trace: frames emptied, replay", ["trace", "replay", "no_frames.trace", "--backend", "cpu", "-o", "x.json"],
             names=["no_frames.trace"], check=leaves_nothing(d, "x.json")),
        Case("trace: frames emptied, compare", ["trace", "compare", "no_frames.trace", "answers.json"],
             names=["no_frames.trace"]),
        Case("trace: summary disagrees with the data", ["trace", "info", "wrong_summary.trace"],
             names=["wrong_summary.trace"]),
        Case("trace: header nested 10^5 deep", ["trace", "info", "nested.trace"], names=["nested.trace", "deep"]),
        Case("trace: replay of a header nested 10^5 deep", ["trace", "replay", "nested.trace", "--backend", "cpu", "-o", "y.json"],
             names=["nested.trace"]),
        Case("trace compare: results nested 10^5 deep", ["trace", "compare", "pair.trace", "nested_answers.json"],
             names=["nested_answers.json", "deep"]),
        Case("trace compare: --worst -1", ["trace", "compare", "pair.trace", "answers.json", "--worst", "-1"],
             names=["--worst"]),
        Case("trace record: --depth-margin nan", ["trace", "record", "pair.json", "-o", "z.trace", "--depth-margin", "nan"],
             names=["--depth-margin"], check=leaves_nothing(d, "z.trace")),
    ]


def killed_record_case(d, cullide):
    """A `trace record` killed mid-run must leave no file: neither the trace nor its scratch."""
    sub = os.path.join(d, "killed")
    os.mkdir(sub)
    write(sub, "cube.off", CUBE_OFF)
    write(sub, "many.json", scene([{"name": "o%d" % i, "mesh": "cube.off",
                                    "transform": {"translate": [0.3 * i, 0, 0]}} for i in range(400)]))
    p = subprocess.Popen([cullide, "trace", "record", "many.json", "-o", "k.trace"], cwd=sub,
                         stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    # Kill it once it has started writing (its scratch appears), or after 3 s at most.
    until = time.monotonic() + 3
    while time.monotonic() < until and p.poll() is None and len(os.listdir(sub)) == 2:
        time.sleep(0.01)
    p.send_signal(signal.SIGKILL)
    p.wait()
    left = sorted(set(os.listdir(sub)) - {"cube.off", "many.json"})
    return ("trace record: killed mid-run leaves nothing", None if not left else "left behind: " + ", ".join(left))


def spec_cases(d):
    write(d, "nested_spec.json", '{"scenes": ' + deep(100000, inner='"bunny:1000"') + "}")
    write(d, "dup_spec.json", '{"scenes": ["pair.json"], "methods": ["original"], "methods": ["modified"]}')
    write(d, "huge_spec.json", json.dumps({
        "scenes": ["pair.json"] * 50, "resolutions": list(range(16, 2016)), "depths": list(range(8, 25)),
        "leaf_sizes": list(range(1, 51))}))
    return [
        Case("study spec: scenes nested 10^5 deep", ["study", "nested_spec.json", "-o", "a.csv"], names=["nested_spec.json", "deep"],
             check=leaves_nothing(d, "a.csv", "a.jsonl")),
        Case("study spec: a duplicate key", ["study", "dup_spec.json", "-o", "b.csv"], names=["dup_spec.json", "methods"],
             check=leaves_nothing(d, "b.csv", "b.jsonl")),
        Case("study spec: 8.5x10^7 runs", ["study", "huge_spec.json", "-o", "c.csv"], names=["huge_spec.json"],
             check=leaves_nothing(d, "c.csv", "c.jsonl")),
        Case("study: --resolutions 4294967396", ["study", "--scenes", "pair.json", "--resolutions", "4294967396",
                                                 "-o", "d.csv"], names=["4294967396"],
             check=leaves_nothing(d, "d.csv", "d.jsonl")),
    ]


def option_cases(d):
    return [
        Case("prune: --resolution 4294967396", ["prune", "pair.json", "--resolution", "4294967396"], names=["--resolution"]),
        Case("prune: --resolution 64x4294967360", ["prune", "pair.json", "--resolution", "64x4294967360"],
             names=["--resolution"]),
        Case("prune: --seed -1", ["prune", "pair.json", "--hierarchy", "random", "--seed", "-1"], names=["--seed"]),
        Case("prune: --seed 2^64", ["prune", "pair.json", "--hierarchy", "random", "--seed", "18446744073709551616"],
             names=["--seed"]),
        Case("prune: --max-viewport 4 finishes", ["prune", "cube.off", "--max-viewport", "4"], rc={0, 2}),
        Case("prune: --max-viewport 2 finishes", ["prune", "pair.json", "--max-viewport", "2"], rc={0, 2}),
        Case("make-scene: --tilt nan", ["make-scene", "sheets", "--tilt", "nan", "-o", "t.json"], names=["--tilt"],
             check=leaves_nothing(d, "t.json")),
        Case("make-scene: --seed -5", ["make-scene", "sheets", "--seed", "-5", "-o", "t2.json"], names=["--seed"]),
        Case("tune: --budget-ms nan", ["tune", "pair.json", "--budget-ms", "nan"], names=["--budget-ms"]),
        Case("validate: --worst -1", ["validate", "pair.json", "--worst", "-1"], names=["--worst"]),
        Case("info: --frame 4294967296", ["info", "pair.json", "--frame", "4294967296"], names=["--frame"]),
    ]


def stays(path, kind):
    """A check that `path` is still a FIFO or a symbolic link (an output renamed onto it replaced it)."""
    def check():
        is_kind = {"fifo": lambda p: stat.S_ISFIFO(os.lstat(p).st_mode), "link": os.path.islink}[kind]
        return None if os.path.lexists(path) and is_kind(path) else f"{path} is no longer a {kind}"
    return check


def linked_output(d):
    """`linked.json` -> `target.json`: oracle --json through the link must keep it a link."""
    def check():
        if not os.path.islink(os.path.join(d, "linked.json")):
            return "linked.json is no longer a symbolic link"
        with open(os.path.join(d, "target.json")) as f:
            return None if '"pairs"' in f.read() else "target.json does not hold the oracle's JSON"
    return check


def output_cases(d):
    os.mkdir(os.path.join(d, "taken.json"))  # a folder where the scene file would go
    os.mkdir(os.path.join(d, "e.jsonl"))  # a folder where the study's .jsonl would go
    os.mkfifo(os.path.join(d, "unread.fifo"))  # an output nobody reads: refused, not waited for
    write(d, "target.json", "{}")
    os.symlink("target.json", os.path.join(d, "linked.json"))
    cases = [
        Case("prune: --json into a FIFO nobody reads", ["prune", "pair.json", "--json", "unread.fifo"],
             names=["unread.fifo", "no process reads"], check=stays(os.path.join(d, "unread.fifo"), "fifo")),
        Case("trace record: into a FIFO", ["trace", "record", "pair.json", "-o", "unread.fifo"],
             names=["unread.fifo", "FIFO"], check=stays(os.path.join(d, "unread.fifo"), "fifo")),
        Case("oracle: --json through a symbolic link", ["oracle", "pair.json", "--json", "linked.json"], rc=0,
             check=linked_output(d)),
        Case("make-scene: scene file cannot be written", ["make-scene", "sheets", "-o", "taken.json"],
             names=["taken.json"], check=lambda: (
                 "left meshes: " + ", ".join(n for n in os.listdir(d) if n.startswith("taken_"))
                 if any(n.startswith("taken_") for n in os.listdir(d)) else None)),
        Case("study: .jsonl cannot be written", ["study", "--scenes", "pair.json", "--resolutions", "16", "-o", "e.csv"],
             names=["e.jsonl"], check=leaves_nothing(d, "e.csv")),
        Case("prune: --json into a missing folder", ["prune", "pair.json", "--json", "nowhere/p.json"],
             names=["nowhere/p.json"]),
    ]
    if os.path.exists("/dev/full"):
        cases.append(Case("info: stdout is full", ["info", "pair.json", "--json"], names=["stdout"], stdout="/dev/full"))
        cases.append(Case("oracle: stdout is full", ["oracle", "pair.json"], names=["stdout"], stdout="/dev/full"))
    return cases


def csv_cases(d):
    write(d, "empty.csv", "")
    write(d, "other.csv", "a,b,c\n1,2,3\n")
    write(d, "garbage.csv", b"\x00\x01\x02\xff\xfe" * 20, mode="wb")
    with open(os.path.join(d, "utf16.csv"), "wb") as f:
        f.write("scene,method\nx,y\n".encode("utf-16"))
    write(d, "ragged.csv", "scene,method,resolution\nx\ny,z,w,v\n")
    write(d, "not_results.json", '{"hello": 1}')
    cases = []
    for name in ["empty.csv", "other.csv", "garbage.csv", "utf16.csv", "ragged.csv", "not_results.json"]:
        cases.append(Case("plot: " + name, ["plot", name, "-o", "charts_" + name], names=[name]))
        cases.append(Case("report: " + name, ["report", name, "-o", "report_" + name], names=[name]))
    return cases


def audit_cases(d):
    """Pair lists for `cullide audit` (on the scene trace_cases writes, pair.json)."""
    header = "frame,object_a,triangle_a,object_b,triangle_b\n"
    write(d, "nested_pairs.json", '{"frames": ' + deep(100000) + "}")
    write(d, "garbage_pairs.csv", b"\x00\x01\x02\xff\xfe" * 20, mode="wb")
    write(d, "wide_pairs.csv", header + "0,0,4294967296,1,0\n")
    write(d, "many_pairs.csv", header + "0,0,0,1,0\n" * 1000000)
    write(d, "many_frames.json", '{"frames": [' + ",".join(['{"pairs": []}'] * 100000) + "]}")
    os.mkfifo(os.path.join(d, "fifo_pairs.csv"))
    return [
        Case("audit: pairs nested 10^5 deep", ["audit", "pair.json", "nested_pairs.json"], names=["nested_pairs.json", "deep"]),
        Case("audit: binary garbage", ["audit", "pair.json", "garbage_pairs.csv"], names=["garbage_pairs.csv", "line 1"]),
        Case("audit: a triangle index of 2^32", ["audit", "pair.json", "wide_pairs.csv"],
             names=["wide_pairs.csv", "line 2"]),
        Case("audit: 10^6 copies of one pair in time", ["audit", "pair.json", "many_pairs.csv"], rc={0, 1}),
        Case("audit: 10^5 frames for a still scene", ["audit", "pair.json", "many_frames.json"],
             names=["many_frames.json", "frame 1"]),
        Case("audit: a FIFO", ["audit", "pair.json", "fifo_pairs.csv"], names=["fifo_pairs.csv", "FIFO"]),
        Case("audit: --json into a missing folder", ["audit", "pair.json", "many_frames.json", "--frame", "0",
                                                     "--json", "nowhere/a.json"], names=["nowhere/a.json"]),
    ]


def python_cases(d):
    """The Python module's own refusals (ValueError naming the cause), when it can be imported."""
    code = r"""
import sys, cullide
checks = {
    "prune of an empty scene": lambda: cullide.prune(cullide.Scene()),
    "resolution 4294967396": lambda: cullide.prune(cullide.load_scene(sys.argv[1]), resolution=4294967396),
    "an empty object name": lambda: cullide.Scene().add("", [[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]]),
    "a mesh path with a NUL": lambda: cullide.load_mesh("cu\0be.off"),
    "a NaN in a positions file's frame 2": lambda: cullide.load_scene(sys.argv[2]).world_mesh(0, 2),
}
bad = 0
for name, f in checks.items():
    try:
        f()
        print(name + ": accepted"); bad += 1
    except ValueError as e:
        pass
    except Exception as e:
        print(name + ": " + type(e).__name__ + ": " + str(e)); bad += 1
sys.exit(1 if bad else 0)
"""
    try:
        import cullide
    except ImportError:
        return []
    # The package as this process found it, also from the corpus folder (PYTHONPATH may be relative).
    package = os.path.dirname(os.path.dirname(os.path.abspath(cullide.__file__)))
    return [("python", [sys.executable, "-c", "import sys; sys.path.insert(0, %r)\n" % package + code,
                        os.path.join(d, "pair.json"), os.path.join(d, "pos_nan_later.json")])]


def run_case(cullide, d, case):
    out = open(case.stdout, "w") if case.stdout else subprocess.DEVNULL
    start = time.monotonic()
    try:
        p = subprocess.run([cullide] + case.argv, cwd=d, stdout=out, stderr=subprocess.PIPE, timeout=case.limit_s)
    except subprocess.TimeoutExpired:
        return "still running after %.0f s" % case.limit_s
    finally:
        if case.stdout:
            out.close()
    took = time.monotonic() - start
    err = p.stderr.decode(errors="replace")
    if p.returncode < 0:
        return "killed by signal %d: %s" % (-p.returncode, err.strip()[-300:])
    if p.returncode not in case.rc:
        return "exit %d (want %s): %s" % (p.returncode, sorted(case.rc), err.strip()[-300:])
    if p.returncode == 2:
        missing = [n for n in case.names if n not in err]
        if missing or "Traceback" in err:
            return "message does not name %s: %s" % (missing, err.strip()[-300:])
    if case.check:
        problem = case.check()
        if problem:
            return problem
    return None if took <= case.limit_s else "took %.1f s" % took


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cullide", required=True)
    ap.add_argument("--keep", help="write the corpus into this folder and keep it")
    ap.add_argument("-k", help="run only cases whose name contains this")
    args = ap.parse_args()
    cullide = os.path.abspath(args.cullide)
    d = args.keep or tempfile.mkdtemp(prefix="cullide-hostile-")
    os.makedirs(d, exist_ok=True)
    cases = mesh_cases(d) + scene_cases(d) + positions_cases(d) + trace_cases(d, cullide) + spec_cases(d) + option_cases(d) + \
        output_cases(d) + csv_cases(d) + audit_cases(d)
    failed = 0
    for case in cases:
        if args.k and args.k not in case.name:
            continue
        problem = run_case(cullide, d, case)
        failed += problem is not None
        print("%s  %s%s" % ("FAIL" if problem else "ok  ", case.name, ": " + problem if problem else ""))
    if not args.k or "killed" in args.k:
        name, problem = killed_record_case(d, cullide)
        failed += problem is not None
        print("%s  %s%s" % ("FAIL" if problem else "ok  ", name, ": " + problem if problem else ""))
    for name, argv in python_cases(d):
        if args.k and args.k not in name:
            continue
        p = subprocess.run(argv, cwd=d, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=60)
        failed += p.returncode != 0
        print("%s  %s%s" % ("FAIL" if p.returncode else "ok  ", name, ": " + p.stdout.decode().strip() if p.returncode else ""))
    print("%d case(s) failed" % failed if failed else "every case holds")
    if not args.keep:
        shutil.rmtree(d, ignore_errors=True)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
