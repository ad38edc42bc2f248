"""Tests of the Python module `cullide` (registered with CTest as Python.Pytest).

Run from a build: PYTHONPATH=build/python CULLIDE_CLI=build/tools/cullide /usr/bin/python3 -m pytest python/tests
One test (at least) per public function; each names the trap it covers.
"""

import csv
import json
import os
import subprocess

import numpy as np
import pytest

import cullide

COW = os.path.join(cullide.data_dir(), "meshes", "cow.off")
SCENE = os.path.join(cullide.data_dir(), "scenes", "two_cows_and_bunny.json")


def box(centre=(0.0, 0.0, 0.0), size=1.0):
    """A closed axis-aligned box: 8 vertices, 12 triangles (outward)."""
    c = np.asarray(centre, dtype=np.float64)
    v = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=np.float64)
    v = (v - 0.5) * size + c
    f = np.array([[0, 2, 1], [1, 2, 3], [4, 5, 6], [5, 7, 6], [0, 1, 4], [1, 5, 4],
                  [2, 6, 3], [3, 6, 7], [0, 4, 2], [2, 4, 6], [1, 3, 5], [3, 7, 5]], dtype=np.int64)
    return v, f


class Mesh:
    """A trimesh-like object: only .vertices and .faces."""

    def __init__(self, v, f):
        self.vertices, self.faces = v, f


def cli(*args, cwd=None):
    exe = os.environ.get("CULLIDE_CLI")
    if not exe:
        pytest.skip("CULLIDE_CLI not set (the ctest registration sets it)")
    return subprocess.run([exe, *args], cwd=cwd, capture_output=True, text=True, check=True)


# Trap: the package must carry the command line's version (0.3.0 from project(VERSION)).
def test_version_and_data_dir():
    assert cullide.__version__ == "0.3.0"
    assert os.path.exists(COW)


# Trap: dtypes and shapes of load_mesh's arrays (float32 (n,3), uint32 (m,3)) and a bad file as ValueError.
def test_load_mesh(tmp_path):
    v, f = cullide.load_mesh(COW)
    assert v.dtype == np.float32 and v.ndim == 2 and v.shape[1] == 3
    assert f.dtype == np.uint32 and f.shape == (5804, 3)
    assert f.max() < len(v)
    bad = tmp_path / "bad.off"
    bad.write_text("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n")
    with pytest.raises(ValueError, match="bad.off"):
        cullide.load_mesh(bad)
    with pytest.raises(ValueError):
        cullide.load_mesh(tmp_path / "missing.off")


# Trap: a scene file's objects and frames, and a mesh file loading as a one-object scene.
def test_load_scene():
    s = cullide.load_scene(SCENE)
    assert s.object_count == len(s.names) >= 2
    assert s.frame_count >= 1
    one = cullide.load_scene(COW)
    assert one.object_count == 1 and one.triangle_count == 5804
    v, f = one.world_mesh(0)
    assert np.array_equal(v, cullide.load_mesh(COW)[0])


# Trap: Scene.add takes arrays of any real/integer dtype, a 4x4 transform, and a trimesh-like object.
def test_scene_add():
    s = cullide.Scene()
    v, f = box()
    assert s.add("a", v, f) == 0
    t = np.eye(4)
    t[:3, 3] = [0.5, 0, 0]
    assert s.add("b", v.astype(np.float32), f.astype(np.uint32), transform=t) == 1
    assert s.add("c", Mesh(v, f)) == 2
    assert s.names == ["a", "b", "c"] and s.triangle_count == 36
    wv, _ = s.world_mesh(1)
    assert np.allclose(wv, v + [0.5, 0, 0])


