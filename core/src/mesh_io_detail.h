// Helpers shared by the mesh readers and writers of mesh_io*.cpp (one file per format; the
// contract is in cullide/mesh_io.h, the choice of parsers in mesh_io.cpp). Private to core/.
#pragma once

#include "cullide/error.h"
#include "cullide/mesh.h"

#include <cstddef>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

namespace cullide::meshio {

bool onlyWhitespace(std::string_view s);

// ---------------------------------------------------------------------------------------------
// Numbers: whole tokens only, locale-free, correctly rounded.

enum class NumStatus { Ok, Invalid, OutOfRange };

NumStatus parseFloatToken(std::string_view tok, float& out);
NumStatus parseDoubleToken(std::string_view tok, double& out);
bool parseIntToken(std::string_view tok, long long& out);
// The token quoted for a message: at most 40 characters, non-printable ones as '?'.
std::string quote(std::string_view tok);

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

std::string_view stripComment(std::string_view s);
void splitTokens(std::string_view s, std::vector<std::string_view>& out);
std::string atLine(size_t n);

// Appends the fan triangulation (v0 v1 v2, v0 v2 v3, ...) of one polygon.
void addFan(Mesh& mesh, const uint32_t* idx, size_t n);

// Reserve no more than the file could possibly hold, so a lying count cannot exhaust memory.
size_t boundedReserve(unsigned long long count, size_t bytes, size_t minBytesPerItem);

inline constexpr unsigned long long kMaxVertices = std::numeric_limits<uint32_t>::max();

// The readers, one per format (`src` names the file in messages).
Mesh readOff(const std::string& src, std::string_view data);
Mesh readPly(const std::string& src, std::string_view data);
Mesh readObj(const std::string& src, std::string_view data);
Mesh readStl(const std::string& src, std::string_view data);

// ---------------------------------------------------------------------------------------------
// Writing: build the bytes (then writeFileAtomically, cullide/file_io.h).

void appendFloat(std::string& out, float x);  // %.9g, locale-free
void appendUint(std::string& out, unsigned long long x);
void checkIndices(const Mesh& mesh);

// The ascii OFF and PLY bodies: one line "x y z" per vertex.
inline void appendVertexLines(std::string& out, const Mesh& mesh) {
    for (const Vec3f& p : mesh.positions) {
        appendFloat(out, p.x());
        out += ' ';
        appendFloat(out, p.y());
        out += ' ';
        appendFloat(out, p.z());
        out += '\n';
    }
}

// A triangle as an ascii OFF or PLY face, "3 a b c", without the line's end (PLY may add colours).
inline void appendTriangleIndices(std::string& out, const Triangle& t) {
    out += '3';
    for (uint32_t v : t) {
        out += ' ';
        appendUint(out, v);
    }
}

}  // namespace cullide::meshio
