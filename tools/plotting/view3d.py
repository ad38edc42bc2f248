"""The 3D view of one frame in `cullide report`'s page: the frame's triangles (light grey), the
oracle's intersecting pairs, and a method's missed and spurious pairs (from `cullide audit --json`),
drawn by three.js in the page itself. three.js comes from npm (tools/report3d: package.json pins its
version, tools/setup.sh runs `npm ci`); its modules are inlined as data: URLs behind an import map,
so that the page fetches nothing when it is viewed.

Inputs: the frame (`--view FILE`, written by `cullide report --view-scene`: the world mesh and the
oracle's pairs) and, optionally, an audit (`--view-audit FILE`). Both are checked; a problem is
InputError naming the file."""
import base64
import html
import json
import os
import sys
from array import array

from .load import InputError, read_json

HERE = os.path.dirname(os.path.abspath(__file__))
REPORT3D = os.path.join(os.path.dirname(HERE), "report3d")
# The most triangles the view takes (the C++ side refuses a larger frame first): the page carries
# them as base64, about 24 bytes a triangle plus its vertices.
MAX_TRIANGLES = 300_000
# Per-triangle state, as view.js colours it; a triangle in several pairs shows the later one.
OTHER, ORACLE, MISSED, SPURIOUS = 0, 1, 2, 3

CSS = """
.view3d { margin: 1em 0 2em; }
.view3d canvas { width: 100%; height: 34em; border: 1px solid #ddd; display: block; touch-action: none; }
.view3d .key span.swatch { display: inline-block; width: 0.9em; height: 0.9em; margin: 0 0.3em 0 1em;
  vertical-align: -0.1em; }
"""


def three_modules():
    """{import specifier: module text} of three.js as pinned in tools/report3d. The build imports
    its core from a second file ('./three.core.min.js'), which a data: URL cannot resolve: the
    import is renamed to the specifier 'three/core', which the import map gives."""
    build = os.path.join(REPORT3D, "node_modules", "three", "build")
    controls = os.path.join(REPORT3D, "node_modules", "three", "examples", "jsm", "controls", "OrbitControls.js")
    paths = {"three": os.path.join(build, "three.module.min.js"),
             "three/core": os.path.join(build, "three.core.min.js"),
             "three/addons/controls/OrbitControls.js": controls}
    missing = [p for p in paths.values() if not os.path.isfile(p)]
    if missing:
        raise InputError(missing[0], "three.js is not installed: run tools/setup.sh (npm ci in tools/report3d)")
    modules = {}
    for name, path in paths.items():
        with open(path, encoding="utf-8") as f:
            modules[name] = f.read()
    core_import = '"./three.core.min.js"'
    if core_import not in modules["three"]:
        raise InputError(paths["three"], f"does not import {core_import}: not the three.js build tools/report3d pins")
    modules["three"] = modules["three"].replace(core_import, '"three/core"')
    return modules


def _pair(path, where, p, counts):
    """[object, triangle, object, triangle] of a JSON pair, checked against the frame's objects."""
    if isinstance(p, dict):
        p = p.get("pair")
    if not (isinstance(p, list) and len(p) >= 4 and all(isinstance(x, int) and not isinstance(x, bool) and x >= 0
                                                         for x in p[:4])):
        raise InputError(path, f"{where}: not a pair [object, triangle, object, triangle]")
    for o, t in ((p[0], p[1]), (p[2], p[3])):
        if o >= len(counts) or t >= counts[o]:
            raise InputError(path, f"{where}: names triangle {t} of object {o}, which the frame does not have")
    return p[:4]


