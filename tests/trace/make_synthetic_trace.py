#!/usr/bin/python3
"""Write a small synthetic cullide trace (docs/trace-format.md), valid or with one chosen corruption.

    make_synthetic_trace.py OUT.trace [--corrupt KIND]     (--list: the corruptions)

For testing trace readers (tools/trace/replay_reference.py, `cullide trace compare`) without the
C++ recorder. Two frames (the second reuses the first's triangle blob), three command lists with
every op, both query kinds and three depth formats; the query rows are made up but satisfy
certain <= reference <= possible. Deterministic: the same arguments give the same bytes.
"""
import argparse
import json
import sys

import numpy as np

CLEAR, FUNC, MASK, BEGIN, END, DRAW = range(6)


def clear(depth):
    lo, hi = np.array([depth], "<f8").view("<u4")
    return [CLEAR, int(lo), int(hi), 0]


def view(depth, viewport, box=(-2.0, 2.0, -2.0, 2.0, -3.0, 3.0)):
    # The frame OrthoView::looking((1, 1, 1)) builds: right = normalize(x cross dir), up = dir cross right.
    d = np.array([1.0, 1.0, 1.0]) / np.sqrt(3.0)
    r = np.cross([1.0, 0.0, 0.0], d)
    r /= np.linalg.norm(r)
    return {"right": r.tolist(), "up": np.cross(d, r).tolist(), "dir": d.tolist(), "box": list(box),
            "viewport": list(viewport), "depth": depth}


def model():
    """The valid trace as Python data: frames of arrays (blobs not laid out yet)."""
    rng = np.random.default_rng(13)
    pos0 = rng.uniform(-1, 1, (8, 3)).astype("<f4")
    tri = rng.integers(0, 8, (12, 3)).astype("<u4")
    pos1 = (pos0 + np.float32(0.25)).astype("<f4")
    u8 = lambda rows: np.array(rows, "<u8").reshape(-1, 3)
    list0 = {"view": view("D24", [500, 500]),
             "commands": [clear(1.0), [FUNC, 1, 0, 0], [MASK, 1, 0, 0], [DRAW, 0, 4, 0], [MASK, 0, 0, 0],
                          [FUNC, 3, 0, 0], [BEGIN, 0, 0, 0], [DRAW, 4, 4, 0], [END, 0, 0, 0],
                          [BEGIN, 1, 0, 0], [DRAW, 8, 4, 0], [END, 0, 0, 0]],
             "queries": u8([[1234, 1200, 1250], [1, 1, 1]])}
    list1 = {"view": view("D16", [64, 48]),
             "commands": [clear(1.0), [MASK, 1, 0, 0], [FUNC, 1, 0, 0], [DRAW, 0, 12, 0],
                          [BEGIN, 0, 0, 0], [DRAW, 0, 6, 0], [END, 0, 0, 0]],
             "queries": u8([[40, 35, 47]])}
    list2 = {"view": view("D32F", [100, 80]),
             "commands": [clear(0.5), [FUNC, 6, 0, 0], [DRAW, 2, 10, 0], [BEGIN, 1, 0, 0], [DRAW, 0, 0, 0],
                          [END, 0, 0, 0], [BEGIN, 0, 0, 0], [DRAW, 0, 12, 0], [END, 0, 0, 0]],
             "queries": u8([[0, 0, 1], [0, 0, 3]])}
    for lst in (list0, list1, list2):
        lst["commands"] = np.array(lst["commands"], "<u4")
    return [{"frame": 0, "positions": pos0, "triangles": tri, "lists": [list0, list1]},
            {"frame": 7, "positions": pos1, "triangles": tri, "lists": [list2]}]


def layout(frames):
    """The header (blob references filled in) and the binary section; identical arrays are stored once."""
    chunks, offsets, size = [], {}, 0

    def ref(a):
        nonlocal size
        key = (a.dtype.str, a.shape, a.tobytes())
        if key not in offsets:
            offsets[key] = size
            data = a.tobytes() + b"\0" * (-a.nbytes % 8)
            chunks.append(data)
            size += len(data)
        return {"offset": offsets[key], "dtype": a.dtype.str, "shape": list(a.shape)}

    out = []
    for f in frames:
        lists = [{"view": l["view"], "commands": ref(l["commands"]), "queries": ref(l["queries"])}
                 for l in f["lists"]]
        out.append({"frame": f["frame"], "positions": ref(f["positions"]), "triangles": ref(f["triangles"]),
                    "lists": lists})
    all_lists = [l for f in frames for l in f["lists"]]
    header = {
        "format": "cullide-trace", "version": 1, "cullide_version": "0.1.0",
        "provenance": {"cullide_version": "0.1.0", "git_commit": "synthetic", "compiler": "none",
                       "cpu_model": "none", "threads": 1},
        "rules": {"subpixel_bits": 8, "fill_rule": "bottom-left", "pixel_centers": "(i + 0.5, j + 0.5)",
                  "depth_encoding": "unorm ties up; float nearest", "depth_plane": "unsnapped vertices, double",
                  "other_subpixel_bits": 4, "depth_margin_lsb": 1, "depth_float_ulps": 4},
        "workload": {"scene": "synthetic (tests/trace/make_synthetic_trace.py)"},
        "summary": {"frames": len(frames), "lists": len(all_lists),
                    "commands": sum(len(l["commands"]) for l in all_lists),
                    "queries": sum(len(l["queries"]) for l in all_lists),
                    "triangles_drawn": int(sum(l["commands"][l["commands"][:, 0] == DRAW, 2].sum()
                                               for l in all_lists))},
        "binary_bytes": size, "frames": out}
    return header, b"".join(chunks)