# Trap: every kind of bad array raises ValueError naming the problem, never a crash.
@pytest.mark.parametrize(
    "vertices,faces,message",
    [
        (np.zeros((4, 2)), np.zeros((1, 3), int), "shape"),
        (np.zeros((4, 3)), np.zeros((1, 4), int), "shape"),
        (np.zeros((4, 3)), np.zeros((3,), int), "shape"),
        (np.zeros((4, 3)), np.zeros((1, 3), float), "integer"),
        (np.zeros((4, 3), dtype=complex), np.zeros((1, 3), int), "real"),
        (np.array([[0, 0, 0], [1, 0, 0], [np.nan, 1, 0]]), np.array([[0, 1, 2]]), "NaN"),
        (np.array([[0, 0, 0], [1, 0, 0], [np.inf, 1, 0]]), np.array([[0, 1, 2]]), "NaN"),
        (np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]]), np.array([[0, 1, 3]]), "index 3"),
        (np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]]), np.array([[0, 1, -1]]), "index -1"),
        (np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]]), np.array([[0, 1, 2**40]], dtype=np.uint64), "index"),
        ("not an array", np.array([[0, 1, 2]]), "vertices"),
    ],
)
def test_bad_arrays_raise_value_error(vertices, faces, message):
    with pytest.raises(ValueError, match=message):
        cullide.Scene().add("m", vertices, faces)
    with pytest.raises(ValueError, match=message):
        cullide.CpuBackend(threads=1).set_geometry(vertices, faces)


# Trap: a transform that is not 4x4 affine, and an object without faces.
def test_bad_transform_and_object():
    v, f = box()
    with pytest.raises(ValueError, match="4"):
        cullide.Scene().add("m", v, f, transform=np.eye(3))
    t = np.eye(4)
    t[3, 0] = 1
    with pytest.raises(ValueError, match="last row"):
        cullide.Scene().add("m", v, f, transform=t)
    with pytest.raises(ValueError, match="vertices and faces"):
        cullide.Scene().add("m", v)


# Trap: a Scene no scene file could be: an empty Scene pruned to an empty result, an empty or
# duplicate name accepted (frames and results name objects), a transform whose world coordinates
# overflow float (Inf reaching the backend) -- all ValueError naming the cause, the scene unchanged.
def test_bad_scenes_raise_value_error():
    v, f = box()
    s = cullide.Scene()
    with pytest.raises(ValueError, match="the scene has no objects"):
        cullide.prune(s)
    with pytest.raises(ValueError, match="the scene has no objects"):
        cullide.oracle(s)
    s.add("a", v, f)
    with pytest.raises(ValueError, match="argument name: duplicate object name 'a'"):
        s.add("a", v, f)
    with pytest.raises(ValueError, match="argument name: an object's name is empty"):
        s.add("", v, f)
    t = np.eye(4) * 1e38
    t[3, 3], t[0, 3] = 1, 3e38
    with pytest.raises(ValueError, match="object 'big': world coordinates overflow"):
        s.add("big", v, f, transform=t)
    assert s.names == ["a"]
    with pytest.raises(ValueError, match="duplicate object name 'bunny'"):
        cullide.load_scene(SCENE).add("bunny", v, f)


# Trap: the Python PCS must equal `cullide prune cow.off --json`'s, bit for bit (same parser, backend, frame).
def test_prune_equals_command_line(tmp_path):
    r = cullide.prune(cullide.load_scene(COW))
    out = tmp_path / "cow.json"
    cli("prune", COW, "--json", str(out))
    j = json.loads(out.read_text())
    expected = np.array(j["frames"][0]["pcs"], dtype=np.uint32).reshape(-1, 2)
    assert r.pcs.dtype == np.uint32 and r.pcs.shape[1] == 2 and len(r.pcs) > 0
    assert np.array_equal(r.pcs, expected)
    # The passes' counts too (not their times).
    passes = j["frames"][0]["passes"]
    assert list(r.passes["triangles_out"]) == [p["triangles_out"] for p in passes]
    assert list(r.passes["queries"]) == [p["queries"] for p in passes]


# Trap: views= not passed through (a clustered run equal to fit's), or passes without their views
# count; the PCS equals `cullide prune --views clustered`'s.
def test_prune_views_equals_command_line(tmp_path):
    r = cullide.prune(cullide.load_scene(SCENE), resolution=64, views="clustered")
    out = tmp_path / "v.json"
    cli("prune", SCENE, "--resolution", "64", "--views", "clustered", "--json", str(out))
    j = json.loads(out.read_text())
    expected = np.array(j["frames"][0]["pcs"], dtype=np.uint32).reshape(-1, 2)
    assert np.array_equal(r.pcs, expected)
    assert list(r.passes["views"]) == [p["views"] for p in j["frames"][0]["passes"]]
    assert max(r.passes["views"]) > 1
    assert set(cullide.prune(cullide.load_scene(SCENE), resolution=64).passes["views"]) == {1}


