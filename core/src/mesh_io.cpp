// Mesh input and output (see mesh_io.h for the contract).
//
// Which parser reads what, and why (each decision was tested against the installed libraries):
//   - OBJ: tinyobjloader (triangulate=false), which keeps the file's vertex indices. It is lenient
//     where we must not be (an unparsable number becomes 0, a face with fewer than three vertices
//     is dropped, an out-of-range index is only a warning), so a strict line scan runs first
//     and its faces must agree with tinyobjloader's; a disagreement is refused, never patched.
//   - OFF and PLY: our own strict readers. assimp 5.2.5 was tried and fails the contract: its OFF
//     importer clamps out-of-range indices, maps negative ones to 0, pads short faces with 0 and
//     silently drops faces; its binary PLY reader reads past the end of a truncated file; its
//     float parser (fast_atof) is not correctly rounded (3486 of 90000 random %.9g floats came
//     back different), so writeOff/writePly(ascii) could not round-trip bit-exactly; and
//     aiProcess_Triangulate ear-clips pentagons rather than fanning them.
//   - STL: our own reader too. assimp's STL importer was tried and silently drops a fourth
//     `vertex` in an ascii facet, leaks its half-built mesh whenever an ascii parse fails (found by
//     the fuzzer, LeakSanitizer) and rounds floats inexactly. Binary when the size is exactly
//     84 + 50 n (n from the header), as assimp decides too; ascii otherwise, if it starts with
//     "solid".
//   - Floats of OFF, PLY and ascii STL are parsed with std::from_chars (correctly rounded, locale-free) and
//     written with std::to_chars(general, 9) (the %.9g format, locale-free), so write -> read is
//     the identity on finite floats.
//
// One file per format: mesh_io_off.cpp, mesh_io_ply.cpp, mesh_io_obj.cpp, mesh_io_stl.cpp; the
// helpers they share (numbers, lines, tokens, writing) are here, declared in mesh_io_detail.h.
#include "cullide/mesh_io.h"

#include "cullide/error.h"
#include "cullide/file_io.h"
#include "mesh_io_detail.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string_view>

namespace cullide::meshio {

bool onlyWhitespace(std::string_view s) {
    return std::all_of(s.begin(), s.end(), [](char c) {
        return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v';
    });
}

NumStatus parseFloatToken(std::string_view tok, float& out) {
    if (tok.size() > 1 && tok[0] == '+' && tok[1] != '-' && tok[1] != '+') tok.remove_prefix(1);
    const char* b = tok.data();
    const char* e = b + tok.size();
    auto r = std::from_chars(b, e, out);
    if (r.ec == std::errc() && r.ptr == e) return NumStatus::Ok;
    if (r.ec == std::errc::result_out_of_range && r.ptr == e) {
        // libstdc++ reports underflow and overflow alike; underflow rounds to a subnormal or zero.
        double d;
        auto rd = std::from_chars(b, e, d);
        if (rd.ptr != e) return NumStatus::Invalid;
        if (rd.ec == std::errc::result_out_of_range) {
            // Beyond double range: overflow unless the exponent is negative.
            const bool tiny = tok.find("e-") != std::string_view::npos || tok.find("E-") != std::string_view::npos;
            if (!tiny) return NumStatus::OutOfRange;
            out = tok[0] == '-' ? -0.0f : 0.0f;
            return NumStatus::Ok;
        }
        const float f = static_cast<float>(d);
        if (std::isinf(f)) return NumStatus::OutOfRange;
        out = f;
        return NumStatus::Ok;
    }
    return NumStatus::Invalid;
}

NumStatus parseDoubleToken(std::string_view tok, double& out) {
    if (tok.size() > 1 && tok[0] == '+' && tok[1] != '-' && tok[1] != '+') tok.remove_prefix(1);
    const char* e = tok.data() + tok.size();
    auto r = std::from_chars(tok.data(), e, out);
    if (r.ptr != e) return NumStatus::Invalid;
    if (r.ec == std::errc::result_out_of_range) return NumStatus::OutOfRange;
    return r.ec == std::errc() ? NumStatus::Ok : NumStatus::Invalid;
}

bool parseIntToken(std::string_view tok, long long& out) {
    if (tok.size() > 1 && tok[0] == '+' && tok[1] != '-' && tok[1] != '+') tok.remove_prefix(1);
    const char* e = tok.data() + tok.size();
    auto r = std::from_chars(tok.data(), e, out);
    return r.ec == std::errc() && r.ptr == e;
}

std::string quote(std::string_view tok) {
    std::string s(tok.substr(0, 40));
    for (char& c : s)
        if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126) c = '?';
    return "'" + s + (tok.size() > 40 ? "...'" : "'");
}

