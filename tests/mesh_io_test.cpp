// Tests for mesh_io: what every loader must keep (indices, face order, fan triangulation), what it
// must refuse (each bad-input class under tests/data/bad), and that the writers round-trip exactly.
#include "cullide/error.h"
#include "cullide/mesh_io.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <random>
#include <sstream>

namespace cullide {
namespace {

using test::TempDir;
using test::testData;

// The geometry of tests/data/good/polys.* (see tests/data/make_io_data.py).
const std::vector<Vec3f> kPolyPositions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0},   {0, 1, 0},
                                           {2, 0, 0}, {2, 1, 0}, {3, 0.5f, 0}};
// Faces (4 5 1), (0 1 2 3), (1 4 6 5 2), fan-triangulated in place.
const std::vector<Triangle> kPolyTriangles = {{4, 5, 1}, {0, 1, 2}, {0, 2, 3}, {1, 4, 6}, {1, 6, 5}, {1, 5, 2}};

const auto slurp = test::readBytes;
const auto spit = test::writeBytes;

bool bitEqual(const Mesh& a, const Mesh& b) {
    if (a.triangles != b.triangles || a.positions.size() != b.positions.size()) return false;
    for (size_t i = 0; i < a.positions.size(); ++i)
        for (int k = 0; k < 3; ++k)
            if (std::bit_cast<uint32_t>(a.positions[i][k]) != std::bit_cast<uint32_t>(b.positions[i][k])) return false;
    return true;
}

// Trap: a loader that renumbers vertices (by first use), reorders faces, drops the polygon's
// extra vertices or triangulates other than as a fan. The faces use the vertices out of order,
// the quad and the pentagon must come out as n-2 consecutive fan triangles, for every format
// (OBJ with a group switch, v/vt/vn references and negative indices; PLY with an extra vertex
// property; big-endian binary PLY).
class MeshIoPolys : public ::testing::TestWithParam<const char*> {};

TEST_P(MeshIoPolys, KeepsFileIndicesFaceOrderAndFansPolygons) {
    const Mesh m = loadMesh(testData(GetParam()));
    EXPECT_EQ(m.positions, kPolyPositions);
    EXPECT_EQ(m.triangles, kPolyTriangles);
}

INSTANTIATE_TEST_SUITE_P(MeshIo, MeshIoPolys,
                         ::testing::Values("good/polys.off", "good/polys.obj", "good/polys_ascii.ply",
                                           "good/polys_binary.ply", "good/polys_binary_be.ply"));