def pack(header, binary):
    text = json.dumps(header, indent=1).encode()
    text += b" " * (-(16 + len(text)) % 8)
    return b"CULTRACE" + len(text).to_bytes(8, "little") + text + binary


def set_cmd(f, l, row, words):
    def apply(frames):
        frames[f]["lists"][l]["commands"][row] = words
    return apply


# Corruptions: (stage, change, what the reader's message must contain). Stage "model" edits the
# arrays before layout, "header" the laid-out header, "bytes" the packed file.
CORRUPTIONS = {
    "truncated": ("bytes", lambda b: b[:-13], "truncated"),
    "truncated-header": ("bytes", lambda b: b[:12], "truncated"),
    "trailing-bytes": ("bytes", lambda b: b + b"\0" * 8, "after the binary section"),
    "bad-magic": ("bytes", lambda b: b"CULTRACX" + b[8:], "magic"),
    "bad-json": ("bytes", lambda b: b[:16] + b"[" + b[17:], "does not parse"),
    "bad-format": ("header", lambda h: h.update(format="cullide-trac"), "format"),
    "future-version": ("header", lambda h: h.update(version=2), "version 2 is newer"),
    "binary-bytes": ("header", lambda h: h.update(binary_bytes=h["binary_bytes"] + 8), "truncated"),
    "blob-out-of-range": ("header", lambda h: h["frames"][1]["lists"][0]["queries"].update(
        offset=h["binary_bytes"]), "outside the binary section"),
    "blob-misaligned": ("header", lambda h: h["frames"][0]["positions"].update(offset=4), "multiple of 8"),
    "blob-dtype": ("header", lambda h: h["frames"][0]["triangles"].update(dtype="<i4"), "dtype"),
    "blob-type": ("header", lambda h: h["frames"][1]["positions"].update(dtype="<u4"), "expected <f4"),
    "blob-width": ("header", lambda h: h["frames"][0]["lists"][0]["commands"].update(shape=[6, 8]), "columns"),
    "bad-view": ("header", lambda h: h["frames"][0]["lists"][1]["view"].update(up=[0, 0, 1]), "orthonormal"),
    "bad-depth": ("header", lambda h: h["frames"][0]["lists"][1]["view"].update(depth="D33"), "depth format"),
    "summary": ("header", lambda h: h["summary"].update(triangles_drawn=1), "summary.triangles_drawn is 1"),
    "summary-missing": ("header", lambda h: h.pop("summary"), "summary"),
    "summary-key-missing": ("header", lambda h: h["summary"].pop("queries"), "summary.queries"),
    "frames-emptied": ("header", lambda h: h.update(frames=[]), "summary.frames is 2, but the trace has 0"),
    "no-frames": ("header", lambda h: h.update(frames=[], summary={"frames": 0, "lists": 0, "commands": 0,
                                                                   "queries": 0, "triangles_drawn": 0}),
                  "frames is empty"),
    "bad-op": ("model", set_cmd(0, 0, 4, [6, 0, 0, 0]), "op 6"),
    "unused-word": ("model", set_cmd(0, 1, 3, [DRAW, 0, 12, 1]), "unused word"),
    "bad-func": ("model", set_cmd(0, 0, 1, [FUNC, 8, 0, 0]), "has a = 8 (0-7)"),
    "bad-clear": ("model", set_cmd(1, 0, 0, clear(1.5)), "not in [0, 1]"),
    "draw-out-of-range": ("model", set_cmd(1, 0, 2, [DRAW, 2, 11, 0]), "draws triangles [2, 13)"),
    "index-out-of-range": ("model", lambda fr: fr[0]["triangles"].__setitem__((5, 1), 8), "triangle index"),
    "unbalanced-queries": ("model", set_cmd(0, 1, 6, [DRAW, 0, 0, 0]), "not ended"),
    "nested-queries": ("model", set_cmd(0, 0, 8, [BEGIN, 0, 0, 0]), "while a query is open"),
    "end-without-begin": ("model", set_cmd(0, 0, 6, [DRAW, 0, 0, 0]), "without an open query"),
    "query-rows": ("model", lambda fr: fr[0]["lists"][0].update(queries=fr[0]["lists"][0]["queries"][:1]),
                   "2 begin_query commands but 1 query rows"),
    "interval": ("model", lambda fr: fr[0]["lists"][1]["queries"].__setitem__((0, 0), 48), "certain <= reference"),
    "any-not-binary": ("model", lambda fr: fr[1]["lists"][0]["queries"].__setitem__((0, 2), 2), "not 0 or 1"),
}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", nargs="?")
    ap.add_argument("--corrupt", choices=sorted(CORRUPTIONS), help="write this corruption instead of a valid trace")
    ap.add_argument("--list", action="store_true", help="print each corruption and the message it must give")
    args = ap.parse_args()
    if args.list:
        for name, (_, _, expect) in sorted(CORRUPTIONS.items()):
            print(f"{name}\t{expect}")
        return 0
    if not args.out:
        ap.error("OUT is required")
    stage, change, _ = CORRUPTIONS.get(args.corrupt, (None, None, None))
    frames = model()
    if stage == "model":
        change(frames)
    header, binary = layout(frames)
    if stage == "header":
        change(header)
    data = pack(header, binary)
    if stage == "bytes":
        data = change(data)
    with open(args.out, "wb") as f:
        f.write(data)
    return 0


if __name__ == "__main__":
    sys.exit(main())
