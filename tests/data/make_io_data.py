#!/usr/bin/env python3
"""Writes the small mesh and scene files under tests/data/good and tests/data/bad that the mesh_io,
scene_io and mesh_stats tests read. Run from anywhere; the output is deterministic. The files are
committed, so this script only documents (and can regenerate) them."""
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))
GOOD = os.path.join(HERE, "good")
BAD = os.path.join(HERE, "bad")

# Seven vertices, a triangle, a quad and a pentagon. The faces use the vertices out of order, so a
# loader that renumbers vertices (in order of first use, say) is caught.
V = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (2, 0, 0), (2, 1, 0), (3, 0.5, 0)]
F = [(4, 5, 1), (0, 1, 2, 3), (1, 4, 6, 5, 2)]
# The same vertices moved (used as a frame's positions file).
V_MOVED = [(x + 10, y, z + 0.25) for (x, y, z) in V]


def write(path, data):
    mode = "wb" if isinstance(data, bytes) else "w"
    with open(path, mode, newline="" if mode == "w" else None) as f:
        f.write(data)


def fmt(x):
    return repr(float(x)) if x != int(x) else str(int(x))


def off_text(verts, faces, header="OFF"):
    s = header + "\n# a comment line\n%d %d 0\n" % (len(verts), len(faces))
    s += "".join(" ".join(fmt(c) for c in v) + "\n" for v in verts)
    s += "".join("%d %s\n" % (len(f), " ".join(map(str, f))) for f in faces)
    return s


def ply_header(fmt_name, nv, nf, extra_face=""):
    return ("ply\nformat %s 1.0\ncomment cullide test data\nelement vertex %d\nproperty float x\n"
            "property float y\nproperty float z\nproperty uchar quality\nelement face %d\n"
            "property list uchar int vertex_indices\n%send_header\n" % (fmt_name, nv, nf, extra_face))


def ply_binary(verts, faces, endian="<", truncate=None):
    name = "binary_little_endian" if endian == "<" else "binary_big_endian"
    b = ply_header(name, len(verts), len(faces)).encode()
    for v in verts:
        b += struct.pack(endian + "3fB", *v, 7)
    for f in faces:
        b += struct.pack(endian + "B%di" % len(f), len(f), *f)
    return b[:truncate] if truncate else b


def ply_ascii(verts, faces):
    s = ply_header("ascii", len(verts), len(faces))
    s += "".join(" ".join(fmt(c) for c in v) + " 7\n" for v in verts)
    s += "".join("%d %s\n" % (len(f), " ".join(map(str, f))) for f in faces)
    return s


# A unit cube as 12 triangles (each corner repeated in several facets: STL welding restores 8).
CUBE_V = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
CUBE_F = [(0, 2, 1), (0, 3, 2), (4, 5, 6), (4, 6, 7), (0, 1, 5), (0, 5, 4),
          (1, 2, 6), (1, 6, 5), (2, 3, 7), (2, 7, 6), (3, 0, 4), (3, 4, 7)]


def stl_ascii(tris):
    s = "solid cube\n"
    for t in tris:
        s += " facet normal 0 0 0\n  outer loop\n"
        s += "".join("   vertex %s\n" % " ".join(fmt(c) for c in v) for v in t)
        s += "  endloop\n endfacet\n"
    return s + "endsolid cube\n"


def stl_binary(tris):
    b = b"cullide test cube".ljust(80, b" ") + struct.pack("<I", len(tris))
    for t in tris:
        b += struct.pack("<3f", 0, 0, 0) + b"".join(struct.pack("<3f", *v) for v in t) + b"\0\0"
    return b


