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
#include "cullide/mesh_io.h"

#include "cullide/error.h"
#include "cullide/file_io.h"

#include <tiny_obj_loader.h>

#include <algorithm>
#include <bit>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <sstream>
#include <string_view>

namespace cullide {
namespace {

namespace fs = std::filesystem;

bool onlyWhitespace(std::string_view s) {
    return std::all_of(s.begin(), s.end(), [](char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v'; });
}

// ---------------------------------------------------------------------------------------------
// Numbers: whole tokens only, locale-free, correctly rounded.

enum class NumStatus { Ok, Invalid, OutOfRange };

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

// ---------------------------------------------------------------------------------------------
// Lines and tokens for the ascii formats. Lines end at '\n', '\r' or "\r\n"; `#` starts a comment
// in OFF and OBJ (not in PLY, where comments are header lines).

struct Line {
    std::string_view text;
    size_t number = 0;  // 1-based
};

class LineReader {
public:
    LineReader(std::string_view data, size_t firstLine = 1) : data_(data), next_(firstLine) {}
    bool next(Line& line) {
        if (pos_ >= data_.size()) return false;
        size_t end = pos_;
        while (end < data_.size() && data_[end] != '\n' && data_[end] != '\r') ++end;
        line.text = data_.substr(pos_, end - pos_);
        line.number = next_++;
        if (end < data_.size() && data_[end] == '\r' && end + 1 < data_.size() && data_[end + 1] == '\n') ++end;
        pos_ = end + 1;
        return true;
    }
    size_t position() const { return pos_; }

private:
    std::string_view data_;
    size_t pos_ = 0;
    size_t next_;
};

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

std::string atLine(size_t n) { return "line " + std::to_string(n) + ": "; }

// Appends the fan triangulation (v0 v1 v2, v0 v2 v3, ...) of one polygon.
void addFan(Mesh& mesh, const uint32_t* idx, size_t n) {
    for (size_t k = 1; k + 1 < n; ++k) mesh.triangles.push_back({idx[0], idx[k], idx[k + 1]});
}

// Reserve no more than the file could possibly hold, so a lying count cannot exhaust memory.
size_t boundedReserve(unsigned long long count, size_t bytes, size_t minBytesPerItem) {
    return static_cast<size_t>(std::min<unsigned long long>(count, bytes / minBytesPerItem + 1));
}

constexpr unsigned long long kMaxVertices = std::numeric_limits<uint32_t>::max();

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
                throw InputError(src, atLine(line.number) + "unsupported OFF variant " + quote(kw) +
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
        if (tok.size() < 3) throw InputError(src, atLine(line.number) + "parse error: vertex " + std::to_string(i) + " has fewer than 3 coordinates");
        Vec3f p;
        for (int k = 0; k < 3; ++k) {
            const NumStatus s = parseFloatToken(tok[k], p[k]);
            if (s == NumStatus::Invalid)
                throw InputError(src, atLine(line.number) + "parse error: " + quote(tok[k]) + " is not a number (vertex " + std::to_string(i) + ")");
            if (s == NumStatus::OutOfRange)
                throw InputError(src, atLine(line.number) + "vertex " + std::to_string(i) + " coordinate " + quote(tok[k]) +
                                          " is out of float range (not finite)");
        }
        mesh.positions.push_back(p);
    }
    std::vector<uint32_t> face;
    for (long long f = 0; f < nf; ++f) {
        nextContent(("face " + std::to_string(f) + " (the header says " + std::to_string(nf) + " faces)").c_str());
        long long n = 0;
        if (!parseIntToken(tok[0], n))
            throw InputError(src, atLine(line.number) + "parse error: face " + std::to_string(f) + " does not start with a vertex count");
        if (n < 3)
            throw InputError(src, atLine(line.number) + "face " + std::to_string(f) + " has " + std::to_string(n) +
                                      " vertices; a face needs at least 3");
        if (static_cast<unsigned long long>(n) > tok.size() - 1)
            throw InputError(src, atLine(line.number) + "parse error: face " + std::to_string(f) + " announces " + std::to_string(n) +
                                      " vertices but lists " + std::to_string(tok.size() - 1));
        face.clear();
        for (long long k = 0; k < n; ++k) {
            long long idx;
            if (!parseIntToken(tok[1 + k], idx))
                throw InputError(src, atLine(line.number) + "parse error: " + quote(tok[1 + k]) + " is not a vertex index (face " + std::to_string(f) + ")");
            if (idx < 0)
                throw InputError(src, atLine(line.number) + "face " + std::to_string(f) + " has a negative vertex index " + std::to_string(idx));
            if (idx >= nv)
                throw InputError(src, atLine(line.number) + "face " + std::to_string(f) + " refers to vertex " + std::to_string(idx) +
                                          ", but the file has only " + std::to_string(nv) + " vertices (index out of range)");
            face.push_back(static_cast<uint32_t>(idx));
        }
        // Whatever follows the indices on the line is a face colour, which we do not keep.
        addFan(mesh, face.data(), face.size());
    }
    while (lines.next(line)) {
        splitTokens(stripComment(line.text), tok);
        if (!tok.empty())
            throw InputError(src, atLine(line.number) + "unexpected content after the last face (the header says " +
                                      std::to_string(nv) + " vertices and " + std::to_string(nf) + " faces)");
    }
    return mesh;
}

// ---------------------------------------------------------------------------------------------
// PLY (ascii, binary_little_endian, binary_big_endian). Needs element "vertex" with scalar x, y, z
// and element "face" with a list "vertex_indices" (or "vertex_index") of integers. Other
// elements and properties are read past and ignored.

enum class PlyType { I8, U8, I16, U16, I32, U32, F32, F64 };

bool plyTypeFromName(std::string_view n, PlyType& t) {
    static const std::pair<std::string_view, PlyType> names[] = {
        {"char", PlyType::I8},     {"int8", PlyType::I8},     {"uchar", PlyType::U8},   {"uint8", PlyType::U8},
        {"short", PlyType::I16},   {"int16", PlyType::I16},   {"ushort", PlyType::U16}, {"uint16", PlyType::U16},
        {"int", PlyType::I32},     {"int32", PlyType::I32},   {"uint", PlyType::U32},   {"uint32", PlyType::U32},
        {"float", PlyType::F32},   {"float32", PlyType::F32}, {"double", PlyType::F64}, {"float64", PlyType::F64}};
    for (const auto& [name, type] : names)
        if (n == name) { t = type; return true; }
    return false;
}

size_t plyTypeSize(PlyType t) {
    switch (t) {
    case PlyType::I8: case PlyType::U8: return 1;
    case PlyType::I16: case PlyType::U16: return 2;
    case PlyType::I32: case PlyType::U32: case PlyType::F32: return 4;
    case PlyType::F64: return 8;
    }
    return 0;
}

bool plyTypeIsInteger(PlyType t) { return t != PlyType::F32 && t != PlyType::F64; }

struct PlyProperty {
    std::string name;
    bool isList = false;
    PlyType countType = PlyType::U8;
    PlyType type = PlyType::F32;
};

struct PlyElement {
    std::string name;
    unsigned long long count = 0;
    std::vector<PlyProperty> properties;
};

// A scalar value as read: integers exactly, floats as the float (or double) they are.
struct PlyValue {
    bool isInteger = true;
    long long i = 0;
    double d = 0;  // for F64
    float f = 0;   // for F32
    bool isF32 = false;
};

class PlyBody {
public:
    PlyBody(const std::string& src, std::string_view body, bool ascii, bool bigEndian, size_t firstLine)
        : src_(src), body_(body), ascii_(ascii), big_(bigEndian), line_(firstLine) {}

    // Reads one value of type `t`; `what` says where (for messages).
    PlyValue read(PlyType t, const std::string& what) { return ascii_ ? readAscii(t, what) : readBinary(t, what); }

    void finish() {
        if (ascii_) {
            std::string_view tok;
            if (nextToken(tok))
                throw InputError(src_, atLine(line_) + "unexpected data " + quote(tok) + " after the last element");
        } else if (pos_ != body_.size()) {
            throw InputError(src_, std::to_string(body_.size() - pos_) + " unexpected bytes after the last element");
        }
    }

private:
    bool nextToken(std::string_view& tok) {
        while (pos_ < body_.size()) {
            const char c = body_[pos_];
            if (c == '\n') ++line_;
            if (c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v') ++pos_;
            else break;
        }
        if (pos_ >= body_.size()) return false;
        size_t e = pos_;
        while (e < body_.size() && !(body_[e] == ' ' || body_[e] == '\t' || body_[e] == '\n' || body_[e] == '\r' || body_[e] == '\f' || body_[e] == '\v')) ++e;
        tok = body_.substr(pos_, e - pos_);
        pos_ = e;
        return true;
    }

    PlyValue readAscii(PlyType t, const std::string& what) {
        std::string_view tok;
        if (!nextToken(tok)) throw InputError(src_, "parse error: the file ends inside " + what + " (truncated)");
        PlyValue v;
        if (plyTypeIsInteger(t)) {
            if (!parseIntToken(tok, v.i))
                throw InputError(src_, atLine(line_) + "parse error: " + quote(tok) + " is not an integer (" + what + ")");
            return v;
        }
        v.isInteger = false;
        NumStatus s;
        if (t == PlyType::F32) {
            v.isF32 = true;
            s = parseFloatToken(tok, v.f);
        } else {
            s = parseDoubleToken(tok, v.d);
        }
        if (s == NumStatus::Invalid)
            throw InputError(src_, atLine(line_) + "parse error: " + quote(tok) + " is not a number (" + what + ")");
        if (s == NumStatus::OutOfRange)
            throw InputError(src_, atLine(line_) + quote(tok) + " is out of range, not finite (" + what + ")");
        return v;
    }

    PlyValue readBinary(PlyType t, const std::string& what) {
        const size_t n = plyTypeSize(t);
        if (body_.size() - pos_ < n) throw InputError(src_, "the file ends inside " + what + " (truncated binary data)");
        unsigned char b[8];
        std::memcpy(b, body_.data() + pos_, n);
        pos_ += n;
        if (big_ != (std::endian::native == std::endian::big)) std::reverse(b, b + n);
        PlyValue v;
        switch (t) {
        case PlyType::I8: { int8_t x; std::memcpy(&x, b, 1); v.i = x; break; }
        case PlyType::U8: { uint8_t x; std::memcpy(&x, b, 1); v.i = x; break; }
        case PlyType::I16: { int16_t x; std::memcpy(&x, b, 2); v.i = x; break; }
        case PlyType::U16: { uint16_t x; std::memcpy(&x, b, 2); v.i = x; break; }
        case PlyType::I32: { int32_t x; std::memcpy(&x, b, 4); v.i = x; break; }
        case PlyType::U32: { uint32_t x; std::memcpy(&x, b, 4); v.i = x; break; }
        case PlyType::F32: v.isInteger = false; v.isF32 = true; std::memcpy(&v.f, b, 4); break;
        case PlyType::F64: v.isInteger = false; std::memcpy(&v.d, b, 8); break;
        }
        return v;
    }

    const std::string& src_;
    std::string_view body_;
    bool ascii_;
    bool big_;
    size_t pos_ = 0;
    size_t line_;
};

float plyValueAsFloat(const PlyValue& v) {
    if (v.isInteger) return static_cast<float>(v.i);
    return v.isF32 ? v.f : static_cast<float>(v.d);
}

Mesh readPly(const std::string& src, std::string_view data) {
    if (onlyWhitespace(data)) throw InputError(src, "empty file");
    LineReader lines(data);
    Line line;
    std::vector<std::string_view> tok;
    if (!lines.next(line) || line.text != "ply") throw InputError(src, "parse error: not a PLY file (no 'ply' magic line)");
    enum class Format { None, Ascii, Le, Be } format = Format::None;
    std::vector<PlyElement> elements;
    bool ended = false;
    while (!ended && lines.next(line)) {
        splitTokens(line.text, tok);
        if (tok.empty()) continue;
        const std::string_view kw = tok[0];
        if (kw == "comment" || kw == "obj_info") continue;
        if (kw == "format") {
            if (tok.size() != 3 || tok[2] != "1.0")
                throw InputError(src, atLine(line.number) + "parse error: expected 'format <ascii|binary_little_endian|binary_big_endian> 1.0'");
            if (tok[1] == "ascii") format = Format::Ascii;
            else if (tok[1] == "binary_little_endian") format = Format::Le;
            else if (tok[1] == "binary_big_endian") format = Format::Be;
            else throw InputError(src, atLine(line.number) + "unknown PLY format " + quote(tok[1]));
        } else if (kw == "element") {
            long long count;
            if (tok.size() != 3 || !parseIntToken(tok[2], count) || count < 0)
                throw InputError(src, atLine(line.number) + "parse error: expected 'element <name> <count>'");
            for (const PlyElement& e : elements)
                if (e.name == tok[1]) throw InputError(src, atLine(line.number) + "element " + quote(tok[1]) + " is declared twice");
            elements.push_back({std::string(tok[1]), static_cast<unsigned long long>(count), {}});
        } else if (kw == "property") {
            if (elements.empty()) throw InputError(src, atLine(line.number) + "parse error: property before any element");
            PlyProperty p;
            bool ok;
            if (tok.size() == 5 && tok[1] == "list") {
                p.isList = true;
                ok = plyTypeFromName(tok[2], p.countType) && plyTypeFromName(tok[3], p.type) && plyTypeIsInteger(p.countType);
                p.name = tok[4];
            } else {
                ok = tok.size() == 3 && plyTypeFromName(tok[1], p.type);
                p.name = tok.size() == 3 ? tok[2] : std::string_view();
            }
            if (!ok) throw InputError(src, atLine(line.number) + "parse error: bad property declaration");
            for (const PlyProperty& q : elements.back().properties)
                if (q.name == p.name) throw InputError(src, atLine(line.number) + "property " + quote(p.name) + " is declared twice");
            elements.back().properties.push_back(p);
        } else if (kw == "end_header") {
            if (tok.size() != 1) throw InputError(src, atLine(line.number) + "parse error: junk after end_header");
            ended = true;
        } else {
            throw InputError(src, atLine(line.number) + "parse error: unknown header line " + quote(kw));
        }
    }
    if (!ended) throw InputError(src, "parse error: the header has no end_header line (truncated?)");
    if (format == Format::None) throw InputError(src, "parse error: the header has no format line");

    // Locate what we need.
    const PlyElement* vertexEl = nullptr;
    const PlyElement* faceEl = nullptr;
    int px = -1, py = -1, pz = -1, plist = -1;
    for (const PlyElement& e : elements) {
        if (e.name == "vertex") {
            vertexEl = &e;
            for (size_t i = 0; i < e.properties.size(); ++i) {
                const PlyProperty& p = e.properties[i];
                int* slot = p.name == "x" ? &px : p.name == "y" ? &py : p.name == "z" ? &pz : nullptr;
                if (slot) {
                    if (p.isList) throw InputError(src, "vertex property " + quote(p.name) + " is a list, expected a scalar");
                    *slot = static_cast<int>(i);
                }
            }
        } else if (e.name == "face") {
            faceEl = &e;
            for (size_t i = 0; i < e.properties.size(); ++i) {
                const PlyProperty& p = e.properties[i];
                if (p.name == "vertex_indices" || p.name == "vertex_index") {
                    if (plist >= 0) throw InputError(src, "face element has both vertex_indices and vertex_index");
                    if (!p.isList || !plyTypeIsInteger(p.type))
                        throw InputError(src, "face property " + quote(p.name) + " must be a list of integers");
                    plist = static_cast<int>(i);
                }
            }
        }
    }
    if (!vertexEl) throw InputError(src, "no 'vertex' element");
    if (px < 0 || py < 0 || pz < 0) throw InputError(src, "the vertex element lacks an x, y or z property");
    if (!faceEl) throw InputError(src, "no 'face' element (zero triangles)");
    if (plist < 0) throw InputError(src, "the face element has no vertex_indices list");
    if (vertexEl->count > kMaxVertices) throw InputError(src, "too many vertices (" + std::to_string(vertexEl->count) + ")");

    const std::string_view body = data.substr(lines.position());
    const bool ascii = format == Format::Ascii;
    PlyBody in(src, body, ascii, format == Format::Be, line.number + 1);
    Mesh mesh;
    std::vector<uint32_t> face;
    for (const PlyElement& e : elements) {
        const bool isVertex = &e == vertexEl;
        const bool isFace = &e == faceEl;
        if (isVertex) mesh.positions.reserve(boundedReserve(e.count, body.size(), ascii ? 6 : 3));
        if (isFace) mesh.triangles.reserve(boundedReserve(e.count, body.size(), ascii ? 8 : 4));
        if (e.properties.empty()) continue;  // nothing to read, whatever the count says
        for (unsigned long long i = 0; i < e.count; ++i) {
            Vec3f p = Vec3f::Zero();
            for (size_t k = 0; k < e.properties.size(); ++k) {
                const PlyProperty& prop = e.properties[k];
                const std::string what = "element '" + e.name + "' " + std::to_string(i) + ", property '" + prop.name + "'";
                if (!prop.isList) {
                    const PlyValue v = in.read(prop.type, what);
                    if (isVertex) {
                        if (static_cast<int>(k) == px) p.x() = plyValueAsFloat(v);
                        if (static_cast<int>(k) == py) p.y() = plyValueAsFloat(v);
                        if (static_cast<int>(k) == pz) p.z() = plyValueAsFloat(v);
                    }
                    continue;
                }
                const PlyValue c = in.read(prop.countType, what + " (list length)");
                if (c.i < 0) throw InputError(src, what + ": negative list length");
                const bool indices = isFace && static_cast<int>(k) == plist;
                if (indices && c.i < 3)
                    throw InputError(src, "face " + std::to_string(i) + " has " + std::to_string(c.i) + " vertices; a face needs at least 3");
                face.clear();
                for (long long j = 0; j < c.i; ++j) {
                    const PlyValue v = in.read(prop.type, what);
                    if (!indices) continue;
                    if (v.i < 0)
                        throw InputError(src, "face " + std::to_string(i) + " has a negative vertex index " + std::to_string(v.i));
                    if (static_cast<unsigned long long>(v.i) >= vertexEl->count)
                        throw InputError(src, "face " + std::to_string(i) + " refers to vertex " + std::to_string(v.i) + ", but the file has only " +
                                                  std::to_string(vertexEl->count) + " vertices (index out of range)");
                    face.push_back(static_cast<uint32_t>(v.i));
                }
                if (indices) addFan(mesh, face.data(), face.size());
            }
            if (isVertex) mesh.positions.push_back(p);
        }
    }
    in.finish();
    return mesh;
}

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
                throw InputError(src, atLine(line.number) + "parse error: a 'v' line needs 3 coordinates (optionally w or r g b)");
            for (size_t k = 1; k < tok.size(); ++k) {
                float x;
                const NumStatus s = parseFloatToken(tok[k], x);
                if (s == NumStatus::Invalid)
                    throw InputError(src, atLine(line.number) + "parse error: " + quote(tok[k]) + " is not a number");
                if (s == NumStatus::OutOfRange || (k <= 3 && !std::isfinite(x)))
                    throw InputError(src, atLine(line.number) + "vertex " + std::to_string(scan.vertices) + " has a non-finite coordinate " +
                                              quote(tok[k]) + " (NaN, Inf or out of float range)");
            }
            ++scan.vertices;
        } else if (tok[0] == "f") {
            if (tok.size() < 4)
                throw InputError(src, atLine(line.number) + "face " + std::to_string(scan.faces.size()) + " has " + std::to_string(tok.size() - 1) +
                                          " vertices; a face needs at least 3");
            std::vector<uint32_t> face;
            for (size_t k = 1; k < tok.size(); ++k) {
                const std::string_view t = tok[k];
                const size_t slash = t.find('/');
                long long idx;
                if (!parseIntToken(t.substr(0, slash), idx) || idx == 0)
                    throw InputError(src, atLine(line.number) + "parse error: " + quote(t) + " is not a vertex reference (OBJ indices start at 1)");
                // Negative indices are relative to the vertices read so far (OBJ spec).
                const long long resolved = idx > 0 ? idx - 1 : static_cast<long long>(scan.vertices) + idx;
                if (resolved < 0)
                    throw InputError(src, atLine(line.number) + "negative vertex index " + std::to_string(idx) + " reaches before the first vertex");
                if (static_cast<unsigned long long>(resolved) >= kMaxVertices)
                    throw InputError(src, atLine(line.number) + "vertex index " + std::to_string(idx) + " out of range");
                face.push_back(static_cast<uint32_t>(resolved));
            }
            scan.faces.push_back(std::move(face));
        }
    }
    for (size_t f = 0; f < scan.faces.size(); ++f)
        for (uint32_t v : scan.faces[f])
            if (v >= scan.vertices)
                throw InputError(src, "face " + std::to_string(f) + " refers to vertex " + std::to_string(v + 1ull) + " (1-based), but the file has only " +
                                          std::to_string(scan.vertices) + " vertices (index out of range)");
    return scan;
}

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
        bool operator()(const std::string&, std::vector<tinyobj::material_t>*, std::map<std::string, int>*, std::string*,
                        std::string*) override {
            return true;
        }
    } noMaterials;
    std::istringstream stream{std::string(data)};
    if (!tinyobj::LoadObj(&attrib, &shapes, &materials, &warn, &err, &stream, &noMaterials, /*triangulate=*/false))
        throw InputError(src, "parse error: " + (err.empty() ? std::string("tinyobjloader failed") : err.substr(0, err.find('\n'))));

    Mesh mesh;
    if (attrib.vertices.size() != 3 * scan.vertices)
        throw InputError(src, "tinyobjloader read " + std::to_string(attrib.vertices.size() / 3) + " vertices where the file has " +
                                  std::to_string(scan.vertices) + "; refusing a mesh that would not keep the file's indices");
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
                throw InputError(src, "tinyobjloader's face " + std::to_string(f) +
                                          " differs from the file's; refusing a mesh that would not keep the file's faces");
            addFan(mesh, face.data(), face.size());
            ++f;
        }
    }
    if (f != scan.faces.size())
        throw InputError(src, "tinyobjloader read " + std::to_string(f) + " faces where the file has " + std::to_string(scan.faces.size()) +
                                  " (faces with more than 255 vertices are not supported)");
    return mesh;
}

