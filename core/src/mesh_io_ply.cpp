// Mesh input and output, PLY (see mesh_io.cpp for the choice of parsers).
#include "cullide/mesh_io.h"

#include "cullide/file_io.h"
#include "mesh_io_detail.h"

#include <algorithm>
#include <bit>
#include <cstring>
#include <string>
#include <string_view>
#include <utility>

namespace cullide::meshio {
namespace {

// ---------------------------------------------------------------------------------------------
// PLY (ascii, binary_little_endian, binary_big_endian). Needs element "vertex" with scalar x, y, z
// and element "face" with a list "vertex_indices" (or "vertex_index") of integers. Other
// elements and properties are read past and ignored.

enum class PlyType { I8, U8, I16, U16, I32, U32, F32, F64 };

bool plyTypeFromName(std::string_view n, PlyType& t) {
    static const std::pair<std::string_view, PlyType> names[] = {
        {"char", PlyType::I8},   {"int8", PlyType::I8},     {"uchar", PlyType::U8},   {"uint8", PlyType::U8},
        {"short", PlyType::I16}, {"int16", PlyType::I16},   {"ushort", PlyType::U16}, {"uint16", PlyType::U16},
        {"int", PlyType::I32},   {"int32", PlyType::I32},   {"uint", PlyType::U32},   {"uint32", PlyType::U32},
        {"float", PlyType::F32}, {"float32", PlyType::F32}, {"double", PlyType::F64}, {"float64", PlyType::F64}};
    for (const auto& [name, type] : names)
        if (n == name) {
            t = type;
            return true;
        }
    return false;
}

size_t plyTypeSize(PlyType t) {
    switch (t) {
        case PlyType::I8:
        case PlyType::U8: return 1;
        case PlyType::I16:
        case PlyType::U16: return 2;
        case PlyType::I32:
        case PlyType::U32:
        case PlyType::F32: return 4;
        case PlyType::F64: return 8;
    }
    return 0;
}

bool plyTypeIsInteger(PlyType t) {
    return t != PlyType::F32 && t != PlyType::F64;
}

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
    float f = 0;  // for F32
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
        while (e < body_.size() &&
               !(body_[e] == ' ' || body_[e] == '\t' || body_[e] == '\n' || body_[e] == '\r' || body_[e] == '\f' ||
                 body_[e] == '\v'))
            ++e;
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
                throw InputError(src_,
                                 atLine(line_) + "parse error: " + quote(tok) + " is not an integer (" + what + ")");
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
        if (body_.size() - pos_ < n)
            throw InputError(src_, "the file ends inside " + what + " (truncated binary data)");
        unsigned char b[8];
        std::memcpy(b, body_.data() + pos_, n);
        pos_ += n;
        if (big_ != (std::endian::native == std::endian::big)) std::reverse(b, b + n);
        PlyValue v;
        switch (t) {
            case PlyType::I8: {
                int8_t x;
                std::memcpy(&x, b, 1);
                v.i = x;
                break;
            }
            case PlyType::U8: {
                uint8_t x;
                std::memcpy(&x, b, 1);
                v.i = x;
                break;
            }
            case PlyType::I16: {
                int16_t x;
                std::memcpy(&x, b, 2);
                v.i = x;
                break;
            }
            case PlyType::U16: {
                uint16_t x;
                std::memcpy(&x, b, 2);
                v.i = x;
                break;
            }
            case PlyType::I32: {
                int32_t x;
                std::memcpy(&x, b, 4);
                v.i = x;
                break;
            }
            case PlyType::U32: {
                uint32_t x;
                std::memcpy(&x, b, 4);
                v.i = x;
                break;
            }
            case PlyType::F32:
                v.isInteger = false;
                v.isF32 = true;
                std::memcpy(&v.f, b, 4);
                break;
            case PlyType::F64:
                v.isInteger = false;
                std::memcpy(&v.d, b, 8);
                break;
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

template <class T>
void appendLe(std::string& out, T value) {
    unsigned char b[sizeof(T)];
    std::memcpy(b, &value, sizeof(T));
    if constexpr (std::endian::native == std::endian::big) std::reverse(b, b + sizeof(T));
    out.append(reinterpret_cast<const char*>(b), sizeof(T));
}

enum class PlyFormat { None, Ascii, Le, Be };

struct PlyHeader {
    PlyFormat format = PlyFormat::None;
    std::vector<PlyElement> elements;
    size_t bodyStart = 0;  // the body's first byte
    size_t endLine = 0;  // end_header's line number
};

// A "format" line's format.
PlyFormat plyFormat(const std::string& src, const std::vector<std::string_view>& tok, size_t lineNumber) {
    if (tok.size() != 3 || tok[2] != "1.0")
        throw InputError(
            src,
            atLine(lineNumber) + "parse error: expected 'format <ascii|binary_little_endian|binary_big_endian> 1.0'");
    if (tok[1] == "ascii") return PlyFormat::Ascii;
    if (tok[1] == "binary_little_endian") return PlyFormat::Le;
    if (tok[1] == "binary_big_endian") return PlyFormat::Be;
    throw InputError(src, atLine(lineNumber) + "unknown PLY format " + quote(tok[1]));
}

// An "element" line: a new element, its name not declared before.
void addPlyElement(const std::string& src, const std::vector<std::string_view>& tok, size_t lineNumber,
                   std::vector<PlyElement>& elements) {
    long long count;
    if (tok.size() != 3 || !parseIntToken(tok[2], count) || count < 0)
        throw InputError(src, atLine(lineNumber) + "parse error: expected 'element <name> <count>'");
    for (const PlyElement& e : elements)
        if (e.name == tok[1])
            throw InputError(src, atLine(lineNumber) + "element " + quote(tok[1]) + " is declared twice");
    elements.push_back({std::string(tok[1]), static_cast<unsigned long long>(count), {}});
}

// A "property" line: a scalar or list property of the last element, its name not declared before.
void addPlyProperty(const std::string& src, const std::vector<std::string_view>& tok, size_t lineNumber,
                    std::vector<PlyElement>& elements) {
    if (elements.empty()) throw InputError(src, atLine(lineNumber) + "parse error: property before any element");
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
    if (!ok) throw InputError(src, atLine(lineNumber) + "parse error: bad property declaration");
    for (const PlyProperty& q : elements.back().properties)
        if (q.name == p.name)
            throw InputError(src, atLine(lineNumber) + "property " + quote(p.name) + " is declared twice");
    elements.back().properties.push_back(p);
}

// The header, from the "ply" magic line to end_header.
PlyHeader readPlyHeader(const std::string& src, std::string_view data) {
    LineReader lines(data);
    Line line;
    std::vector<std::string_view> tok;
    if (!lines.next(line) || line.text != "ply")
        throw InputError(src, "parse error: not a PLY file (no 'ply' magic line)");
    PlyHeader header;
    bool ended = false;
    while (!ended && lines.next(line)) {
        splitTokens(line.text, tok);
        if (tok.empty()) continue;
        const std::string_view kw = tok[0];
        if (kw == "comment" || kw == "obj_info") continue;
        if (kw == "format") {
            header.format = plyFormat(src, tok, line.number);
        } else if (kw == "element") {
            addPlyElement(src, tok, line.number, header.elements);
        } else if (kw == "property") {
            addPlyProperty(src, tok, line.number, header.elements);
        } else if (kw == "end_header") {
            if (tok.size() != 1) throw InputError(src, atLine(line.number) + "parse error: junk after end_header");
            ended = true;
        } else {
            throw InputError(src, atLine(line.number) + "parse error: unknown header line " + quote(kw));
        }
    }
    if (!ended) throw InputError(src, "parse error: the header has no end_header line (truncated?)");
    if (header.format == PlyFormat::None) throw InputError(src, "parse error: the header has no format line");
    header.bodyStart = lines.position();
    header.endLine = line.number;
    return header;
}

// Where the mesh is in the elements: the vertex element and its x, y, z properties, the face
// element and its index list.
struct PlyLayout {
    const PlyElement* vertexEl = nullptr;
    const PlyElement* faceEl = nullptr;
    int px = -1, py = -1, pz = -1, plist = -1;
};

PlyLayout locateMesh(const std::string& src, const std::vector<PlyElement>& elements) {
    PlyLayout l;
    for (const PlyElement& e : elements) {
        if (e.name == "vertex") {
            l.vertexEl = &e;
            for (size_t i = 0; i < e.properties.size(); ++i) {
                const PlyProperty& p = e.properties[i];
                int* slot = p.name == "x" ? &l.px : p.name == "y" ? &l.py : p.name == "z" ? &l.pz : nullptr;
                if (slot) {
                    if (p.isList)
                        throw InputError(src, "vertex property " + quote(p.name) + " is a list, expected a scalar");
                    *slot = static_cast<int>(i);
                }
            }
        } else if (e.name == "face") {
            l.faceEl = &e;
            for (size_t i = 0; i < e.properties.size(); ++i) {
                const PlyProperty& p = e.properties[i];
                if (p.name == "vertex_indices" || p.name == "vertex_index") {
                    if (l.plist >= 0) throw InputError(src, "face element has both vertex_indices and vertex_index");
                    if (!p.isList || !plyTypeIsInteger(p.type))
                        throw InputError(src, "face property " + quote(p.name) + " must be a list of integers");
                    l.plist = static_cast<int>(i);
                }
            }
        }
    }
    if (!l.vertexEl) throw InputError(src, "no 'vertex' element");
    if (l.px < 0 || l.py < 0 || l.pz < 0) throw InputError(src, "the vertex element lacks an x, y or z property");
    if (!l.faceEl) throw InputError(src, "no 'face' element (zero triangles)");
    if (l.plist < 0) throw InputError(src, "the face element has no vertex_indices list");
    if (l.vertexEl->count > kMaxVertices)
        throw InputError(src, "too many vertices (" + std::to_string(l.vertexEl->count) + ")");
    return l;
}

// One list property of item i: its values read, and when they are a face's indices (`indices`),
// checked and its fan added to the mesh. `face`: scratch.
void readPlyList(const std::string& src, PlyBody& in, const PlyProperty& prop, const std::string& what,
                 unsigned long long i, bool indices, unsigned long long vertexCount, Mesh& mesh,
                 std::vector<uint32_t>& face) {
    const PlyValue c = in.read(prop.countType, what + " (list length)");
    if (c.i < 0) throw InputError(src, what + ": negative list length");
    if (indices && c.i < 3)
        throw InputError(
            src, "face " + std::to_string(i) + " has " + std::to_string(c.i) + " vertices; a face needs at least 3");
    face.clear();
    for (long long j = 0; j < c.i; ++j) {
        const PlyValue v = in.read(prop.type, what);
        if (!indices) continue;
        if (v.i < 0)
            throw InputError(src, "face " + std::to_string(i) + " has a negative vertex index " + std::to_string(v.i));
        if (static_cast<unsigned long long>(v.i) >= vertexCount)
            throw InputError(src,
                             "face " + std::to_string(i) + " refers to vertex " + std::to_string(v.i) +
                                 ", but the file has only " + std::to_string(vertexCount) +
                                 " vertices (index out of range)");
        face.push_back(static_cast<uint32_t>(v.i));
    }
    if (indices) addFan(mesh, face.data(), face.size());
}

// The items of one element: a vertex element's positions and a face element's triangles into the
// mesh, every other value read past.
void readPlyElement(const std::string& src, PlyBody& in, const PlyElement& e, const PlyLayout& l, Mesh& mesh,
                    std::vector<uint32_t>& face) {
    const bool isVertex = &e == l.vertexEl;
    const bool isFace = &e == l.faceEl;
    for (unsigned long long i = 0; i < e.count; ++i) {
        Vec3f p = Vec3f::Zero();
        for (size_t k = 0; k < e.properties.size(); ++k) {
            const PlyProperty& prop = e.properties[k];
            const std::string what = "element '" + e.name + "' " + std::to_string(i) + ", property '" + prop.name + "'";
            if (!prop.isList) {
                const PlyValue v = in.read(prop.type, what);
                if (isVertex) {
                    if (static_cast<int>(k) == l.px) p.x() = plyValueAsFloat(v);
                    if (static_cast<int>(k) == l.py) p.y() = plyValueAsFloat(v);
                    if (static_cast<int>(k) == l.pz) p.z() = plyValueAsFloat(v);
                }
                continue;
            }
            const bool indices = isFace && static_cast<int>(k) == l.plist;
            readPlyList(src, in, prop, what, i, indices, l.vertexEl->count, mesh, face);
        }
        if (isVertex) mesh.positions.push_back(p);
    }
}

}  // namespace

Mesh readPly(const std::string& src, std::string_view data) {
    if (onlyWhitespace(data)) throw InputError(src, "empty file");
    const PlyHeader header = readPlyHeader(src, data);
    const PlyLayout layout = locateMesh(src, header.elements);
    const std::string_view body = data.substr(header.bodyStart);
    const bool ascii = header.format == PlyFormat::Ascii;
    PlyBody in(src, body, ascii, header.format == PlyFormat::Be, header.endLine + 1);
    Mesh mesh;
    std::vector<uint32_t> face;
    for (const PlyElement& e : header.elements) {
        if (&e == layout.vertexEl) mesh.positions.reserve(boundedReserve(e.count, body.size(), ascii ? 6 : 3));
        if (&e == layout.faceEl) mesh.triangles.reserve(boundedReserve(e.count, body.size(), ascii ? 8 : 4));
        if (e.properties.empty()) continue;  // nothing to read, whatever the count says
        readPlyElement(src, in, e, layout, mesh, face);
    }
    in.finish();
    return mesh;
}

}  // namespace cullide::meshio

namespace cullide {

namespace fs = std::filesystem;
using namespace meshio;

void writePly(const Mesh& mesh, const fs::path& path, const PlyWriteOptions& options) {
    CULLIDE_CHECK(options.faceColours.empty() || options.faceColours.size() == mesh.triangles.size(),
                  "writePly: faceColours must be empty or one per triangle");
    checkIndices(mesh);
    const bool colours = !options.faceColours.empty();
    std::string out;
    out.reserve(128 + mesh.positions.size() * (options.binary ? 12 : 36) +
                mesh.triangles.size() * (options.binary ? 16 : 40));
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
        appendVertexLines(out, mesh);
        for (size_t i = 0; i < mesh.triangles.size(); ++i) {
            appendTriangleIndices(out, mesh.triangles[i]);
            if (colours)
                for (uint8_t c : options.faceColours[i]) {
                    out += ' ';
                    appendUint(out, c);
                }
            out += '\n';
        }
    }
    writeFileAtomically(path, out);
}

}  // namespace cullide
