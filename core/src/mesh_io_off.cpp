// Mesh input and output, OFF (see mesh_io.cpp for the choice of parsers).
#include "cullide/mesh_io.h"

#include "cullide/file_io.h"
#include "mesh_io_detail.h"

#include <string>

namespace cullide::meshio {

// ---------------------------------------------------------------------------------------------
// OFF: [ST][C][N]OFF keyword (optional), then "nv nf [ne]", nv vertex lines (x y z, anything after
// is colour/normal data and ignored), nf face lines ("n i0 .. in-1", anything after is colour).

Mesh readOff(const std::string& src, std::string_view data) {
    LineReader lines(data);
    Line line;
    std::vector<std::string_view> tok;
    auto nextContent = [&](const char* what) {
        while (lines.next(line)) {
            splitTokens(stripComment(line.text), tok);
            if (!tok.empty()) return;
        }
        throw InputError(src, std::string("parse error: the file ends before ") + what);
    };

    if (onlyWhitespace(data)) throw InputError(src, "empty file");
    nextContent("the vertex and face counts");
    size_t first = 0;
    {
        const std::string_view kw = tok[0];
        if (kw.size() >= 3 && kw.substr(kw.size() - 3) == "OFF") {
            std::string_view pre = kw.substr(0, kw.size() - 3);
            if (pre.starts_with("ST")) pre.remove_prefix(2);
            if (pre.starts_with("C")) pre.remove_prefix(1);
            if (pre.starts_with("N")) pre.remove_prefix(1);
            if (!pre.empty())
                throw InputError(src,
                                 atLine(line.number) + "unsupported OFF variant " + quote(kw) +
                                     " (only [ST][C][N]OFF, three-dimensional)");
            first = 1;
        }
    }
    if (first == tok.size()) {
        nextContent("the vertex and face counts");
        first = 0;
    }
    long long nv = -1, nf = -1, ne = 0;
    if (tok.size() - first < 2 || tok.size() - first > 3 || !parseIntToken(tok[first], nv) ||
        !parseIntToken(tok[first + 1], nf) || (tok.size() - first == 3 && !parseIntToken(tok[first + 2], ne)))
        throw InputError(src, atLine(line.number) + "parse error: expected 'vertices faces [edges]' counts");
    if (nv < 0 || nf < 0 || ne < 0) throw InputError(src, atLine(line.number) + "negative count in the header");
    if (static_cast<unsigned long long>(nv) > kMaxVertices)
        throw InputError(src, atLine(line.number) + "too many vertices (" + std::to_string(nv) + ")");

    Mesh mesh;
    mesh.positions.reserve(boundedReserve(nv, data.size(), 6));
    mesh.triangles.reserve(boundedReserve(nf, data.size(), 8));
    for (long long i = 0; i < nv; ++i) {
        nextContent(("vertex " + std::to_string(i) + " (the header says " + std::to_string(nv) + " vertices)").c_str());
        if (tok.size() < 3)
            throw InputError(
                src,
                atLine(line.number) + "parse error: vertex " + std::to_string(i) + " has fewer than 3 coordinates");
        Vec3f p;
        for (int k = 0; k < 3; ++k) {
            const NumStatus s = parseFloatToken(tok[k], p[k]);
            if (s == NumStatus::Invalid)
                throw InputError(src,
                                 atLine(line.number) + "parse error: " + quote(tok[k]) + " is not a number (vertex " +
                                     std::to_string(i) + ")");
            if (s == NumStatus::OutOfRange)
                throw InputError(src,
                                 atLine(line.number) + "vertex " + std::to_string(i) + " coordinate " + quote(tok[k]) +
                                     " is out of float range (not finite)");
        }
        mesh.positions.push_back(p);
    }
    std::vector<uint32_t> face;
    for (long long f = 0; f < nf; ++f) {
        nextContent(("face " + std::to_string(f) + " (the header says " + std::to_string(nf) + " faces)").c_str());
        long long n = 0;
        if (!parseIntToken(tok[0], n))
            throw InputError(
                src,
                atLine(line.number) + "parse error: face " + std::to_string(f) + " does not start with a vertex count");
        if (n < 3)
            throw InputError(src,
                             atLine(line.number) + "face " + std::to_string(f) + " has " + std::to_string(n) +
                                 " vertices; a face needs at least 3");
        if (static_cast<unsigned long long>(n) > tok.size() - 1)
            throw InputError(src,
                             atLine(line.number) + "parse error: face " + std::to_string(f) + " announces " +
                                 std::to_string(n) + " vertices but lists " + std::to_string(tok.size() - 1));
        face.clear();
        for (long long k = 0; k < n; ++k) {
            long long idx;
            if (!parseIntToken(tok[1 + k], idx))
                throw InputError(src,
                                 atLine(line.number) + "parse error: " + quote(tok[1 + k]) +
                                     " is not a vertex index (face " + std::to_string(f) + ")");
            if (idx < 0)
                throw InputError(src,
                                 atLine(line.number) + "face " + std::to_string(f) + " has a negative vertex index " +
                                     std::to_string(idx));
            if (idx >= nv)
                throw InputError(src,
                                 atLine(line.number) + "face " + std::to_string(f) + " refers to vertex " +
                                     std::to_string(idx) + ", but the file has only " + std::to_string(nv) +
                                     " vertices (index out of range)");
            face.push_back(static_cast<uint32_t>(idx));
        }
        // Whatever follows the indices on the line is a face colour, which we do not keep.
        addFan(mesh, face.data(), face.size());
    }
    while (lines.next(line)) {
        splitTokens(stripComment(line.text), tok);
        if (!tok.empty())
            throw InputError(src,
                             atLine(line.number) + "unexpected content after the last face (the header says " +
                                 std::to_string(nv) + " vertices and " + std::to_string(nf) + " faces)");
    }
    return mesh;
}

}  // namespace cullide::meshio

namespace cullide {

namespace fs = std::filesystem;
using namespace meshio;

void writeOff(const Mesh& mesh, const fs::path& path) {
    checkIndices(mesh);
    std::string out;
    out.reserve(32 + mesh.positions.size() * 36 + mesh.triangles.size() * 24);
    out += "OFF\n";
    appendUint(out, mesh.positions.size());
    out += ' ';
    appendUint(out, mesh.triangles.size());
    out += " 0\n";
    appendVertexLines(out, mesh);
    for (const Triangle& t : mesh.triangles) {
        appendTriangleIndices(out, t);
        out += '\n';
    }
    writeFileAtomically(path, out);
}

}  // namespace cullide