# Trap: prune's options (method, resolution text, depth, directions, threads) and face_mask's agreement with pcs.
def test_prune_options_and_face_mask():
    s = cullide.load_scene(SCENE)
    r = cullide.prune(s, method="original", resolution="256x128", depth="16", directions="14", threads=2)
    assert r.total_seconds > 0 and r.levels >= 1
    total = 0
    for o in range(s.object_count):
        m = r.face_mask(o)
        assert m.dtype == bool and len(m) == len(s.world_mesh(o)[1])
        assert np.array_equal(np.flatnonzero(m), r.pcs[r.pcs[:, 0] == o, 1])
        total += int(m.sum())
    assert total == len(r.pcs)
    # Threads do not change the result (the CPU reference is deterministic).
    assert np.array_equal(cullide.prune(s, threads=1).pcs, cullide.prune(s, threads=2).pcs)
    # A (V, F) pair and a trimesh-like object are one-object scenes (a closed box never prunes
    # under the modified method: the seed paper's Figure 4).
    v, f = box()
    one = cullide.Scene()
    one.add("box", v, f)
    expected = cullide.prune(one).pcs
    assert len(expected) == 12
    assert np.array_equal(cullide.prune((v, f)).pcs, expected)
    assert np.array_equal(cullide.prune(Mesh(v, f)).pcs, expected)


# Trap: bad option values are ValueError naming the argument (the core parser's InputError).
@pytest.mark.parametrize(
    "kwargs,message",
    [
        ({"method": "best"}, "method"),
        ({"resolution": 0}, "resolution"),
        ({"resolution": "10x"}, "resolution"),
        ({"depth": "d99"}, "depth"),
        ({"directions": "0,0,0"}, "directions"),
        ({"hierarchy": "octree"}, "hierarchy"),
        ({"leaf_size": 0}, "leaf_size"),
        ({"backend": "vulkan9"}, "backend"),
        ({"threads": -1}, "threads"),
        ({"frame": 5}, "frame"),
        ({"views": "cluster"}, "views"),
        # Numbers through the core's strict parser: never wrapped (4294967396 was 100), clamped or cut.
        ({"resolution": 4294967396}, "argument resolution: 4294967396 is out of range"),
        ({"resolution": "4294967396"}, "argument resolution: 4294967396 is out of range"),
        ({"resolution": 2**70}, "argument resolution: 1180591620717411303424 is out of range"),
        ({"seed": -1}, "argument seed: -1 is out of range"),
        ({"seed": 2**64}, "argument seed: 18446744073709551616 is out of range"),
        ({"leaf_size": 2**32 + 16}, "argument leaf_size: 4294967312 is out of range"),
        ({"leaf_size": "16x"}, "argument leaf_size: '16x' is not an integer"),
        ({"leaf_size": 16.5}, "argument leaf_size: float is not an integer"),
        ({"threads": 2**32}, "argument threads: 4294967296 is out of range"),
    ],
)
def test_prune_bad_options(kwargs, message):
    with pytest.raises(ValueError, match=message):
        cullide.prune(cullide.load_scene(COW), **kwargs)


# Trap: two boxes crossing give crossing pairs between objects; classes and order as documented.
def test_oracle():
    s = cullide.Scene()
    v, f = box()
    s.add("a", v, f)
    s.add("b", v + [0.5, 0.3, 0.2], f)
    pairs = cullide.oracle(s)
    assert pairs.dtype == np.uint32 and pairs.shape[1] == 5 and len(pairs) > 0
    assert set(pairs[:, 4]) <= {0, 1}
    assert np.all(pairs[:, 0] == 0) and np.all(pairs[:, 2] == 1)
    cow = cullide.oracle(cullide.load_scene(COW))
    assert len(cow) == 101 and int((cow[:, 4] == 0).sum()) == 89  # as `cullide oracle cow.off`
    with pytest.raises(ValueError, match="frame"):
        cullide.oracle(s, frame=1)


