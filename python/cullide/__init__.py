"""cullide: image-space collision and self-intersection culling (Cullide) from Python.

numpy in, numpy out. The compiled part is ``cullide._cullide``; this package gives it keyword
defaults, docstrings and the study's table. docs/python.md has an example.

Bad input (wrong shapes or dtypes, NaN, indices out of range, unknown option values, unreadable
files) raises ValueError naming the problem.
"""

import os as _os

from . import _cullide

__version__ = _cullide.version()

Scene = _cullide.Scene
PruneResult = _cullide.PruneResult
CommandList = _cullide.CommandList
CpuBackend = _cullide.CpuBackend


def _find_resources():
    """The folder holding data/ and tools/: $CULLIDE_RESOURCE_DIR, else share/ inside the package
    (pip), else the source tree for the build tree's package, else share/cullide relative to the
    package installed by cmake --install."""
    if _os.environ.get("CULLIDE_RESOURCE_DIR"):
        return _os.environ["CULLIDE_RESOURCE_DIR"]
    here = _os.path.dirname(_os.path.abspath(__file__))
    if _os.path.isdir(_os.path.join(here, "share", "data")):  # installed by pip (setup.py)
        return _os.path.join(here, "share")
    try:
        from . import _build_tree

        return _build_tree.RESOURCE_DIR
    except ImportError:
        pass
    try:
        from . import _install_paths

        return _os.path.normpath(_os.path.join(here, _install_paths.RESOURCE_DIR_RELATIVE))
    except ImportError:
        return None


_resources = _find_resources()
if _resources:
    _cullide.set_resource_dir(_resources)


def data_dir():
    """The bundled data folder (meshes/cow.off, meshes/bunny.off, scenes/...)."""
    return _os.path.join(_cullide.resource_dir(), "data")


def load_mesh(path):
    """Load a mesh file (.off, .obj, .ply, .stl).

    Returns (V, F): V float32 (n, 3) positions, F uint32 (m, 3) vertex indices.
    Raises ValueError naming the file and the problem when it cannot be read or is invalid.
    """
    return _cullide.load_mesh(_os.fspath(path))


def load_scene(path):
    """Load a scene file (.json) or a mesh file (one object) as a Scene.

    Raises ValueError naming the file and the problem.
    """
    return _cullide.load_scene(_os.fspath(path))


def prune(scene, method="modified", resolution=500, depth="d24", directions="axes", hierarchy="connectivity",
          leaf_size=16, backend="cpu", threads=0, frame=0, branching=4, seed=1, views="fit", exact_switch="never"):
    """Run Cullide on one frame of a scene and return a PruneResult.

    The options are the ones of ``cullide prune`` with the same meaning and the same values
    (method: original | modified | reliable; resolution: N or 'WxH'; depth: 'd24', '16', 'float', ...;
    directions: 'axes', N or a list 'x,-y,z'; hierarchy: connectivity | random; backend: cpu | gl;
    threads: 0 for all cores; views: fit | clustered; exact_switch: never | auto | N,
    docs/cullide.md#switch-to-exact). The result equals ``cullide prune SCENE --frame F --json``'s PCS bit
    for bit. ``scene`` is a Scene, or (V, F), or an object with .vertices and .faces.

    Result: ``.pcs`` (k, 2) uint32 [object, triangle]; ``.passes`` dict of numpy columns per
    reducePCS call; ``.face_mask(object)`` bool per face; ``.total_seconds``.
    Raises ValueError on a bad option value, a bad mesh or a frame the scene does not have.
    """
    return _cullide.prune(_as_scene(scene), method=method, resolution=resolution, depth=depth,
                          directions=directions, hierarchy=hierarchy, leaf_size=leaf_size, branching=branching,
                          seed=seed, backend=backend, threads=threads, frame=frame, views=views,
                          exact_switch=str(exact_switch))


def oracle(scene, frame=0):
    """Every intersecting pair of triangles of one frame, exactly (cullide's oracle).

    Returns (p, 5) uint32 rows [objA, triA, objB, triB, class], class 0 = crossing (one passes
    through the other), 1 = touching (they meet only on a boundary, or coplanar); sorted, each
    unordered pair once, (objA, triA) < (objB, triB).
    """
    return _cullide.oracle(_as_scene(scene), frame=frame)


CAUSES = ("depth_rounding", "sampling", "edge_on", "untested", "unexplained")


