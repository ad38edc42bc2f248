// Mesh input and output, STL (see mesh_io.cpp for the choice of parsers).
#include "cullide/mesh_io.h"

#include "mesh_io_detail.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <cstring>
#include <map>
#include <string>
#include <string_view>

namespace cullide::meshio {
namespace {

// ---------------------------------------------------------------------------------------------
// STL, ascii or binary, welded on bit-identical positions.

class StlWelder {
public:
    explicit StlWelder(Mesh& mesh) : mesh_(mesh) {}
    uint32_t add(const Vec3f& p) {
        const std::array<uint32_t, 3> key{std::bit_cast<uint32_t>(p.x()), std::bit_cast<uint32_t>(p.y()),
                                          std::bit_cast<uint32_t>(p.z())};
        auto [it, inserted] = index_.try_emplace(key, static_cast<uint32_t>(mesh_.positions.size()));
        if (inserted) mesh_.positions.push_back(p);
        return it->second;
    }

private:
    Mesh& mesh_;
    std::map<std::array<uint32_t, 3>, uint32_t> index_;  // lookups only: the order comes from the file
};

bool keywordIs(std::string_view tok, std::string_view kw) {
    return tok.size() == kw.size() && std::equal(tok.begin(), tok.end(), kw.begin(), [](char a, char b) {
               return std::tolower(static_cast<unsigned char>(a)) == b;
           });
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
            if (!p.allFinite())
                throw InputError(src, "facet " + std::to_string(f) + " has a non-finite coordinate (NaN or Inf)");
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
                    if (parseFloatToken(tok[2 + c], n) == NumStatus::Invalid)
                        fail("parse error: " + quote(tok[2 + c]) + " is not a number");
                }
                state = State::Facet;
                break;
            case State::Facet:
                if (tok.size() != 2 || !keywordIs(kw, "outer") || !keywordIs(tok[1], "loop"))
                    fail("parse error: expected 'outer loop'");
                state = State::Loop;
                corners = 0;
                break;
            case State::Loop:
                if (keywordIs(kw, "endloop")) {
                    if (tok.size() != 1) fail("parse error: junk after 'endloop'");
                    if (corners != 3)
                        fail("facet " + std::to_string(facet) + " has " + std::to_string(corners) +
                             " vertices; every facet needs exactly 3");
                    state = State::EndLoop;
                    break;
                }
                if (!keywordIs(kw, "vertex") || tok.size() != 4)
                    fail("parse error: expected 'vertex <x> <y> <z>' or 'endloop'");
                if (corners == 3)
                    fail("facet " + std::to_string(facet) + " has more than 3 vertices; every facet needs exactly 3");
                {
                    Vec3f p;
                    for (int c = 0; c < 3; ++c) {
                        const NumStatus st = parseFloatToken(tok[1 + c], p[c]);
                        if (st == NumStatus::Invalid) fail("parse error: " + quote(tok[1 + c]) + " is not a number");
                        if (st == NumStatus::OutOfRange || !std::isfinite(p[c]))
                            fail("facet " + std::to_string(facet) + " has a non-finite coordinate " +
                                 quote(tok[1 + c]) + " (NaN, Inf or out of float range)");
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
    if (state != State::Outside)
        throw InputError(src, "parse error: the file ends inside a solid (truncated? no 'endsolid')");
    return mesh;
}

}  // namespace

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
        throw InputError(src,
                         "parse error: neither an ascii STL (no 'solid') nor a binary STL (" +
                             std::to_string(data.size()) +
                             " bytes is not 84 + 50 x the facet count in its header; truncated?)");
    return readStlAscii(src, data);
}

}  // namespace cullide::meshio