// Trap: STL has no indices. Welding must be on bit-identical positions in first-occurrence order
// (not a hash map's order, not a tolerance), so a closed cube gets back 8 vertices and triangle i
// is still facet i with its corners in file order. Ascii and binary must agree.
TEST(MeshIo, StlWeldsBitIdenticalCornersInFirstOccurrenceOrder) {
    const std::vector<Vec3f> cube = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                     {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
    const std::vector<Triangle> facets = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                                          {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
    // Expected: weld by hand in first-occurrence order.
    Mesh expected;
    std::map<int, uint32_t> seen;
    for (const Triangle& f : facets) {
        Triangle t;
        for (int k = 0; k < 3; ++k) {
            auto [it, inserted] =
                seen.try_emplace(static_cast<int>(f[k]), static_cast<uint32_t>(expected.positions.size()));
            if (inserted) expected.positions.push_back(cube[f[k]]);
            t[k] = it->second;
        }
        expected.triangles.push_back(t);
    }
    for (const char* file : {"good/cube_ascii.stl", "good/cube_binary.stl"}) {
        SCOPED_TRACE(file);
        const Mesh m = loadMesh(testData(file));
        EXPECT_EQ(m.positions.size(), 8u);
        EXPECT_TRUE(bitEqual(m, expected));
    }
}

// Trap: STL welding by value (==) would merge -0.0 with 0.0; the contract says bit-identical.
TEST(MeshIo, StlDoesNotWeldNegativeZeroWithZero) {
    TempDir dir;
    std::string b(80, ' ');
    auto put = [&](float x) {
        char c[4];
        std::memcpy(c, &x, 4);
        b.append(c, 4);
    };
    const uint32_t n = 2;
    b.append(reinterpret_cast<const char*>(&n), 4);
    const float tris[2][9] = {{0, 0, 0, 1, 0, 0, 0, 1, 0}, {-0.0f, 0, 0, 1, 0, 0, 0, 1, 0}};
    for (const auto& t : tris) {
        for (int k = 0; k < 3; ++k) put(0);
        for (float x : t) put(x);
        b.append(2, '\0');
    }
    spit(dir / "z.stl", b);
    const Mesh m = loadMesh(dir / "z.stl");
    EXPECT_EQ(m.positions.size(), 4u);
    EXPECT_EQ(m.triangles[1], (Triangle{3, 1, 2}));
}

struct BadCase {
    const char* file;
    const char* cause;  // a substring the message must contain
};

// Trap: every bad-input class must be refused with InputError whose message starts with the file
// path and states the cause; in particular the cases assimp and tinyobjloader accept silently
// (out-of-range index clamped, negative index mapped to 0, 2-vertex face dropped, 4th STL vertex
// dropped, truncated binary PLY read past its end, NaN/Inf, numbers that overflow float).
class MeshIoBad : public ::testing::TestWithParam<BadCase> {};

TEST_P(MeshIoBad, ThrowsInputErrorNamingFileAndCause) {
    const std::string path = testData(GetParam().file);
    try {
        const Mesh m = loadMesh(path);
        FAIL() << "loaded " << m.triangleCount() << " triangles from " << path;
    } catch (const InputError& e) {
        const std::string what = e.what();
        EXPECT_EQ(what.rfind(path + ": ", 0), 0u) << what;
        EXPECT_EQ(e.source(), path);
        EXPECT_NE(what.find(GetParam().cause), std::string::npos) << what;
    }
}

INSTANTIATE_TEST_SUITE_P(
    MeshIo, MeshIoBad,
    ::testing::Values(
        BadCase{"bad/does_not_exist.off", "no such file"}, BadCase{"bad/a_directory.off", "directory"},
        BadCase{"bad/unknown_extension.xyz", "unknown mesh format"},
        BadCase{"bad/parse_error.obj", "line 2: parse error"}, BadCase{"bad/parse_error.off", "line 4: parse error"},
        BadCase{"bad/parse_error.ply", "unknown header line"}, BadCase{"bad/parse_error.stl", "parse error"},
        BadCase{"bad/truncated_binary.ply", "truncated"}, BadCase{"bad/nan.off", "non-finite"},
        BadCase{"bad/inf.off", "non-finite"}, BadCase{"bad/nan_binary.ply", "non-finite"},
        BadCase{"bad/overflow.obj", "non-finite"}, BadCase{"bad/index_out_of_range.off", "out of range"},
        BadCase{"bad/index_out_of_range.obj", "out of range"},
        BadCase{"bad/negative_index.off", "negative vertex index"},
        BadCase{"bad/negative_index.obj", "before the first vertex"}, BadCase{"bad/empty.off", "empty file"},
        BadCase{"bad/empty.obj", "empty file"}, BadCase{"bad/empty.stl", "empty file"},
        BadCase{"bad/zero_triangles.off", "zero triangles"}, BadCase{"bad/zero_triangles.obj", "zero triangles"},
        BadCase{"bad/two_vertex_face.off", "at least 3"}, BadCase{"bad/two_vertex_face.obj", "at least 3"},
        BadCase{"bad/four_vertex_facet.stl", "exactly 3"},
        BadCase{"bad/fewer_faces_than_header.off", "ends before face 1"}),
    // Stable, readable names (the default prints the pointers, which change with ASLR and make
    // CTest's discovered names miss the tests).
    [](const auto& param) { return cullide::test::paramName(param.param.file); });

// Trap: a lying header count must not make the reader allocate for it (or loop over it).
TEST(MeshIo, HugeHeaderCountsFailFastWithoutAllocating) {
    TempDir dir;
    spit(dir / "a.off", "OFF\n3000000000 1 0\n0 0 0\n");
    EXPECT_THROW(loadMesh(dir / "a.off"), InputError);
    spit(dir / "b.off", "OFF\n2000000000 2000000000 0\n0 0 0\n");
    EXPECT_THROW(loadMesh(dir / "b.off"), InputError);
    spit(dir / "c.ply",
         "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\nproperty float "
         "y\nproperty float z\n"
         "element face 1\nproperty list uint int vertex_indices\nelement junk 1000000000000\nend_header\n");
    EXPECT_THROW(loadMesh(dir / "c.ply"), InputError);
    spit(dir / "d.ply",
         "ply\nformat binary_little_endian 1.0\nelement junk 1000000000000000\nelement vertex 0\nproperty float "
         "x\nproperty float y\n"
         "property float z\nelement face 0\nproperty list uint int vertex_indices\nend_header\n");
    EXPECT_THROW(loadMesh(dir / "d.ply"), InputError);
}

// Trap: tinyobjloader stores a face's vertex count in an unsigned char, so a 300-gon would come
// back truncated; the loader must notice the disagreement with its own scan and refuse.
TEST(MeshIo, ObjFaceLongerThanTinyobjloaderCanHoldIsRefused) {
    TempDir dir;
    std::string obj;
    for (int i = 0; i < 300; ++i) {
        obj += "v ";
        obj += std::to_string(std::cos(i * 0.02));
        obj += ' ';
        obj += std::to_string(std::sin(i * 0.02));
        obj += " 0\n";
    }
    obj += "f";
    for (int i = 1; i <= 300; ++i) {
        obj += ' ';
        obj += std::to_string(i);
    }
    obj += "\n";
    spit(dir / "big.obj", obj);
    try {
        (void)loadMesh(dir / "big.obj");
        FAIL();
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("refusing"), std::string::npos) << e.what();
    }
}

// Trap: extensions in upper case are still meshes; anything else is refused by name.
TEST(MeshIo, FormatFromExtensionIgnoresCase) {
    EXPECT_EQ(meshFormatFromPath("a/B.OFF"), MeshFormat::Off);
    EXPECT_EQ(meshFormatFromPath("x.Ply"), MeshFormat::Ply);
    EXPECT_EQ(meshFormatFromPath("x.sTl"), MeshFormat::Stl);
    EXPECT_EQ(meshFormatFromPath("x.obj"), MeshFormat::Obj);
    EXPECT_THROW(meshFormatFromPath("x.off.gz"), InputError);
    EXPECT_THROW(meshFormatFromPath("noext"), InputError);
}

// Random floats covering what %.9g and from_chars must get exactly right: subnormals, huge and
// tiny magnitudes, -0.0, values with 9 significant digits.
Mesh randomMesh(uint32_t seed, size_t nv, size_t nt) {
    std::mt19937 rng(seed);
    Mesh m;
    for (size_t i = 0; i < nv; ++i) {
        Vec3f p;
        for (int k = 0; k < 3; ++k) {
            uint32_t bits;
            do bits = rng();
            while (!std::isfinite(std::bit_cast<float>(bits)));
            p[k] = std::bit_cast<float>(bits);
        }
        if (i == 0) p = Vec3f(-0.0f, std::numeric_limits<float>::denorm_min(), std::numeric_limits<float>::max());
        if (i == 1) p = Vec3f(0.1f, -std::numeric_limits<float>::min(), 16777217.0f);
        m.positions.push_back(p);
    }
    for (size_t i = 0; i < nt; ++i)
        m.triangles.push_back(
            {static_cast<uint32_t>(rng() % nv), static_cast<uint32_t>(rng() % nv), static_cast<uint32_t>(rng() % nv)});
    return m;
}

// Trap: float printing or parsing that is not round-trip exact (assimp's fast_atof is not), or a
// writer that reorders anything. Every bit of every coordinate must come back, for OFF, ascii
// PLY and binary PLY.
TEST(MeshIo, WriteThenReadIsBitExact) {
    TempDir dir;
    const Mesh m = randomMesh(20240611, 3000, 4000);
    writeOff(m, dir / "m.off");
    EXPECT_TRUE(bitEqual(loadMesh(dir / "m.off"), m));
    writePly(m, dir / "b.ply");
    EXPECT_TRUE(bitEqual(loadMesh(dir / "b.ply"), m));
    writePly(m, dir / "a.ply", {.binary = false, .faceColours = {}});
    EXPECT_TRUE(bitEqual(loadMesh(dir / "a.ply"), m));
}

// Trap: output that depends on locale, uninitialised memory or anything but the mesh: the same
// mesh gives the same bytes, and the OFF text is exactly what the format says.
TEST(MeshIo, WritersAreDeterministic) {
    TempDir dir;
    Mesh m;
    m.positions = {{0, 0, 0}, {0.1f, 1e-7f, -2.5f}, {1e30f, -0.0f, 3}};
    m.triangles = {{0, 1, 2}};
    writeOff(m, dir / "a.off");
    EXPECT_EQ(slurp(dir / "a.off"),
              "OFF\n3 1 0\n0 0 0\n0.100000001 1.00000001e-07 -2.5\n1.00000002e+30 -0 3\n3 0 1 2\n");
    writeOff(m, dir / "b.off");
    EXPECT_EQ(slurp(dir / "a.off"), slurp(dir / "b.off"));
    writePly(m, dir / "a.ply");
    writePly(m, dir / "b.ply");
    EXPECT_EQ(slurp(dir / "a.ply"), slurp(dir / "b.ply"));
}

// Trap: colours written on the vertex element, or in another order, or not at all. They must be
// `property uchar red/green/blue` on the face element, one per triangle, readable back (the
// reader skips them) in both encodings.
TEST(MeshIo, PlyWritesPerFaceColours) {
    TempDir dir;
    Mesh m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
    m.triangles = {{0, 1, 2}, {1, 3, 2}};
    const std::vector<Rgb8> colours = {{255, 0, 16}, {1, 2, 3}};
    writePly(m, dir / "a.ply", {.binary = false, .faceColours = colours});
    const std::string text = slurp(dir / "a.ply");
    EXPECT_NE(
        text.find("element face 2\nproperty list uchar uint vertex_indices\nproperty uchar red\nproperty uchar green\n"
                  "property uchar blue\nend_header\n"),
        std::string::npos)
        << text;
    EXPECT_NE(text.find("\n3 0 1 2 255 0 16\n3 1 3 2 1 2 3\n"), std::string::npos) << text;
    EXPECT_EQ(loadMesh(dir / "a.ply"), m);

    writePly(m, dir / "b.ply", {.binary = true, .faceColours = colours});
    const std::string bin = slurp(dir / "b.ply");
    ASSERT_GE(bin.size(), 16u);
    EXPECT_EQ(bin.substr(bin.size() - 3), std::string("\x01\x02\x03", 3));
    EXPECT_EQ(bin.substr(bin.size() - 16 - 3, 3), std::string("\xff\x00\x10", 3));
    EXPECT_EQ(loadMesh(dir / "b.ply"), m);
}

// Trap: a failed write that leaves a half-written target or a stray temporary file behind, or
// an error message that does not name the file.
TEST(MeshIo, FailedWriteLeavesNoFile) {
    TempDir dir;
    Mesh m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    m.triangles = {{0, 1, 2}};
    const auto missingDir = dir / "no_such_folder" / "m.off";
    try {
        writeOff(m, missingDir);
        FAIL();
    } catch (const InputError& e) {
        EXPECT_EQ(std::string(e.what()).rfind(missingDir.string(), 0), 0u);
    }
    EXPECT_FALSE(std::filesystem::exists(missingDir));
    // The target is a folder: the temporary is written, the rename fails, the temporary goes.
    std::filesystem::create_directory(dir / "taken.ply");
    EXPECT_THROW(writePly(m, dir / "taken.ply"), InputError);
    size_t entries = 0;
    for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir.path())) ++entries;
    EXPECT_EQ(entries, 1u);  // only taken.ply itself
}