def main():
    os.makedirs(GOOD, exist_ok=True)
    os.makedirs(BAD, exist_ok=True)

    # --- good ---------------------------------------------------------------------------------
    write(os.path.join(GOOD, "polys.off"), off_text(V, F))
    write(os.path.join(GOOD, "polys_moved.off"), off_text(V_MOVED, F))
    write(os.path.join(GOOD, "polys_ascii.ply"), ply_ascii(V, F))
    write(os.path.join(GOOD, "polys_binary.ply"), ply_binary(V, F, "<"))
    write(os.path.join(GOOD, "polys_binary_be.ply"), ply_binary(V, F, ">"))
    # OBJ: 1-based, a group switch, v/vt/vn references and negative (relative) indices.
    obj = "# polys\nmtllib none.mtl\no polys\n"
    obj += "".join("v %s\n" % " ".join(fmt(c) for c in v) for v in V)
    obj += "vt 0 0\nvn 0 0 1\n"
    obj += "f 5 6 2\ng second\nusemtl whatever\nf 1/1/1 2/1/1 3/1/1 4/1/1\n"
    obj += "f -6//1 -3//1 -1//1 -2//1 -5//1\n"
    write(os.path.join(GOOD, "polys.obj"), obj)
    cube_tris = [tuple(CUBE_V[i] for i in f) for f in CUBE_F]
    write(os.path.join(GOOD, "cube_ascii.stl"), stl_ascii(cube_tris))
    write(os.path.join(GOOD, "cube_binary.stl"), stl_binary(cube_tris))
    # Duplicated vertices: 1 and 3 repeat 0 bit for bit; 4 is -0.0, which is not bit-identical.
    write(os.path.join(GOOD, "dup_verts.off"),
          "OFF\n6 3 0\n0 0 0\n1 0 0\n0 1 0\n0 0 0\n-0 0 0\n1 0 0\n3 0 1 2\n3 3 5 2\n3 2 1 0\n")
    # Degenerate triangles: repeated index, coincident corners, exactly collinear corners, and a
    # nearly collinear one that is not degenerate.
    write(os.path.join(GOOD, "degenerate.off"),
          "OFF\n9 5 0\n0 0 0\n1 0 0\n0 1 0\n1 0 0\n0.5 0.5 0.5\n1 1 1\n2 2 2.0000002\n"
          "0.25 0.25 0.25\n7 7 7\n"
          "3 0 1 2\n3 0 1 1\n3 0 1 3\n3 0 4 5\n3 0 5 6\n")
    scene = """{
  "objects": [
    {"name": "polys", "mesh": "polys.off",
     "transform": {"translate": [1, 2, 3], "rotate": {"axis": [0, 0, 1], "degrees": 90}, "scale": 2}},
    {"name": "cube", "mesh": "cube_binary.stl"},
    {"name": "matrixed", "mesh": "polys_ascii.ply",
     "transform": {"matrix": [[1, 0, 0, 5], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]}}
  ],
  "animation": {
    "frames": [
      {},
      {"objects": {"polys": {"positions": "polys_moved.off"}}},
      {"objects": {"cube": {"transform": {"translate": [0, 0, 1]}},
                   "polys": {"transform": {"scale": [1, 2, 3]}, "positions": "polys_moved.off"}}}
    ]
  }
}
"""
    write(os.path.join(GOOD, "scene.json"), scene)

    # --- bad: meshes ---------------------------------------------------------------------------
    os.makedirs(os.path.join(BAD, "a_directory.off"), exist_ok=True)
    write(os.path.join(BAD, "a_directory.off", ".keep"), "")
    bad = [  # (name, contents)
        ("unknown_extension.xyz", off_text(V, F)),
        ("parse_error.obj", "v 0 0 0\nv 1 abc 0\nv 0 1 0\nf 1 2 3\n"),
        ("parse_error.off", "OFF\n3 1 0\n0 0 0\n1 x 0\n0 1 0\n3 0 1 2\n"),
        ("parse_error.ply",
         "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
         "element face 1\nproperty list uchar int vertex_indices\nbogus line\nend_header\n"),
        ("parse_error.stl",
         "solid t\nfacet normal 0 0 1\n outer loop\n vertex 0 0 0\n vertex 1 x 0\n vertex 1 1 0\n"
         " endloop\nendfacet\nendsolid t\n"),
        ("truncated_binary.ply", ply_binary(V, F, "<", truncate=-7)),
        ("nan.off", "OFF\n3 1 0\n0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n"),
        ("inf.off", "OFF\n3 1 0\n0 0 0\n1 inf 0\n0 1 0\n3 0 1 2\n"),
        ("nan_binary.ply", ply_binary([(0, 0, 0), (float("nan"), 0, 0), (0, 1, 0)], [(0, 1, 2)])),
        ("overflow.obj", "v 0 0 0\nv 1e39 0 0\nv 0 1 0\nf 1 2 3\n"),
        ("index_out_of_range.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n"),
        ("index_out_of_range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n"),
        ("negative_index.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 -1\n"),
        ("negative_index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n"),
        ("empty.off", ""),
        ("empty.obj", "\n\n"),
        ("empty.stl", ""),
        ("zero_triangles.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n"),
        ("zero_triangles.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n"),
        ("two_vertex_face.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n"),
        ("two_vertex_face.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2\n"),
        ("four_vertex_facet.stl",
         "solid t\nfacet normal 0 0 1\n outer loop\n vertex 0 0 0\n vertex 1 0 0\n vertex 1 1 0\n"
         " vertex 2 2 2\n endloop\nendfacet\nendsolid t\n"),
        ("fewer_faces_than_header.off", "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"),
        # --- bad: scenes -----------------------------------------------------------------------
        ("malformed.json", '{\n  "objects": [\n    {"name": "a", "mesh": "../good/polys.off",}\n  ]\n}\n'),
        ("missing_key.json", '{"objects": [{"name": "a"}]}\n'),
        ("wrong_type.json",
         '{"objects": [{"name": "a", "mesh": "../good/polys.off", "transform": {"scale": "big"}}]}\n'),
        ("unknown_key.json", '{"objects": [{"name": "a", "mesh": "../good/polys.off", "colour": 3}]}\n'),
        ("duplicate_name.json",
         '{"objects": [{"name": "a", "mesh": "../good/polys.off"}, {"name": "a", "mesh": "../good/polys.off"}]}\n'),
        ("duplicate_key.json", '{"objects": [{"name": "a", "name": "b", "mesh": "../good/polys.off"}]}\n'),
        ("unknown_object_in_frame.json",
         '{"objects": [{"name": "a", "mesh": "../good/polys.off"}],\n'
         ' "animation": {"frames": [{"objects": {"b": {"transform": {"translate": [0, 0, 1]}}}}]}}\n'),
        ("wrong_position_count.json",
         '{"objects": [{"name": "a", "mesh": "../good/polys.off"}],\n'
         ' "animation": {"frames": [{"objects": {"a": {"positions": "../good/cube_binary.stl"}}}]}}\n'),
        ("missing_mesh.json", '{"objects": [{"name": "a", "mesh": "no_such_mesh.off"}]}\n'),
        ("nul_in_mesh_path.json", '{"objects": [{"name": "a", "mesh": "../good/polys.off\\u0000.ply"}]}\n'),
        ("nonfinite_transform.json",
         '{"objects": [{"name": "a", "mesh": "../good/polys.off", "transform": {"translate": [0, 1e39, 0]}}]}\n'),
        # Each number a finite float, but the world coordinates they make are not.
        ("overflow_transform.json",
         '{"objects": [{"name": "cow", "mesh": "../good/polys.off",\n'
         '              "transform": {"scale": 1e38, "translate": [3e38, 0, 0]}}]}\n'),
        ("overflow_frame.json",
         '{"objects": [{"name": "a", "mesh": "../good/polys.off"}, {"name": "cow", "mesh": "../good/polys.off"}],\n'
         ' "animation": {"frames": [{}, {}, {}, {"objects": {"cow": {"transform": {"scale": 1e38, '
         '"translate": [0, 3e38, 0]}}}}]}}\n'),
        ("beyond_2_60.json",
         '{"objects": [{"name": "a", "mesh": "../good/polys.off", "transform": {"scale": 1e19}}]}\n'),
    ]
    for name, data in bad:
        write(os.path.join(BAD, name), data)


if __name__ == "__main__":
    main()