// ---------------------------------------------------------------------------------------------
// STL, ascii or binary, welded on bit-identical positions.

class StlWelder {
public:
    explicit StlWelder(Mesh& mesh) : mesh_(mesh) {}
    uint32_t add(const Vec3f& p) {
        const std::array<uint32_t, 3> key{std::bit_cast<uint32_t>(p.x()), std::bit_cast<uint32_t>(p.y()), std::bit_cast<uint32_t>(p.z())};
        auto [it, inserted] = index_.try_emplace(key, static_cast<uint32_t>(mesh_.positions.size()));
        if (inserted) mesh_.positions.push_back(p);
        return it->second;
    }

private:
    Mesh& mesh_;
    std::map<std::array<uint32_t, 3>, uint32_t> index_;  // lookups only: the order comes from the file
};

bool keywordIs(std::string_view tok, std::string_view kw) {
    return tok.size() == kw.size() &&
           std::equal(tok.begin(), tok.end(), kw.begin(), [](char a, char b) { return std::tolower(static_cast<unsigned char>(a)) == b; });
}

Mesh readStlBinary(const std::string& src, std::string_view data, uint32_t facets) {
    Mesh mesh;
    mesh.triangles.reserve(facets);
    StlWelder weld(mesh);
    for (uint32_t f = 0; f < facets; ++f) {
        const char* rec = data.data() + 84 + 50 * size_t(f) + 12;  // skip the normal
        Triangle t;
        for (int k = 0; k < 3; ++k) {
            Vec3f p;
            for (int c = 0; c < 3; ++c) {
                unsigned char b[4];
                std::memcpy(b, rec + 12 * k + 4 * c, 4);
                if constexpr (std::endian::native == std::endian::big) std::reverse(b, b + 4);
                std::memcpy(&p[c], b, 4);
            }
            if (!p.allFinite()) throw InputError(src, "facet " + std::to_string(f) + " has a non-finite coordinate (NaN or Inf)");
            t[k] = weld.add(p);
        }
        mesh.triangles.push_back(t);
    }
    return mesh;
}

