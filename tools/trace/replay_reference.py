#!/usr/bin/python3
"""Read a cullide trace (docs/trace-format.md) and write its reference answers as a results file.

    replay_reference.py TRACE -o RESULTS.json [--quiet]

A complete, independent reader of trace format version 1 (Python 3 and numpy only, no cullide
import), and the template for replaying a trace on a new backend: keep read_trace, lists and
decode_commands, and replace execute() by your device's execution of the commands. It validates
everything it reads; on a malformed trace it prints "TRACE: problem" and exits 2.

Memory: the binary section is memory-mapped and every array is a numpy view of it, so the
geometry is never copied into Python objects; validation makes temporaries of one list at a time.
"""
import argparse
import json
import os
import sys

import numpy as np

MAGIC = b"CULTRACE"
VERSION = 1
# Each blob's type and row width (docs/trace-format.md, "The header").
BLOBS = {"positions": ("<f4", 3), "triangles": ("<u4", 3), "commands": ("<u4", 4), "queries": ("<u8", 3)}
CLEAR, FUNC, MASK, BEGIN, END, DRAW = range(6)
# Per op: the largest allowed value of word a (None: any), and whether words b and c are used.
OPS = {CLEAR: (None, True, False), FUNC: (7, False, False), MASK: (1, False, False),
       BEGIN: (1, False, False), END: (0, False, False), DRAW: (None, True, False)}
QUERY_KINDS = ("samples", "any")  # begin_query's a: 0 samples passed (a count), 1 any samples passed


class TraceError(Exception):
    """A malformed trace; main() reports it as 'TRACE: message' and exits 2."""


def require(ok, message):
    if not ok:
        raise TraceError(message)


def is_int(v):
    return isinstance(v, int) and not isinstance(v, bool)


def is_num(v):
    return is_int(v) or (isinstance(v, float) and np.isfinite(v))