std::string_view stripComment(std::string_view s) {
    const size_t h = s.find('#');
    return h == std::string_view::npos ? s : s.substr(0, h);
}

void splitTokens(std::string_view s, std::vector<std::string_view>& out) {
    out.clear();
    size_t i = 0;
    while (i < s.size()) {
        while (i < s.size() && (s[i] == ' ' || s[i] == '\t' || s[i] == '\f' || s[i] == '\v')) ++i;
        size_t j = i;
        while (j < s.size() && s[j] != ' ' && s[j] != '\t' && s[j] != '\f' && s[j] != '\v') ++j;
        if (j > i) out.push_back(s.substr(i, j - i));
        i = j;
    }
}

std::string atLine(size_t n) {
    return "line " + std::to_string(n) + ": ";
}

void addFan(Mesh& mesh, const uint32_t* idx, size_t n) {
    for (size_t k = 1; k + 1 < n; ++k) mesh.triangles.push_back({idx[0], idx[k], idx[k + 1]});
}

size_t boundedReserve(unsigned long long count, size_t bytes, size_t minBytesPerItem) {
    return static_cast<size_t>(std::min<unsigned long long>(count, bytes / minBytesPerItem + 1));
}

void appendFloat(std::string& out, float x) {
    char buf[32];
    const auto r = std::to_chars(buf, buf + sizeof buf, x, std::chars_format::general, 9);  // == %.9g
    out.append(buf, r.ptr);
}

void appendUint(std::string& out, unsigned long long x) {
    char buf[24];
    const auto r = std::to_chars(buf, buf + sizeof buf, x);
    out.append(buf, r.ptr);
}

void checkIndices(const Mesh& mesh) {
    for (const Triangle& t : mesh.triangles)
        for (uint32_t v : t)
            CULLIDE_CHECK(v < mesh.positions.size(), "writing a mesh with a triangle index out of range");
}

}  // namespace cullide::meshio

namespace cullide {

namespace fs = std::filesystem;

MeshFormat meshFormatFromPath(const fs::path& path) {
    std::string ext = path.extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (ext == ".obj") return MeshFormat::Obj;
    if (ext == ".off") return MeshFormat::Off;
    if (ext == ".ply") return MeshFormat::Ply;
    if (ext == ".stl") return MeshFormat::Stl;
    throw InputError(path.string(), "unknown mesh format '" + ext + "' (expected .obj, .off, .ply or .stl)");
}

Mesh loadMesh(const fs::path& path) {
    const std::string src = path.string();
    const MeshFormat format = meshFormatFromPath(path);
    const std::string data = readFile(path);
    Mesh mesh;
    switch (format) {
        case MeshFormat::Obj: mesh = meshio::readObj(src, data); break;
        case MeshFormat::Off: mesh = meshio::readOff(src, data); break;
        case MeshFormat::Ply: mesh = meshio::readPly(src, data); break;
        case MeshFormat::Stl: mesh = meshio::readStl(src, data); break;
    }
    validateMesh(mesh, src);
    return mesh;
}

}  // namespace cullide