// solid [name] { facet normal a b c  outer loop  vertex x y z (3 times)  endloop  endfacet }
// endsolid [name], possibly several solids one after the other. Keywords in any case.
Mesh readStlAscii(const std::string& src, std::string_view data) {
    Mesh mesh;
    StlWelder weld(mesh);
    LineReader lines(data);
    Line line;
    std::vector<std::string_view> tok;
    size_t facet = 0;
    enum class State { Outside, Solid, Facet, Loop, EndLoop } state = State::Outside;
    int corners = 0;
    Triangle t{};
    auto fail = [&](const std::string& cause) -> void { throw InputError(src, atLine(line.number) + cause); };
    while (lines.next(line)) {
        splitTokens(line.text, tok);
        if (tok.empty()) continue;
        const std::string_view kw = tok[0];
        switch (state) {
        case State::Outside:
            if (!keywordIs(kw, "solid")) fail("parse error: expected 'solid', got " + quote(kw));
            state = State::Solid;  // the rest of the line is the solid's name
            break;
        case State::Solid:
            if (keywordIs(kw, "endsolid")) {
                state = State::Outside;
                break;
            }
            if (!keywordIs(kw, "facet") || tok.size() != 5 || !keywordIs(tok[1], "normal"))
                fail("parse error: expected 'facet normal <x> <y> <z>' or 'endsolid'");
            for (int c = 0; c < 3; ++c) {
                float n;  // the normal is not used, but must be a number (NaN/Inf/overflow tolerated)
                if (parseFloatToken(tok[2 + c], n) == NumStatus::Invalid) fail("parse error: " + quote(tok[2 + c]) + " is not a number");
            }
            state = State::Facet;
            break;
        case State::Facet:
            if (tok.size() != 2 || !keywordIs(kw, "outer") || !keywordIs(tok[1], "loop")) fail("parse error: expected 'outer loop'");
            state = State::Loop;
            corners = 0;
            break;
        case State::Loop:
            if (keywordIs(kw, "endloop")) {
                if (tok.size() != 1) fail("parse error: junk after 'endloop'");
                if (corners != 3)
                    fail("facet " + std::to_string(facet) + " has " + std::to_string(corners) + " vertices; every facet needs exactly 3");
                state = State::EndLoop;
                break;
            }
            if (!keywordIs(kw, "vertex") || tok.size() != 4) fail("parse error: expected 'vertex <x> <y> <z>' or 'endloop'");
            if (corners == 3) fail("facet " + std::to_string(facet) + " has more than 3 vertices; every facet needs exactly 3");
            {
                Vec3f p;
                for (int c = 0; c < 3; ++c) {
                    const NumStatus st = parseFloatToken(tok[1 + c], p[c]);
                    if (st == NumStatus::Invalid) fail("parse error: " + quote(tok[1 + c]) + " is not a number");
                    if (st == NumStatus::OutOfRange || !std::isfinite(p[c]))
                        fail("facet " + std::to_string(facet) + " has a non-finite coordinate " + quote(tok[1 + c]) + " (NaN, Inf or out of float range)");
                }
                t[corners++] = weld.add(p);
            }
            break;
        case State::EndLoop:
            if (!keywordIs(kw, "endfacet") || tok.size() != 1) fail("parse error: expected 'endfacet'");
            mesh.triangles.push_back(t);
            ++facet;
            state = State::Solid;
            break;
        }
    }
    if (state != State::Outside) throw InputError(src, "parse error: the file ends inside a solid (truncated? no 'endsolid')");
    return mesh;
}

