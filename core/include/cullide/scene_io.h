// Scene files: a small JSON format listing objects and an optional animation.
//
//   {
//     "objects": [
//       {"name": "bunny", "mesh": "meshes/bunny.off",          // path relative to the scene file
//        "transform": {"translate": [0,0,0], "rotate": {"axis": [0,1,0], "degrees": 30},
//                      "scale": 1.0}},                         // or "matrix": 4x4 row-major
//       ...
//     ],
//     "animation": {                                           // optional
//       "frames": [
//         {"objects": {"bunny": {"transform": {...}, "positions": "frames/bunny_001.off"}}},
//         ...
//       ]
//     }
//   }
//
// A plain mesh file (.obj .off .ply .stl) is also accepted wherever a scene is: it becomes a
// one-object scene named after the file. Every problem throws InputError naming the scene file
// (or the mesh file it refers to) and the cause: malformed JSON (with line/column), a missing
// or mistyped key, an unknown key, an unreadable mesh, a duplicate object name, a frame that
// refers to an unknown object or gives the wrong number of positions.
#pragma once

#include "cullide/scene.h"

#include <filesystem>

namespace cullide {

// Loads a scene file (.json) or a single mesh file. Throws InputError.
Animation loadScene(const std::filesystem::path& path);

// Writes `animation` as a scene file at `path`, each object's mesh (and per-frame positions)
// as OFF files under `path`'s folder named from the scene's stem and the object name.
// Deterministic: the same animation gives the same bytes. Throws InputError on write failure.
void writeScene(const Animation& animation, const std::filesystem::path& path);

}  // namespace cullide
