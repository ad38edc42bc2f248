// Mesh input and output, OBJ (see mesh_io.cpp for the choice of parsers).
#include "cullide/mesh_io.h"

#include <tiny_obj_loader.h>
#include "mesh_io_detail.h"

#include <sstream>
#include <string>
#include <string_view>

namespace cullide::meshio {
namespace {

// ---------------------------------------------------------------------------------------------
// OBJ: strict scan of `v` and `f` lines, then tinyobjloader, then agreement.

struct ObjScan {
    size_t vertices = 0;
    std::vector<std::vector<uint32_t>> faces;  // resolved, 0-based
};

ObjScan scanObj(const std::string& src, std::string_view data) {
    ObjScan scan;
    LineReader lines(data);
    Line line;
    std::vector<std::string_view> tok;
    while (lines.next(line)) {
        splitTokens(stripComment(line.text), tok);
        if (tok.empty()) continue;
        if (tok[0] == "v") {
            if (tok.size() < 4 || tok.size() > 8)
                throw InputError(
                    src, atLine(line.number) + "parse error: a 'v' line needs 3 coordinates (optionally w or r g b)");
            for (size_t k = 1; k < tok.size(); ++k) {
                float x;
                const NumStatus s = parseFloatToken(tok[k], x);
                if (s == NumStatus::Invalid)
                    throw InputError(src, atLine(line.number) + "parse error: " + quote(tok[k]) + " is not a number");
                if (s == NumStatus::OutOfRange || (k <= 3 && !std::isfinite(x)))
                    throw InputError(src,
                                     atLine(line.number) + "vertex " + std::to_string(scan.vertices) +
                                         " has a non-finite coordinate " + quote(tok[k]) +
                                         " (NaN, Inf or out of float range)");
            }
            ++scan.vertices;
        } else if (tok[0] == "f") {
            if (tok.size() < 4)
                throw InputError(src,
                                 atLine(line.number) + "face " + std::to_string(scan.faces.size()) + " has " +
                                     std::to_string(tok.size() - 1) + " vertices; a face needs at least 3");
            std::vector<uint32_t> face;
            for (size_t k = 1; k < tok.size(); ++k) {
                const std::string_view t = tok[k];
                const size_t slash = t.find('/');
                long long idx;
                if (!parseIntToken(t.substr(0, slash), idx) || idx == 0)
                    throw InputError(src,
                                     atLine(line.number) + "parse error: " + quote(t) +
                                         " is not a vertex reference (OBJ indices start at 1)");
                // Negative indices are relative to the vertices read so far (OBJ spec).
                const long long resolved = idx > 0 ? idx - 1 : static_cast<long long>(scan.vertices) + idx;
                if (resolved < 0)
                    throw InputError(src,
                                     atLine(line.number) + "negative vertex index " + std::to_string(idx) +
                                         " reaches before the first vertex");
                if (static_cast<unsigned long long>(resolved) >= kMaxVertices)
                    throw InputError(src,
                                     atLine(line.number) + "vertex index " + std::to_string(idx) + " out of range");
                face.push_back(static_cast<uint32_t>(resolved));
            }
            scan.faces.push_back(std::move(face));
        }
    }
    for (size_t f = 0; f < scan.faces.size(); ++f)
        for (uint32_t v : scan.faces[f])
            if (v >= scan.vertices)
                throw InputError(src,
                                 "face " + std::to_string(f) + " refers to vertex " + std::to_string(v + 1ull) +
                                     " (1-based), but the file has only " + std::to_string(scan.vertices) +
                                     " vertices (index out of range)");
    return scan;
}

}  // namespace

Mesh readObj(const std::string& src, std::string_view data) {
    if (onlyWhitespace(data)) throw InputError(src, "empty file");
    const ObjScan scan = scanObj(src, data);
    if (scan.faces.empty()) throw InputError(src, "mesh has zero triangles (no 'f' lines)");

    tinyobj::attrib_t attrib;
    std::vector<tinyobj::shape_t> shapes;
    std::vector<tinyobj::material_t> materials;
    std::string warn, err;
    // Materials are of no use here; an empty reader keeps tinyobjloader from opening other files.
    struct NoMaterials : tinyobj::MaterialReader {
        bool operator()(const std::string&, std::vector<tinyobj::material_t>*, std::map<std::string, int>*,
                        std::string*, std::string*) override {
            return true;
        }
    } noMaterials;
    std::istringstream stream{std::string(data)};
    if (!tinyobj::LoadObj(&attrib, &shapes, &materials, &warn, &err, &stream, &noMaterials, /*triangulate=*/false))
        throw InputError(
            src, "parse error: " + (err.empty() ? std::string("tinyobjloader failed") : err.substr(0, err.find('\n'))));

    Mesh mesh;
    if (attrib.vertices.size() != 3 * scan.vertices)
        throw InputError(src,
                         "tinyobjloader read " + std::to_string(attrib.vertices.size() / 3) +
                             " vertices where the file has " + std::to_string(scan.vertices) +
                             "; refusing a mesh that would not keep the file's indices");
    mesh.positions.resize(scan.vertices);
    for (size_t i = 0; i < scan.vertices; ++i)
        mesh.positions[i] = Vec3f(attrib.vertices[3 * i], attrib.vertices[3 * i + 1], attrib.vertices[3 * i + 2]);

    // tinyobjloader puts faces in shapes (one per o/g/usemtl run), in file order.
    size_t f = 0;
    std::vector<uint32_t> face;
    for (const tinyobj::shape_t& shape : shapes) {
        size_t offset = 0;
        for (unsigned char n : shape.mesh.num_face_vertices) {
            face.clear();
            for (size_t k = 0; k < n; ++k) {
                const int v = shape.mesh.indices[offset + k].vertex_index;
                face.push_back(v < 0 ? std::numeric_limits<uint32_t>::max() : static_cast<uint32_t>(v));
            }
            offset += n;
            if (f >= scan.faces.size() || face != scan.faces[f])
                throw InputError(src,
                                 "tinyobjloader's face " + std::to_string(f) +
                                     " differs from the file's; refusing a mesh that would not keep the file's faces");
            addFan(mesh, face.data(), face.size());
            ++f;
        }
    }
    if (f != scan.faces.size())
        throw InputError(src,
                         "tinyobjloader read " + std::to_string(f) + " faces where the file has " +
                             std::to_string(scan.faces.size()) +
                             " (faces with more than 255 vertices are not supported)");
    return mesh;
}

}  // namespace cullide::meshio
