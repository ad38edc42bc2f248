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
//       "positions": {"cloth": "cloth.pos"},                   // every frame of it (optional)
//       "frames": [                                            // optional with "positions"
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
// refers to an unknown object or gives the wrong number of positions, a positions file whose
// header, size, vertex count or frame count is wrong (positions_file.h).
#pragma once

#include "cullide/scene.h"

#include <filesystem>

namespace cullide {

// Loads a scene file (.json) or a single mesh file. Throws InputError.
Animation loadScene(const std::filesystem::path& path);

// Writes `animation` as a scene file at `path`, each object's mesh as an OFF file and each
// deforming object's positions in every frame as one positions file (.pos), beside it, named from
// the scene's stem, the object's index and its name. Deterministic: the same animation gives the
// same bytes. When the scene file cannot be written, the files this call created are removed.
// Throws InputError on write failure, or when a frame's positions file no longer reads.
void writeScene(const Animation& animation, const std::filesystem::path& path);

}  // namespace cullide