# Trap: check() counts false prunes by class and attributes every missed pair to a cause; the
# modified method keeps every crossing pair, so only touching ones may be false prunes.
def test_check():
    s = cullide.load_scene(COW)
    pairs = cullide.oracle(s)
    r = cullide.prune(s, resolution=64, depth="12")
    c = cullide.check(r, pairs)
    assert c["same_pcs"]
    assert set(c["false_prunes"]) == {"crossing", "touching"}
    assert c["pcs_triangles"] == len(r.pcs)
    assert sum(c["causes"].values()) == c["false_prune_count"]
    assert c["missed"].shape == (sum(c["cause_pairs"].values()), 8)
    assert set(c["causes"]) == set(cullide.CAUSES)
    assert 0 <= c["efficiency"] <= 1
    # No false prunes of pairs the method promises to keep, at any resolution (the paper's claim
    # for crossing pairs holds when the penetration exceeds the depth unit; counted, not assumed).
    assert c["causes"]["unexplained"] == 0
    # Bad pairs.
    with pytest.raises(ValueError, match="shape"):
        cullide.check(r, pairs[:, :4])
    bad = pairs.copy()
    bad[0, 1] = 999999
    with pytest.raises(ValueError, match="does not have"):
        cullide.check(r, bad)
    bad = pairs.copy()
    bad[0, 4] = 7
    with pytest.raises(ValueError, match="class"):
        cullide.check(r, bad)


# Trap: study() writes the command's CSV (same header) and returns one row per configuration.
def test_study(tmp_path):
    out = tmp_path / "s.csv"
    rows = cullide.study("cows:500", methods=["original", "modified"], resolutions=[64, 128], repeats=1, out=out)
    with open(out, newline="") as fh:
        table = list(csv.DictReader(fh))
    assert len(table) == 4
    names = list(rows.keys()) if isinstance(rows, dict) else list(rows.columns)
    assert names == list(table[0].keys())
    assert len(rows[names[0]]) == 4
    with pytest.raises(ValueError, match="method"):
        cullide.study("cows:500", methods="best", repeats=1, out=tmp_path / "t.csv")
    with pytest.raises(ValueError, match="backend"):
        cullide.study("cows:500", backends="vulkan9", repeats=1, out=tmp_path / "t.csv")
    # The views axis (docs/cullide.md#views-per-cluster): one row per mode, named in its column.
    v = cullide.study("cows:500", resolutions=64, views=["fit", "clustered"], repeats=1, oracle=False,
                      out=tmp_path / "v.csv")
    assert list(v["views"]) == ["fit", "clustered"]
    with pytest.raises(ValueError, match="views"):
        cullide.study("cows:500", views="cluster", repeats=1, out=tmp_path / "u.csv")
    # Near contacts: counted when asked, with the oracle only.
    n = cullide.study("cows:500", resolutions=64, repeats=1, near_distance=0.01, out=tmp_path / "n.csv")
    assert n["near_contacts"][0] > 0 and n["near_distance"][0] > 0
    with pytest.raises(ValueError, match="near_distance"):
        cullide.study("cows:500", repeats=1, near_distance=0.01, oracle=False, out=tmp_path / "m.csv")
    # Every family in one call: the exact oracle and a peer beside an image-space method, judged
    # by the audit with the tolerance given.
    e = cullide.study("cows:500", methods=["modified", "exact", "embree"], resolutions=64, repeats=1, tolerance=1e-4,
                      out=tmp_path / "e.csv")
    assert list(e["family"]) == ["image-space", "exact", "peer"]
    assert e["pairs_missed"][1] == 0 and list(e["missed_unexplained"])[1:] == [0, 0]
    with pytest.raises(ValueError, match="tolerance"):
        cullide.study("cows:500", methods="exact", repeats=1, tolerance=0.5, out=tmp_path / "f.csv")


# Trap: a deforming object's frames read from its positions file one at a time: another frame
# gives other positions, the last frame as the command line wrote it, and the same triangles.
def test_positions_file_scene(tmp_path):
    cli("make-scene", "cloth", "--triangles", "800", "--frames", "3", "-o", str(tmp_path / "c.json"))
    s = cullide.load_scene(tmp_path / "c.json")
    assert s.frame_count == 3 and s.names == ["cloth", "sphere"]
    v0, f0 = s.world_mesh(0, frame=0)
    v2, f2 = s.world_mesh(0, frame=2)
    assert np.array_equal(f0, f2) and not np.array_equal(v0, v2)
    assert v2[:, 1].min() < v0[:, 1].min()  # the cloth fell