Mesh readStl(const std::string& src, std::string_view data) {
    if (data.empty()) throw InputError(src, "empty file");
    if (data.size() >= 84) {
        uint32_t facets;
        unsigned char b[4];
        std::memcpy(b, data.data() + 80, 4);
        if constexpr (std::endian::native == std::endian::big) std::reverse(b, b + 4);
        std::memcpy(&facets, b, 4);
        // A binary STL is exactly 84 + 50 n bytes, even when its header starts with "solid".
        if (84 + 50ull * facets == data.size()) {
            if (facets == 0) throw InputError(src, "mesh has zero triangles (binary STL with 0 facets)");
            return readStlBinary(src, data, facets);
        }
    }
    size_t i = 0;
    while (i < data.size() && std::isspace(static_cast<unsigned char>(data[i]))) ++i;
    if (!keywordIs(data.substr(i, 5), "solid"))
        throw InputError(src, "parse error: neither an ascii STL (no 'solid') nor a binary STL (" + std::to_string(data.size()) +
                                  " bytes is not 84 + 50 x the facet count in its header; truncated?)");
    return readStlAscii(src, data);
}

// ---------------------------------------------------------------------------------------------
// Writing: build the bytes, write them to a temporary file beside the target, rename.

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

template <class T>
void appendLe(std::string& out, T value) {
    unsigned char b[sizeof(T)];
    std::memcpy(b, &value, sizeof(T));
    if constexpr (std::endian::native == std::endian::big) std::reverse(b, b + sizeof(T));
    out.append(reinterpret_cast<const char*>(b), sizeof(T));
}