def check(result, pairs):
    """False prunes of a PruneResult against the oracle's pairs, by class and by cause.

    ``pairs`` is what oracle() returned for the same scene and frame. Returns a dict:
      - false_prunes {'crossing', 'touching'}: colliding triangles missing from the PCS, each
        counted once, as crossing when it is in some crossing pair (measures.h's rules);
      - missed_pairs, missed_self_pairs (by class), false_positives, efficiency, pcs_triangles,
        colliding_triangles, colliding_in_pcs;
      - causes / cause_pairs {cause: count} for false-pruned triangles / missed pairs, causes as in
        docs/studies.md: depth_rounding, sampling, edge_on, untested, unexplained;
      - missed: (q, 8) uint32 [objA, triA, objB, triB, class, cause index into CAUSES, call, direction];
      - same_pcs: the causes come from a second, instrumented run of Cullide with the result's
        options on a new backend of the same kind; True when it gave the same PCS (always for
        the CPU reference, which is deterministic).
    """
    return _cullide.check(result, pairs)


def _as_list(value, name):
    if isinstance(value, (str, int)):
        return [str(value)] if name != "leaf_sizes" and name != "threads" else [int(value)]
    try:
        values = list(value)
    except TypeError:
        raise ValueError("argument %s: give a value or a list of values" % name) from None
    if name in ("leaf_sizes", "threads"):
        for v in values:
            if isinstance(v, bool) or not isinstance(v, int):
                raise ValueError("argument %s: %r is not an integer" % (name, v))
        return values
    return [str(v) for v in values]


def study(scenes, methods="modified", resolutions=500, depths="24", directions="axes", hierarchies="connectivity",
          leaf_sizes=16, backends="cpu", threads=0, repeats=3, oracle=True, out="study.csv", views="fit",
          exact_switches="never", near_distance=0.0, tolerance=1e-5):
    """Run a precision study, as ``cullide study`` (docs/studies.md), and return its rows.

    Each argument takes one value or a list (the study's axes: every combination runs); scenes are
    files or the generated names of the command (e.g. 'bunny:5000', 'cows:2000', 'twist:5000',
    'cloth:10000', 'nbody:10000'). With oracle=True each run is measured against the exact oracle
    and its false prunes are attributed to causes; near_distance > 0 also counts near contacts
    within that fraction of the scene's diagonal (as ``--near-distance``). Methods include 'exact'
    (the oracle alone) and the peers 'fcl', 'embree', 'bullet', 'cgal', whose pairs are judged
    against the oracle with ``tolerance`` (a fraction of the diagonal, as ``--tolerance``). Writes ``out`` (.csv, or .jsonl) exactly as the command does, through
    the same study library.

    Returns the rows as a pandas DataFrame when pandas is installed, else a dict of numpy columns
    (the CSV's columns, in order).
    """
    import json

    import numpy as np

    records = _cullide.study(
        _as_list(scenes, "scenes"), _as_list(methods, "methods"), _as_list(resolutions, "resolutions"),
        _as_list(depths, "depths"), _as_list(directions, "directions"), _as_list(hierarchies, "hierarchies"),
        _as_list(leaf_sizes, "leaf_sizes"), _as_list(backends, "backends"), _as_list(threads, "threads"),
        int(repeats), bool(oracle), _os.fspath(out), _as_list(views, "views"),
        _as_list(exact_switches, "exact_switches"), float(near_distance), float(tolerance))
    rows = [json.loads(r) for r in records]
    columns = {}
    for name in _cullide.study_columns():
        values = [r.get(name) for r in rows]
        present = [v for v in values if v is not None]
        if present and all(isinstance(v, bool) for v in present):
            columns[name] = np.array(values, dtype=object if len(present) < len(values) else bool)
        elif present and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in present):
            columns[name] = np.array([np.nan if v is None else v for v in values], dtype=float)
        else:
            columns[name] = np.array(["" if v is None else str(v) for v in values], dtype=object)
    try:
        import pandas

        return pandas.DataFrame(columns)
    except ImportError:
        return columns


def _as_scene(scene):
    """A Scene from a Scene, a (V, F) pair or an object with .vertices and .faces."""
    if isinstance(scene, Scene):
        return scene
    s = Scene()
    if isinstance(scene, tuple) and len(scene) == 2:
        s.add("mesh", scene[0], scene[1])
    elif hasattr(scene, "vertices") and hasattr(scene, "faces"):
        s.add("mesh", scene)
    else:
        raise ValueError("scene: give a Scene, a (vertices, faces) pair or an object with .vertices and .faces")
    return s


__all__ = ["Scene", "PruneResult", "CommandList", "CpuBackend", "load_mesh", "load_scene", "prune", "oracle",
           "check", "study", "data_dir", "CAUSES", "__version__"]