// Trap: a parser that crashes, hangs, reads out of bounds or returns an invalid mesh on damaged
// input. A fixed-seed mutation of every good file (bit flips, truncations, inserted junk, repeated
// chunks) must give either a valid mesh or InputError. (The libFuzzer harnesses in tests/fuzz do
// this at scale; this keeps a deterministic slice of it in every test run.)
TEST(MeshIo, MutatedFilesLoadOrThrowInputErrorNeverCrash) {
    TempDir dir;
    std::mt19937 rng(1234567);
    const char* files[] = {"good/polys.off",        "good/polys.obj",           "good/polys_ascii.ply",
                           "good/polys_binary.ply", "good/polys_binary_be.ply", "good/cube_ascii.stl",
                           "good/cube_binary.stl",  "good/degenerate.off"};
    const char* junk[] = {"-1", "nan", "1e39", "\n",           " ",     "4294967295", "999999999999",
                          "#",  "/",   "\0",   "end_header\n", "solid", "3"};
    size_t loaded = 0, refused = 0;
    for (const char* file : files) {
        const std::string original = slurp(testData(file));
        const std::string ext = std::filesystem::path(file).extension().string();
        for (int i = 0; i < 60; ++i) {
            std::string s = original;
            const int edits = 1 + static_cast<int>(rng() % 3);
            for (int e = 0; e < edits && !s.empty(); ++e) {
                const size_t at = rng() % s.size();
                switch (rng() % 4) {
                    case 0: s[at] = static_cast<char>(s[at] ^ (1 << (rng() % 8))); break;
                    case 1: s.resize(at); break;
                    case 2: s.insert(at, junk[rng() % std::size(junk)]); break;
                    case 3: s.insert(at, s.substr(at, rng() % 16)); break;
                }
            }
            std::string name = std::to_string(i);  // (not "m" + ...: GCC 12's -Wrestrict false positive)
            name += ext;
            const auto path = dir / name;
            spit(path, s);
            try {
                const Mesh m = loadMesh(path);
                EXPECT_NO_THROW(validateMesh(m, path.string()));
                ++loaded;
            } catch (const InputError& e) {
                EXPECT_EQ(std::string(e.what()).rfind(path.string(), 0), 0u) << e.what();
                ++refused;
            }
        }
    }
    EXPECT_EQ(loaded + refused, 480u);
    EXPECT_GT(refused, 0u);
}

}  // namespace
}  // namespace cullide