# Trap: the exact switch lost between Python and the core (the keyword ignored, so the default
# runs) or its bad value not named. A switch below the whole mesh keeps a superset of never's PCS
# and says where it stopped; the study's axis records each run's switch and time to exact pairs.
def test_exact_switch(tmp_path):
    scene = cullide.load_scene(COW)
    never = cullide.prune(scene, resolution=128)
    stopped = cullide.prune(scene, resolution=128, exact_switch=1000000)
    assert never.switched_at_level is None
    assert stopped.switched_at_level == 0
    assert {tuple(p) for p in never.pcs} <= {tuple(p) for p in stopped.pcs}
    with pytest.raises(ValueError, match="exact_switch"):
        cullide.prune(scene, exact_switch="sometimes")
    rows = cullide.study("cows:500", resolutions=64, repeats=1, out=tmp_path / "x.csv", exact_switches=["never", 100])
    assert list(rows["exact_switch"]) == ["never", "100"]
    assert all(t >= 0 for t in rows["time_to_exact_ms"])


# Trap: the backend interface from Python: two overlapping quads, the far one drawn first, the
# near one's samples pass (LESS); depth readback shape (h, w); queries numbered in order.
def test_cpu_backend_and_command_list():
    v = np.array([[0, 0, 0.5], [1, 0, 0.5], [1, 1, 0.5], [0, 1, 0.5],
                  [0, 0, 0.25], [1, 0, 0.25], [1, 1, 0.25], [0, 1, 0.25]], dtype=np.float32)
    f = np.array([[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]], dtype=np.uint32)
    b = cullide.CpuBackend(threads=2)
    b.set_geometry(v, f)
    frame = b.set_view((0, 0, 1), (0, 1, 0, 1, 0, 1), width=16, height=8, depth="d24")
    assert frame["dir"] == (0.0, 0.0, 1.0)
    # The view box in the frame's own coordinates: exactly the quads' projection.
    x, y = v @ np.array(frame["right"]), v @ np.array(frame["up"])
    b.set_view((0, 0, 1), (x.min(), x.max(), y.min(), y.max(), 0, 1), width=16, height=8, depth="d24")
    cl = cullide.CommandList()
    cl.clear(1.0)
    cl.depth_func("less")
    assert cl.begin_query() == 0
    cl.draw(0, 2)
    cl.end_query()
    assert cl.begin_query("samples") == 1
    cl.draw(2, 2)
    cl.end_query()
    assert cl.begin_query("any") == 2
    cl.draw(0, 2)
    cl.end_query()
    assert cl.query_count == 3 and len(cl) == 11
    res = b.execute(cl)
    assert res.dtype == np.uint64 and list(res) == [128, 128, 0]
    d = b.read_depth()
    assert d.shape == (8, 16) and d.dtype == np.uint32
    assert np.all(d == round(0.25 * (2**24 - 1)))
    # Misuse raises ValueError.
    with pytest.raises(ValueError, match="depth function"):
        cl.depth_func("sometimes")
    bad = cullide.CommandList()
    bad.draw(0, 99)
    with pytest.raises(ValueError, match="command list"):
        b.execute(bad)
    with pytest.raises(ValueError):
        cullide.CommandList().end_query()
    with pytest.raises(ValueError, match="first"):
        cullide.CommandList().draw(-1, 2)
    with pytest.raises(ValueError, match="count"):
        cullide.CommandList().draw_conservative(0, 2**40, True, False)
    with pytest.raises(ValueError, match="clear depth"):
        cullide.CommandList().clear(float("nan"))
    with pytest.raises(ValueError, match="set_view"):
        cullide.CpuBackend().execute(cullide.CommandList())
    with pytest.raises(ValueError, match="box"):
        b.set_view((0, 0, 1), (0, 1, 0))
    with pytest.raises(ValueError, match="direction"):
        b.set_view((0, 0, float("nan")), (0, 1, 0, 1, 0, 1))


