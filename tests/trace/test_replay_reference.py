#!/usr/bin/python3
"""tools/trace/replay_reference.py on synthetic traces (tests/trace/make_synthetic_trace.py).

The valid trace must be read, summarized and answered with its reference column; each corruption
must be refused with exit 2 and a message naming the file and the problem. Exit 0 when all hold,
1 otherwise, 77 (skipped) without numpy.
"""
import json
import os
import subprocess
import sys
import tempfile

try:
    import numpy as np
except ImportError:
    print("numpy missing: skipped")
    sys.exit(77)

HERE = os.path.dirname(os.path.abspath(__file__))
READER = os.path.join(HERE, "..", "..", "tools", "trace", "replay_reference.py")
MAKER = os.path.join(HERE, "make_synthetic_trace.py")
failures = []


def check(ok, what):
    if not ok:
        failures.append(what)
        print("FAIL:", what)


def run(*args):
    return subprocess.run([sys.executable, *args], capture_output=True, text=True)


def main():
    with tempfile.TemporaryDirectory(prefix="cullide-trace-") as tmp:  # gone when the checks end
        return checks(tmp)


def checks(tmp):
    valid = os.path.join(tmp, "valid.trace")
    results = os.path.join(tmp, "valid.json")
    subprocess.run([sys.executable, MAKER, valid], check=True)

    # The valid trace: exit 0, the reference column per list, a summary naming every part.
    r = run(READER, valid, "-o", results)
    print(r.stdout, end="")
    check(r.returncode == 0 and r.stderr == "", f"valid trace: exit {r.returncode}, stderr {r.stderr!r}")
    if r.returncode == 0:
        with open(results) as f:
            out = json.load(f)
        check(out["results"] == [[1234, 1], [40], [0, 0]], f"valid trace: results {out['results']}")
        check(out["backend"].startswith("reference answers"), "valid trace: backend string")
    for part in ("frames: 2", "lists: 3", "commands: 28", "queries: 5", "triangles_drawn: 52",
                 "3 samples passed, 2 any samples passed", "D16 1, D24 1, D32F 1", "64x48, 100x80, 500x500",
                 "subpixel_bits", "git_commit"):
        check(part in r.stdout, f"valid trace: summary lacks {part!r}")
    r = run(READER, valid, "-o", results, "--quiet")
    check(r.returncode == 0 and r.stdout == "", "valid trace with --quiet: exit 0, nothing printed")

    # The same bytes twice (the generator is deterministic, as recordings are).
    again = os.path.join(tmp, "again.trace")
    subprocess.run([sys.executable, MAKER, again], check=True)
    with open(valid, "rb") as a, open(again, "rb") as b:
        check(a.read() == b.read(), "generator: two runs differ")

    # Each corruption: exit 2, "FILE: ...expected words...", no traceback.
    listing = run(MAKER, "--list").stdout.splitlines()
    for line in listing:
        name, expect = line.split("\t")
        path = os.path.join(tmp, name + ".trace")
        subprocess.run([sys.executable, MAKER, path, "--corrupt", name], check=True)
        r = run(READER, path, "-o", os.path.join(tmp, name + ".json"))
        msg = r.stderr.strip()
        print(f"{name:20} exit {r.returncode}: {msg}")
        check(r.returncode == 2 and msg.startswith(path + ": ") and expect in msg and "Traceback" not in msg,
              f"{name}: exit {r.returncode}, message {msg!r} (expected exit 2 and {expect!r})")
        check(not os.path.exists(os.path.join(tmp, name + ".json")), f"{name}: a results file was written")
    check(len(listing) >= 20, "generator lists too few corruptions")

    # A missing file: exit 2 naming it.
    missing = os.path.join(tmp, "missing.trace")
    r = run(READER, missing, "-o", results)
    check(r.returncode == 2 and r.stderr.startswith(missing + ": "), f"missing file: {r.returncode} {r.stderr!r}")

    # window_coordinates: the doc's transform, checked on a view whose numbers are exact in binary.
    sys.path.insert(0, os.path.dirname(READER))
    from replay_reference import window_coordinates
    view = {"right": [0, 1, 0], "up": [0, 0, 1], "dir": [1, 0, 0], "box": [-1, 3, 0, 2, 10, 14],
            "viewport": [8, 4]}
    w = window_coordinates(view, np.array([[11, 1, 0.5], [14, -1, 2]], "<f4"))
    check(w.dtype == np.float64 and np.array_equal(w, [[4, 1, 0.25], [0, 4, 1]]), f"window_coordinates {w.tolist()}")
    # A tile of that view: the grid's scale, the origin subtracted.
    tile = dict(view, viewport=[4, 2], tile={"origin": [2, 1], "grid": [8, 4]})
    w = window_coordinates(tile, np.array([[11, 1, 0.5], [14, -1, 2]], "<f4"))
    check(np.array_equal(w, [[2, 0, 0.25], [-2, 3, 1]]), f"window_coordinates of a tile {w.tolist()}")

    print(f"{len(failures)} failures" if failures else "all checks hold")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