void checkIndices(const Mesh& mesh) {
    for (const Triangle& t : mesh.triangles)
        for (uint32_t v : t) CULLIDE_CHECK(v < mesh.positions.size(), "writing a mesh with a triangle index out of range");
}

}  // namespace

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
    case MeshFormat::Obj: mesh = readObj(src, data); break;
    case MeshFormat::Off: mesh = readOff(src, data); break;
    case MeshFormat::Ply: mesh = readPly(src, data); break;
    case MeshFormat::Stl: mesh = readStl(src, data); break;
    }
    validateMesh(mesh, src);
    return mesh;
}

void writePly(const Mesh& mesh, const fs::path& path, const PlyWriteOptions& options) {
    CULLIDE_CHECK(options.faceColours.empty() || options.faceColours.size() == mesh.triangles.size(),
                  "writePly: faceColours must be empty or one per triangle");
    checkIndices(mesh);
    const bool colours = !options.faceColours.empty();
    std::string out;
    out.reserve(128 + mesh.positions.size() * (options.binary ? 12 : 36) + mesh.triangles.size() * (options.binary ? 16 : 40));
    out += "ply\nformat ";
    out += options.binary ? "binary_little_endian" : "ascii";
    out += " 1.0\ncomment written by cullide\nelement vertex ";
    appendUint(out, mesh.positions.size());
    out += "\nproperty float x\nproperty float y\nproperty float z\nelement face ";
    appendUint(out, mesh.triangles.size());
    out += "\nproperty list uchar uint vertex_indices\n";
    if (colours) out += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    out += "end_header\n";
    if (options.binary) {
        for (const Vec3f& p : mesh.positions)
            for (int k = 0; k < 3; ++k) appendLe(out, p[k]);
        for (size_t i = 0; i < mesh.triangles.size(); ++i) {
            out += static_cast<char>(3);
            for (uint32_t v : mesh.triangles[i]) appendLe(out, v);
            if (colours)
                for (uint8_t c : options.faceColours[i]) out += static_cast<char>(c);
        }
    } else {
        for (const Vec3f& p : mesh.positions) {
            appendFloat(out, p.x()); out += ' ';
            appendFloat(out, p.y()); out += ' ';
            appendFloat(out, p.z()); out += '\n';
        }
        for (size_t i = 0; i < mesh.triangles.size(); ++i) {
            out += '3';
            for (uint32_t v : mesh.triangles[i]) { out += ' '; appendUint(out, v); }
            if (colours)
                for (uint8_t c : options.faceColours[i]) { out += ' '; appendUint(out, c); }
            out += '\n';
        }
    }
    writeFileAtomically(path, out);
}

void writeOff(const Mesh& mesh, const fs::path& path) {
    checkIndices(mesh);
    std::string out;
    out.reserve(32 + mesh.positions.size() * 36 + mesh.triangles.size() * 24);
    out += "OFF\n";
    appendUint(out, mesh.positions.size()); out += ' ';
    appendUint(out, mesh.triangles.size()); out += " 0\n";
    for (const Vec3f& p : mesh.positions) {
        appendFloat(out, p.x()); out += ' ';
        appendFloat(out, p.y()); out += ' ';
        appendFloat(out, p.z()); out += '\n';
    }
    for (const Triangle& t : mesh.triangles) {
        out += '3';
        for (uint32_t v : t) { out += ' '; appendUint(out, v); }
        out += '\n';
    }
    writeFileAtomically(path, out);
}

}  // namespace cullide