def read_trace(path):
    """The header (a dict) and the binary section (a uint8 array mapped from the file)."""
    size = os.path.getsize(path)
    with open(path, "rb") as f:
        pre = f.read(16)
        require(len(pre) == 16, f"truncated: {size} bytes, shorter than the 16-byte magic and header length")
        require(pre[:8] == MAGIC, f"not a cullide trace (magic {pre[:8]!r}, expected {MAGIC!r})")
        j = int.from_bytes(pre[8:], "little")
        require(16 + j <= size, f"truncated: header length {j} runs past the end of the file ({size} bytes)")
        require((16 + j) % 8 == 0, f"header length {j}: 16 + {j} is not a multiple of 8")
        raw = f.read(j)
    try:
        header = json.loads(raw.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as e:
        raise TraceError(f"the JSON header does not parse: {e}")
    require(isinstance(header, dict), "the JSON header is not an object")
    require(header.get("format") == "cullide-trace", f"format is {header.get('format')!r}, not 'cullide-trace'")
    v = header.get("version")
    require(is_int(v) and v >= 1, f"version {v!r} is not a format version (1, 2, ...)")
    require(v <= VERSION, f"version {v} is newer than this reader reads ({VERSION})")
    n = header.get("binary_bytes")
    require(is_int(n) and n >= 0, f"binary_bytes {n!r} is not a byte count")
    have = size - 16 - j
    require(have >= n, f"truncated: the binary section has {have} bytes, binary_bytes says {n}")
    require(have == n, f"{have - n} bytes after the binary section's {n} (binary_bytes)")
    binary = np.memmap(path, dtype=np.uint8, mode="r", offset=16 + j, shape=(n,)) if n else np.zeros(0, np.uint8)
    return header, binary


def blob(binary, ref, name, where):
    """The [n, k] array `ref` names, a view of the binary section, after checking the reference."""
    dtype, width = BLOBS[name]
    what = f"{where}: {name}"
    require(isinstance(ref, dict), f"{what} is not a blob reference")
    off, dt, shape = ref.get("offset"), ref.get("dtype"), ref.get("shape")
    require(dt in ("<f4", "<u4", "<u8"), f"{what} has dtype {dt!r} (not <f4, <u4 or <u8)")
    require(dt == dtype, f"{what} has dtype {dt}, expected {dtype}")
    require(isinstance(shape, list) and len(shape) == 2 and all(is_int(s) and s >= 0 for s in shape),
            f"{what} has shape {shape!r}, not [rows, columns]")
    require(shape[1] == width, f"{what} has {shape[1]} columns, expected {width}")
    require(is_int(off) and off >= 0 and off % 8 == 0, f"{what} has offset {off!r}, not a multiple of 8")
    nbytes = shape[0] * width * np.dtype(dt).itemsize
    require(off + nbytes <= binary.size,
            f"{what} [{off}, {off + nbytes}) lies outside the binary section ({binary.size} bytes)")
    if shape[0] == 0:
        return np.zeros((0, width), dt)
    return np.frombuffer(binary, dtype=dt, count=shape[0] * width, offset=off).reshape(shape[0], width)


def check_view(view, where):
    require(isinstance(view, dict), f"{where}: view is not an object")
    frame = []
    for k in ("right", "up", "dir"):
        vec = view.get(k)
        require(isinstance(vec, list) and len(vec) == 3 and all(map(is_num, vec)), f"{where}: view {k} {vec!r}")
        frame.append(np.array(vec, dtype=np.float64))
    r, u, d = frame
    tol = 1e-9  # as OrthoView::validate
    require(all(abs(np.linalg.norm(a) - 1) < tol for a in frame) and
            abs(r @ u) < tol and abs(r @ d) < tol and abs(u @ d) < tol,
            f"{where}: the view frame (right, up, dir) is not orthonormal")
    require(np.cross(r, u) @ d > 0, f"{where}: the view frame (right, up, dir) is left-handed")
    box = view.get("box")
    require(isinstance(box, list) and len(box) == 6 and all(map(is_num, box)), f"{where}: view box {box!r}")
    require(box[0] < box[1] and box[2] < box[3] and box[4] < box[5],
            f"{where}: the view box {box} is empty (need xmin < xmax, ymin < ymax, znear < zfar)")
    vp = view.get("viewport")
    require(isinstance(vp, list) and len(vp) == 2 and all(is_int(s) and s >= 1 for s in vp),
            f"{where}: viewport {vp!r} is not [width, height]")
    tile = view.get("tile")
    if tile is not None:
        pairs = [tile.get(k) if isinstance(tile, dict) else None for k in ("origin", "grid")]
        require(all(isinstance(q, list) and len(q) == 2 and all(is_int(s) and s >= 0 for s in q) for q in pairs),
                f"{where}: tile {tile!r} is not {{origin: [x, y], grid: [width, height]}}")
        (ox, oy), (gw, gh) = pairs
        require(ox + vp[0] <= gw and oy + vp[1] <= gh, f"{where}: the tile does not lie inside its grid {gw}x{gh}")
    depth = view.get("depth")
    ok = depth == "D32F" or (isinstance(depth, str) and depth[:1] == "D" and depth[1:].isdigit() and
                             8 <= int(depth[1:]) <= 32 and depth[1:] == str(int(depth[1:])))
    require(ok, f"{where}: depth format {depth!r} (D8..D32 or D32F)")


def window_coordinates(view, positions):
    """Window coordinates [n, 3] (xw, yw, zw) of positions [n, 3] under a view, in float64.

    The doc's window transform, in OrthoView::toWindow's order of operations (dot products left to
    right, no fused multiply-add): what a backend's projection must reproduce, up to the rounding
    the trace's intervals allow. Origin at the bottom-left corner, y up, depth in [0, 1]."""
    p = positions.astype(np.float64)
    xmin, xmax, ymin, ymax, znear, zfar = map(float, view["box"])
    # A tile of a larger view: the grid's scale, then its origin subtracted (an exact shift).
    tile = view.get("tile", {"origin": [0, 0], "grid": view["viewport"]})
    (width, height), (ox, oy) = tile["grid"], tile["origin"]
    x, y, z = (a[0] * p[:, 0] + a[1] * p[:, 1] + a[2] * p[:, 2] for a in (view["right"], view["up"], view["dir"]))
    return np.stack([(x - xmin) / (xmax - xmin) * width - ox, (y - ymin) / (ymax - ymin) * height - oy,
                     (z - znear) / (zfar - znear)], axis=1)


def decode_commands(cmd):
    """Columns of a [c, 4] command blob: op, a, b, c and the clear depths (float64, meaningful where op == 0)."""
    clear = np.ascontiguousarray(cmd[:, 1:3]).view("<f8")[:, 0]
    return cmd[:, 0], cmd[:, 1], cmd[:, 2], cmd[:, 3], clear


def require_none(mask, message):
    """Fail naming the first row where mask holds: message(row) describes it."""
    bad = np.flatnonzero(mask)
    if bad.size:
        raise TraceError(message(int(bad[0])))


def check_list(cmd, queries, ntri, where):
    """Validate one list's commands against its frame's triangle count and its query rows.

    Returns the query kinds (begin_query's a, in order) and the number of triangles drawn."""
    op, a, b, c, clear = decode_commands(cmd)
    require_none(op > 5, lambda i: f"{where}: command {i} has op {op[i]} (0-5)")
    for o, (amax, use_b, use_c) in OPS.items():
        if amax is not None:
            require_none((op == o) & (a > amax), lambda i: f"{where}: command {i} (op {o}) has a = {a[i]} (0-{amax})")
        unused = ((b != 0) & (not use_b)) | ((c != 0) & (not use_c))
        require_none((op == o) & unused, lambda i: f"{where}: command {i} {cmd[i].tolist()}: an unused word is not 0")
    require_none((op == CLEAR) & ~((clear >= 0) & (clear <= 1)),
                 lambda i: f"{where}: command {i} clears to depth {clear[i]}, not in [0, 1]")
    end = a.astype(np.uint64) + b
    require_none((op == DRAW) & (end > ntri),
                 lambda i: f"{where}: command {i} draws triangles [{a[i]}, {end[i]}), the frame has {ntri}")
    is_q = (op == BEGIN) | (op == END)
    # Queries alternate begin, end, begin, end... and the last one ends in its list.
    expect = np.where(np.cumsum(is_q) % 2 == 1, BEGIN, END)
    require_none(is_q & (op != expect), lambda i: f"{where}: command {i}: "
                 f"{'begin_query while a query is open' if op[i] == BEGIN else 'end_query without an open query'}")
    require(np.count_nonzero(is_q) % 2 == 0, f"{where}: the last query is not ended in its list")
    kinds = a[op == BEGIN]
    require(kinds.size == queries.shape[0],
            f"{where}: {kinds.size} begin_query commands but {queries.shape[0]} query rows")
    ref, certain, possible = queries[:, 0], queries[:, 1], queries[:, 2]
    require_none((certain > ref) | (ref > possible), lambda i: f"{where}: query {i} has [reference, certain, "
                 f"possible] {queries[i].tolist()}, not certain <= reference <= possible")
    require_none((kinds == 1) & (possible > 1),
                 lambda i: f"{where}: any-samples query {i} has {queries[i].tolist()}, not 0 or 1")
    return kinds, int(b[op == DRAW].sum(dtype=np.uint64))


def lists(header, binary):
    """Yield (index L, frame number, positions, triangles, view, commands, queries) per command list, validated."""
    frames = header.get("frames")
    require(isinstance(frames, list), "frames is not a list")
    index = 0
    for f, frame in enumerate(frames):
        where = f"frame {f}"
        require(isinstance(frame, dict) and is_int(frame.get("frame")), f"{where}: not an object with a frame number")
        pos = blob(binary, frame.get("positions"), "positions", where)
        tri = blob(binary, frame.get("triangles"), "triangles", where)
        require(bool(np.all(np.isfinite(pos))), f"{where}: a position is not finite")
        require(tri.size == 0 or int(tri.max()) < pos.shape[0],
                f"{where}: a triangle index ({int(tri.max()) if tri.size else 0}) is not below the {pos.shape[0]} vertices")
        require(isinstance(frame.get("lists"), list), f"{where}: lists is not a list")
        for entry in frame["lists"]:
            where = f"list {index} (frame {frame['frame']})"
            require(isinstance(entry, dict), f"{where}: not an object")
            check_view(entry.get("view"), where)
            cmd = blob(binary, entry.get("commands"), "commands", where)
            queries = blob(binary, entry.get("queries"), "queries", where)
            yield index, frame["frame"], pos, tri, entry["view"], cmd, queries
            index += 1


def execute(positions, triangles, view, cmd, nqueries):
    """The place where a real backend runs one list and returns its nqueries results (ints).

    A backend would: upload positions and triangles once per frame; (re)create a depth-only target
    of view["viewport"] in view["depth"]; set the projection that reproduces window_coordinates(view, ...);
    then walk op, a, b, c, clear = decode_commands(cmd) in order: 0 clear to clear[i], 1 depth
    function GL_NEVER + a[i], 2 depth mask a[i], 3 begin a query (a[i] == 0: samples passed, 1: any
    samples passed), 4 end it, 5 draw triangles [a[i], a[i] + b[i]); and finally read every query.
    This reference reader has no device: it returns None and main() uses the trace's answers."""
    return None


def main():
    ap = argparse.ArgumentParser(description="Read a cullide trace and write its reference answers as results.")
    ap.add_argument("trace")
    ap.add_argument("-o", "--output", required=True, help="results JSON file to write")
    ap.add_argument("--quiet", action="store_true", help="print no summary")
    args = ap.parse_args()
    try:
        header, binary = read_trace(args.trace)
        results, kinds, draws, formats, viewports, ncmd = [], np.zeros(2, np.int64), 0, {}, set(), 0
        for index, frame, pos, tri, view, cmd, queries in lists(header, binary):
            k, d = check_list(cmd, queries, tri.shape[0], f"list {index} (frame {frame})")
            answers = execute(pos, tri, view, cmd, queries.shape[0])
            results.append(answers if answers is not None else queries[:, 0].tolist())
            kinds += np.bincount(k, minlength=2)[:2]
            draws, ncmd = draws + d, ncmd + cmd.shape[0]
            formats[view["depth"]] = formats.get(view["depth"], 0) + 1
            viewports.add(tuple(view["viewport"]))
        counts = {"frames": len(header["frames"]), "lists": len(results), "commands": ncmd,
                  "queries": int(kinds.sum()), "triangles_drawn": draws}
        summary = header.get("summary")
        require(isinstance(summary, dict), "summary is not an object")
        for key, value in counts.items():
            require(is_int(summary.get(key)) and summary[key] >= 0, f"summary.{key} is {summary.get(key)!r}, not a count")
            require(summary[key] == value,
                    f"summary.{key} is {summary[key]}, but the trace has {value} (the header disagrees with its data)")
        require(counts["frames"] > 0, "frames is empty: a trace records at least one frame")
    except TraceError as e:
        print(f"{args.trace}: {e}", file=sys.stderr)
        return 2
    except (OSError, ValueError) as e:  # unreadable file; a mapping numpy refuses
        print(f"{args.trace}: cannot read: {e}", file=sys.stderr)
        return 2
    if not args.quiet:
        print(f"{args.trace}: cullide-trace version {header['version']}")
        for key, value in counts.items():
            print(f"  {key}: {value}")
        print(f"  queries by kind: {kinds[0]} samples passed, {kinds[1]} any samples passed")
        print("  depth formats (lists): " + ", ".join(f"{k} {v}" for k, v in sorted(formats.items())))
        print("  viewports: " + ", ".join(f"{w}x{h}" for w, h in sorted(viewports)))
        print("  rules: " + json.dumps(header.get("rules"), sort_keys=True))
        print("  provenance: " + json.dumps(header.get("provenance"), sort_keys=True))
    out = {"backend": "reference answers from the trace (tools/trace/replay_reference.py)", "results": results}
    try:
        with open(args.output, "w") as f:
            json.dump(out, f)
            f.write("\n")
    except OSError as e:
        print(f"{args.output}: cannot write: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