def read_view(path):
    """The frame the C++ side wrote: positions, triangles (indices into positions), objects'
    triangle counts, the oracle's pairs."""
    j = read_json(path)
    try:
        positions, triangles, objects = j["positions"], j["triangles"], j["objects"]
        counts = [int(o["triangles"]) for o in objects]
        pairs = j["pairs"]
    except (KeyError, TypeError, ValueError):
        raise InputError(path, "not a 3D view frame of `cullide report --view-scene`") from None
    if len(triangles) != 3 * sum(counts) or len(positions) % 3:
        raise InputError(path, "its triangle counts and index list disagree")
    if sum(counts) > MAX_TRIANGLES:
        raise InputError(path, f"{sum(counts):,} triangles, over the 3D view's limit of {MAX_TRIANGLES:,}")
    if any(not isinstance(i, int) or i < 0 or i >= len(positions) // 3 for i in triangles):
        raise InputError(path, "a triangle names a vertex the frame does not have")
    j["counts"] = counts
    j["pairs"] = [_pair(path, f"pairs[{k}]", p, counts) + [p[4] if len(p) > 4 else "crossing"]
                  for k, p in enumerate(pairs)]
    return j


def read_audit(path, frame, counts):
    """(missed, spurious) pairs of `frame` in an audit (`cullide audit --json`: per frame an object
    with "frame", "missed" and "spurious"; as a list, or under "frames")."""
    j = read_json(path)
    frames = j.get("frames") if isinstance(j, dict) else j
    if isinstance(j, dict) and "missed" in j:
        frames = [j]
    if not isinstance(frames, list) or not all(isinstance(f, dict) for f in frames):
        raise InputError(path, "not an audit (`cullide audit --json`): no list of frames")
    chosen = [f for f in frames if f.get("frame", frame if len(frames) == 1 else None) == frame]
    if not chosen:
        raise InputError(path, f"the audit has no frame {frame}")
    f = chosen[0]
    lists = []
    for key in ("missed", "spurious"):
        items = f.get(key, [])
        if not isinstance(items, list):
            raise InputError(path, f"frame {frame}: {key} is not a list")
        lists.append([_pair(path, f"frame {frame}: {key}[{k}]", p, counts) for k, p in enumerate(items)])
    return lists


def _b64(typecode, values):
    a = array(typecode, values)
    if a.itemsize != 4 and typecode in "fI":
        raise InputError("report", f"this Python's {typecode!r} arrays are not 4 bytes")
    if sys.byteorder == "big":  # the page's typed arrays are little-endian on every browser host
        a.byteswap()
    return base64.b64encode(a.tobytes()).decode("ascii")


def triangle_states(view, missed, spurious):
    first = [0]
    for c in view["counts"]:
        first.append(first[-1] + c)
    state = bytearray(first[-1])
    for kind, pairs in ((ORACLE, view["pairs"]), (SPURIOUS, spurious), (MISSED, missed)):
        for p in pairs:
            state[first[p[0]] + p[1]] = kind
            state[first[p[2]] + p[3]] = kind
    return state


def _script_json(value):
    """JSON safe inside a <script> element: no '</script>' can end it early."""
    return json.dumps(value, separators=(",", ":")).replace("<", "\\u003c")


def _data_url(text):
    return "data:text/javascript;base64," + base64.b64encode(text.encode("utf-8")).decode("ascii")


def view_section(view_path, audit_path=None, method=None):
    """The HTML of the 3D view (its own <style>, the import map, the data and the module)."""
    view = read_view(view_path)
    missed, spurious = read_audit(audit_path, view.get("frame", 0), view["counts"]) if audit_path else ([], [])
    modules = three_modules()
    with open(os.path.join(REPORT3D, "view.js"), encoding="utf-8") as f:
        code = f.read()
    if "</script" in code.lower():
        raise InputError(os.path.join(REPORT3D, "view.js"), "holds '</script', which would end its element early")
    state = triangle_states(view, missed, spurious)
    data = {"positions": _b64("f", view["positions"]), "triangles": _b64("I", view["triangles"]),
            "state": base64.b64encode(bytes(state)).decode("ascii")}
    importmap = {"imports": {name: _data_url(text) for name, text in modules.items()}}
    crossing = sum(1 for p in view["pairs"] if p[4] == "crossing")
    esc = html.escape
    who = esc(method) if method else "the audited list"
    audit_note = "no audit given (--view-audit): the oracle's pairs only"
    if audit_path:
        audit_note = (f"{who}: {len(missed):,} missed, {len(spurious):,} spurious "
                      f"(audit {esc(os.path.basename(audit_path))})")
    key = "".join(f'<span class="swatch" style="background:{c}"></span>{esc(t)}' for c, t in (
        ("#c8c8c8", "other triangles"), ("#f0a020", "oracle's pairs"), ("#e0201a", "missed"),
        ("#1f6fe0", "spurious")))
    scene = str(view.get("scene", ""))
    return (f"<style>{CSS}</style>\n"
            f'<p class="note">{esc(scene)}, frame {int(view.get("frame", 0))}: {sum(view["counts"]):,} triangles in '
            f'{len(view["counts"])} object(s); the oracle finds {len(view["pairs"]):,} intersecting pairs '
            f"({crossing:,} crossing); {audit_note}. Drag to rotate, wheel to zoom, right-drag to pan.</p>\n"
            f'<div class="view3d" id="view3d" data-source="view3d-data" data-view-state="loading" '
            f'data-scene="{esc(scene)}" data-oracle-pairs="{len(view["pairs"])}" data-missed="{len(missed)}" '
            f'data-spurious="{len(spurious)}">\n<canvas width="960" height="540"></canvas>\n'
            f'<p class="key">{key} <label><input type="checkbox" name="others" checked="checked" /> show other '
            'triangles</label> <label><input type="checkbox" name="dots" checked="checked" /> dots on pairs</label>'
            '</p>\n<p class="view3d-status note"></p>\n</div>\n'
            f'<script type="application/json" id="view3d-data">{_script_json(data)}</script>\n'
            f'<script type="importmap">{_script_json(importmap)}</script>\n'
            f'<script type="module">{code}</script>\n')