# Trap: every public function and class has a docstring.
def test_docstrings():
    for name in cullide.__all__:
        obj = getattr(cullide, name)
        if callable(obj):
            assert obj.__doc__ and obj.__doc__.strip(), name
    for cls in (cullide.Scene, cullide.CpuBackend, cullide.CommandList, cullide.PruneResult):
        for attr, value in vars(cls).items():
            if not attr.startswith("_"):
                assert getattr(value, "__doc__", None), cls.__name__ + "." + attr


# Trap: the backend's speed options from Python (simd, direct, view cache, tile size, the scalar
# reference) must all give the same queries, depth and counters bit for bit, the second run of a
# list too; and each option must reach the backend (a binding that dropped one would pass the
# equality alone): the direct path taken on one thread and not when turned off, the second run
# replayed from the view cache on the tile path and not when the cache is 0 bytes. The fill rule
# gets its own check: a unit square whose bottom and left edges (in the view) and diagonal run
# through pixel centres covers each centre once, and the bottom row is in under the bottom-left
# rule (16 samples) and out under the top-left one (12).
def test_cpu_backend_options_same_results():
    rng = np.random.default_rng(7)
    n = 3000
    centres = rng.uniform(0.05, 0.95, size=(n, 1, 3))
    v = (centres + rng.uniform(-0.03, 0.03, size=(n, 3, 3))).reshape(-1, 3).astype(np.float32)
    f = np.arange(3 * n, dtype=np.uint32).reshape(n, 3)
    cl = cullide.CommandList()
    cl.clear(1.0)
    cl.depth_func("less")
    for first in range(0, n, 500):
        cl.begin_query()
        cl.draw(first, 500)
        cl.end_query()
    results = []
    for kw in ({}, {"direct": False}, {"direct": False, "view_cache_bytes": 0}, {"simd": False},
               {"tile_size": 16}, {"scalar_reference": True}, {"threads": 2, "direct": False}):
        b = cullide.CpuBackend(threads=kw.pop("threads", 1), **kw)
        b.set_geometry(v, f)
        frame = b.set_view((0, 0, 1), (0, 1, 0, 1, -1, 2))
        x, y = v @ np.array(frame["right"]), v @ np.array(frame["up"])
        b.set_view((0, 0, 1), (x.min(), x.max(), y.min(), y.max(), -1, 2), width=97, height=61, depth="d16")
        for run in range(2):
            q = b.execute(cl)
            results.append((list(q), b.read_depth().tobytes(), b.last_stats))
            if kw == {} or kw.get("direct") is False:
                assert b.last_ran_direct == (kw == {})
            if kw == {"direct": False}:
                assert b.last_replayed_view == (run == 1)
            if kw.get("view_cache_bytes") == 0:
                assert not b.last_replayed_view
    assert results[0][2]["fragments"] > 0 and results[0][2]["triangles"] == n
    assert all(r == results[0] for r in results[1:])
    # Two triangles sharing a diagonal; pixel centres on the square's low edges and 0.25, 0.5, 0.75 in.
    q = np.array([[0, 0, 0.5], [1, 0, 0.5], [1, 1, 0.5], [0, 1, 0.5]], dtype=np.float32)
    counts = []
    for rule in ("bottom-left", "top-left"):
        b = cullide.CpuBackend(fill_rule=rule)
        b.set_geometry(q, np.array([[0, 1, 2], [0, 2, 3]], dtype=np.uint32))
        frame = b.set_view((0, 0, 1), (0, 1, 0, 1, 0, 1))
        x0, y0 = (q @ np.array(frame["right"])).min(), (q @ np.array(frame["up"])).min()
        b.set_view((0, 0, 1), (x0 - 0.125, x0 + 0.875, y0 - 0.125, y0 + 0.875, 0, 1), width=4, height=4)
        one = cullide.CommandList()
        one.begin_query()
        one.draw(0, 2)
        one.end_query()
        counts.append(int(b.execute(one)[0]))
    assert counts == [16, 12]
    with pytest.raises(ValueError, match="fill_rule"):
        cullide.CpuBackend(fill_rule="top-right")
    with pytest.raises(ValueError, match="view_cache_bytes"):
        cullide.CpuBackend(view_cache_bytes=-1)
