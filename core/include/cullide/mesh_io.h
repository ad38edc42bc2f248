// Mesh input and output.
//
// Input: tinyobjloader reads OBJ (it keeps the file's vertex indices; assimp's OBJ importer does
// not), behind a strict line scan it must agree with. OFF, PLY (ascii, binary little- and
// big-endian) and STL (ascii and binary) have small strict readers of our own, because assimp's
// importers clamp bad indices, drop faces and facet corners, read past truncated binary data,
// leak on parse errors and round floats inexactly (see mesh_io.cpp for what was measured).
// Contract for every format:
//   - vertex i of the file is positions[i]; faces keep the file's order; an n-gon is
//     fan-triangulated in place (v0 v1 v2, v0 v2 v3, ...), giving n-2 consecutive triangles;
//   - no welding, except for STL, which has no indices: STL vertices are welded when their three
//     float coordinates are bit-identical (first occurrence gives the index, in file order), so
//     a closed STL mesh gets its connectivity back; nothing else is merged;
//   - OFF, PLY and ascii STL floats are parsed correctly rounded (std::from_chars), so
//     writeOff/writePly -> loadMesh gives the same mesh bit for bit; OBJ floats are parsed by
//     tinyobjloader (through double; 90000 random %.9g floats came back bit-exact);
//   - PLY: element "vertex" with scalar x, y, z (any numeric type, converted to float) and element
//     "face" with an integer list "vertex_indices" (or "vertex_index"); other elements and
//     properties are read past and ignored. OFF: [ST][C][N]OFF, extra values on vertex and face
//     lines (colours, normals) ignored;
//   - the result passes validateMesh(); anything else throws InputError naming the file and the
//     cause (missing/unreadable file, unknown format, parse error, NaN/Inf, index out of range,
//     negative index, truncated data, empty mesh, zero triangles, faces with fewer than three
//     vertices), with the line number for ascii formats. Nothing is silently dropped or clamped.
// Output: PLY (binary little-endian or ascii), optionally with one RGB colour per face
// (used to show the PCS, as in the paper's Figures 6 and 7), and OFF. Writers write to a
// temporary file in the same folder and rename it, so a failed write leaves nothing half-written.
#pragma once

#include "cullide/mesh.h"

#include <array>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>

namespace cullide {

enum class MeshFormat { Obj, Off, Ply, Stl };

// The format from the file extension (.obj .off .ply .stl, any case); throws InputError
// naming the file when the extension is none of these.
MeshFormat meshFormatFromPath(const std::filesystem::path& path);

// Loads a mesh (see the contract above). Throws InputError.
Mesh loadMesh(const std::filesystem::path& path);

using Rgb8 = std::array<uint8_t, 3>;

struct PlyWriteOptions {
    bool binary = true;
    std::span<const Rgb8> faceColours;  // empty, or one per triangle
};

// Writes `mesh` as PLY (faces as "list uchar uint vertex_indices", then red green blue when
// colours are given; floats as %.9g in ascii); throws InputError naming the file if it cannot be
// written. Precondition (checked): every index < vertexCount(), faceColours empty or one per face.
void writePly(const Mesh& mesh, const std::filesystem::path& path, const PlyWriteOptions& options = {});
// Writes `mesh` as ascii OFF with floats printed round-trip exact (%.9g); deterministic bytes.
void writeOff(const Mesh& mesh, const std::filesystem::path& path);

}  // namespace cullide
