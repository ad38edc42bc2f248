// _cullide: the compiled part of the Python module `cullide` (docs/python.md). numpy in, numpy out.
//
// Conventions
//   - Every array from Python is validated here before it reaches the libraries, which trust
//     validated meshes (an index out of range would read out of bounds): shape, dtype kind,
//     finiteness, index range. Problems raise ValueError naming the argument and the problem;
//     cullide::InputError from the libraries becomes ValueError with its message.
//   - Long calls (loading, pruning, the oracle, studies, backend execution) release the GIL. Nothing
//     calls back into Python while it is released.
//   - prune() does what `cullide prune` does for one frame: parseCullideOptions on the same texts,
//     raster::makeBackend(backend, threads), Animation::sceneAt(frame), runCullide; so the PCS is
//     the command line's bit for bit.
#include "cullide/cullide.h"
#include "cullide/error.h"
#include "cullide/mesh_io.h"
#include "cullide/options.h"
#include "cullide/oracle/oracle.h"
#include "cullide/provenance.h"
#include "cullide/raster/backends.h"
#include "cullide/raster/cpu_backend.h"
#include "cullide/resources.h"
#include "cullide/scene_io.h"
#include "cullide/study/causes.h"
#include "cullide/study/measures.h"
#include "cullide/study/study.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

namespace py = pybind11;
using namespace cullide;

namespace {

[[noreturn]] void fail(const std::string& what) {
    throw py::value_error(what);
}

// A numpy array of the given shape (rows x cols) and dtype, owning a copy of `data`.
template <typename T>
py::array_t<T> makeArray(const std::vector<T>& data, size_t rows, size_t cols) {
    py::array_t<T> a({py::ssize_t(rows), py::ssize_t(cols)});
    if (!data.empty()) std::memcpy(a.mutable_data(), data.data(), data.size() * sizeof(T));
    return a;
}

py::array_t<float> verticesArray(const Mesh& m) {
    std::vector<float> v;
    v.reserve(m.positions.size() * 3);
    for (const Vec3f& p : m.positions) v.insert(v.end(), {p.x(), p.y(), p.z()});
    return makeArray(v, m.positions.size(), 3);
}

py::array_t<uint32_t> facesArray(const Mesh& m) {
    std::vector<uint32_t> f;
    f.reserve(m.triangles.size() * 3);
    for (const Triangle& t : m.triangles) f.insert(f.end(), t.begin(), t.end());
    return makeArray(f, m.triangles.size(), 3);
}

// The array as a C-contiguous array of T, after checking its dtype kind ('f' float, 'i'/'u' integer)
// and shape (rows unknown: -1). `name` names the argument in errors.
py::array checkedArray(const py::handle& obj, const std::string& name, int cols, bool integer) {
    py::array a;
    try {
        a = py::array::ensure(obj);
    } catch (...) {}
    if (!a) fail(name + ": not an array (got " + std::string(py::str(py::type::handle_of(obj).attr("__name__"))) + ")");
    const char kind = a.dtype().kind();
    if (integer && kind != 'i' && kind != 'u')
        fail(name + ": dtype " + std::string(py::str(a.dtype())) + " is not an integer type");
    if (!integer && kind != 'f' && kind != 'i' && kind != 'u')
        fail(name + ": dtype " + std::string(py::str(a.dtype())) + " is not a real number type");
    if (a.ndim() != 2 || a.shape(1) != cols) {
        std::string shape = "(";
        for (py::ssize_t d = 0; d < a.ndim(); ++d) shape += (d ? ", " : "") + std::to_string(a.shape(d));
        shape += a.ndim() == 1 ? ",)" : ")";
        fail(name + ": shape " + shape + " is not (n, " + std::to_string(cols) + ")");
    }
    return a;
}

// (V, F) -> Mesh, validated: V (n,3) real, finite; F (m,3) integers in [0, n).
Mesh meshFromArrays(const py::handle& vertices, const py::handle& faces, const std::string& name) {
    const py::array v = checkedArray(vertices, name + ": vertices", 3, false);
    const py::array f = checkedArray(faces, name + ": faces", 3, true);
    const auto vd = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(v);
    Mesh m;
    m.positions.resize(size_t(v.shape(0)));
    const double* pv = vd.data();
    for (size_t i = 0; i < m.positions.size(); ++i) {
        for (int k = 0; k < 3; ++k) {
            const double x = pv[3 * i + k];
            if (!std::isfinite(x) || !std::isfinite(float(x)))
                fail(name + ": vertices: row " + std::to_string(i) +
                     " has a NaN, infinite or out-of-float-range value");
        }
        m.positions[i] = Vec3f(float(pv[3 * i]), float(pv[3 * i + 1]), float(pv[3 * i + 2]));
    }
    // Indices read as signed 64-bit (uint64 above INT64_MAX wraps negative and is refused too).
    const auto fd = py::array_t<int64_t, py::array::c_style | py::array::forcecast>::ensure(f);
    m.triangles.resize(size_t(f.shape(0)));
    const int64_t* pf = fd.data();
    const int64_t n = int64_t(m.positions.size());
    for (size_t t = 0; t < m.triangles.size(); ++t)
        for (int k = 0; k < 3; ++k) {
            const int64_t idx = pf[3 * t + k];
            if (idx < 0 || idx >= n)
                fail(name + ": faces: row " + std::to_string(t) + " has index " + std::to_string(idx) + " outside 0.." +
                     std::to_string(n - 1) + " (" + std::to_string(n) + " vertices)");
            m.triangles[t][size_t(k)] = uint32_t(idx);
        }
    validateMesh(m, name);
    return m;
}

// (V, F) from either two arrays or one object with .vertices and .faces (trimesh, Open3D-like).
Mesh meshFromPython(const py::object& v, const py::object& f, const std::string& name) {
    if (f.is_none()) {
        if (py::hasattr(v, "vertices") && py::hasattr(v, "faces"))
            return meshFromArrays(v.attr("vertices"), v.attr("faces"), name);
        fail(name + ": give vertices and faces, or one object with .vertices and .faces");
    }
    return meshFromArrays(v, f, name);
}

Transform transformFromPython(const py::object& obj, const std::string& name) {
    Transform t = Transform::Identity();
    if (obj.is_none()) return t;
    const py::array a = checkedArray(obj, name, 4, false);
    if (a.shape(0) != 4) fail(name + ": shape (" + std::to_string(a.shape(0)) + ", 4) is not (4, 4)");
    const auto d = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a);
    const double* p = d.data();
    for (int i = 0; i < 16; ++i)
        if (!std::isfinite(p[i])) fail(name + ": has a NaN or infinite value");
    if (p[12] != 0 || p[13] != 0 || p[14] != 0 || p[15] != 1)
        fail(name + ": the last row must be [0, 0, 0, 1] (an affine transform)");
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) t.matrix()(r, c) = float(p[4 * r + c]);
    return t;
}

// A scene: cullide's Animation (a still scene has no frames).
struct PyScene {
    Animation animation;
    std::string source = "scene";

    Scene at(long frame) const {
        if (frame < 0 || size_t(frame) >= animation.frameCount())
            fail("frame: " + std::to_string(frame) + " is outside 0.." + std::to_string(animation.frameCount() - 1) +
                 " (the scene has " + std::to_string(animation.frameCount()) + " frame(s))");
        return animation.sceneAt(size_t(frame));
    }
};

// What prune() keeps: the run's result plus what check() needs to explain it again.
struct PyResult {
    CullideResult result;
    Scene scene;
    CullideOptions options;
    std::string backend;
    int threads = 0;
    long frame = 0;
};

OptionNames pythonNames() {
    OptionNames n;
    n.method = "argument method";
    n.resolution = "argument resolution";
    n.depth = "argument depth";
    n.directions = "argument directions";
    n.hierarchy = "argument hierarchy";
    n.leafSize = "argument leaf_size";
    n.branching = "argument branching";
    n.views = "argument views";
    n.exactSwitch = "argument exact_switch";
    return n;
}

std::string resolutionText(const py::object& r) {
    if (py::isinstance<py::str>(r)) return r.cast<std::string>();
    if (py::isinstance<py::bool_>(r) || !py::isinstance<py::int_>(r))
        fail("argument resolution: give an integer N or a text 'N', 'WxH', 'auto' or 'auto:K'");
    return std::to_string(r.cast<long long>());
}

uint32_t checkedCount(long long v, const std::string& name) {
    if (v < 0 || v > 4'000'000'000LL) fail(name + ": " + std::to_string(v) + " is out of range");
    return uint32_t(v);
}

int checkedThreads(int threads) {
    if (threads < 0 || threads > 1024) fail("argument threads: " + std::to_string(threads) + " is not 0..1024");
    return threads;
}

std::unique_ptr<DepthBackend> makeBackendChecked(const std::string& name, int threads) {
    if (!raster::isBackendName(name))
        fail("argument backend: '" + name + "' is not a backend (" + raster::backendNameList() + ")");
    if (name != "cpu" && threads != 0) fail("argument threads: applies to backend 'cpu' only");
    return raster::makeBackend(name, threads);
}

PyResult prune(const PyScene& s, const std::string& method, const py::object& resolution, const std::string& depth,
               const std::string& directions, const std::string& hierarchy, long long leafSize, long long branching,
               long long seed, const std::string& backendName, int threads, long frame, const std::string& views,
               const std::string& exactSwitch) {
    OptionText text;
    text.method = method;
    text.resolution = resolutionText(resolution);
    text.depth = depth;
    text.directions = directions;
    text.hierarchy = hierarchy;
    text.views = views;
    text.leafSize = checkedCount(leafSize, "argument leaf_size");
    text.branching = checkedCount(branching, "argument branching");
    if (seed < 0) fail("argument seed: must be >= 0");
    text.seed = uint64_t(seed);
    text.exactSwitch = exactSwitch;
    PyResult r;
    r.options = parseCullideOptions(text, pythonNames());
    r.backend = backendName;
    r.threads = checkedThreads(threads);
    r.frame = frame;
    r.scene = s.at(frame);
    std::unique_ptr<DepthBackend> backend = makeBackendChecked(backendName, threads);
    py::gil_scoped_release release;
    // Auto's cost model reads the scene: given to this run only (r moves on return).
    CullideOptions run = r.options;
    if (run.exactSwitch.kind == ExactSwitchKind::Auto) run.exactSwitch.exactCost = study::exactStageCostModel(r.scene);
    r.result = runCullide(r.scene, *backend, run);
    return r;
}

// (k, 5) uint32 [objA, triA, objB, triB, class] -> the oracle's pairs, validated against the scene.
oracle::Truth truthFromPairs(const py::handle& pairs, const Scene& scene) {
    const py::array a = checkedArray(pairs, "pairs", 5, true);
    const auto d = py::array_t<int64_t, py::array::c_style | py::array::forcecast>::ensure(a);
    oracle::Truth truth;
    const int64_t* p = d.data();
    auto checkTri = [&](int64_t o, int64_t t, size_t row) {
        if (o < 0 || size_t(o) >= scene.objects.size() || t < 0 ||
            size_t(t) >= scene.objects[size_t(o)].mesh.triangleCount())
            fail("pairs: row " + std::to_string(row) + " names triangle " + std::to_string(t) + " of object " +
                 std::to_string(o) + ", which the scene does not have");
    };
    for (size_t i = 0; i < size_t(a.shape(0)); ++i) {
        const int64_t* row = p + 5 * i;
        checkTri(row[0], row[1], i);
        checkTri(row[2], row[3], i);
        if (row[4] != 0 && row[4] != 1)
            fail("pairs: row " + std::to_string(i) + " has class " + std::to_string(row[4]) +
                 " (0: crossing, 1: touching)");
        oracle::IntersectingPair q{uint32_t(row[0]), uint32_t(row[1]), uint32_t(row[2]), uint32_t(row[3]),
                                   row[4] == 0 ? oracle::PairClass::Crossing : oracle::PairClass::Touching};
        if (q.b() < q.a()) std::swap(q.objectA, q.objectB), std::swap(q.triangleA, q.triangleB);
        truth.pairs.push_back(q);
    }
    std::sort(truth.pairs.begin(), truth.pairs.end());
    truth.pairs.erase(std::unique(truth.pairs.begin(), truth.pairs.end(),
                                  [](const auto& x, const auto& y) { return x.a() == y.a() && x.b() == y.b(); }),
                      truth.pairs.end());
    return truth;
}

py::dict check(const PyResult& r, const py::handle& pairs) {
    const oracle::Truth truth = truthFromPairs(pairs, r.scene);
    std::unique_ptr<DepthBackend> backend = makeBackendChecked(r.backend, r.threads);
    study::PcsReport report;
    study::Attribution attribution;
    {
        py::gil_scoped_release release;
        report = study::measurePcs(r.scene, truth, r.result.pcs, r.options);
        attribution = study::attributeFalsePrunes(r.scene, truth, *backend, r.options);
    }
    py::dict out;
    py::dict fp, missed, missedSelf, causeTriangles, causePairs;
    for (int c = 0; c < 2; ++c) {
        const char* name = oracle::toString(oracle::PairClass(c));
        fp[name] = report.falsePrunes[c];
        missed[name] = report.missedPairs[c];
        missedSelf[name] = report.missedSelfPairs[c];
    }
    for (int c = 0; c < study::kCauseCount; ++c) {
        const char* name = study::toString(study::Cause(c));
        causeTriangles[name] = attribution.triangles[size_t(c)];
        causePairs[name] = attribution.pairs[size_t(c)];
    }
    std::vector<uint32_t> rows;
    for (const study::MissedPairCause& m : attribution.missed)
        rows.insert(rows.end(),
                    {m.pair.objectA, m.pair.triangleA, m.pair.objectB, m.pair.triangleB, uint32_t(m.pair.cls),
                     uint32_t(m.cause), m.call, m.direction});
    out["pcs_triangles"] = report.pcsTriangles;
    out["colliding_triangles"] = report.collidingTriangles;
    out["colliding_in_pcs"] = report.collidingInPcs;
    out["false_prunes"] = fp;
    out["false_prune_count"] = report.falsePruneCount();
    out["missed_pairs"] = missed;
    out["missed_self_pairs"] = missedSelf;
    out["false_positives"] = report.falsePositives;
    out["efficiency"] = report.efficiency;
    out["causes"] = causeTriangles;
    out["cause_pairs"] = causePairs;
    out["missed"] = makeArray(rows, attribution.missed.size(), 8);
    // The causes come from a second, instrumented run on a new backend of the same kind: for the
    // CPU reference it gives the same PCS (deterministic); this says whether it did.
    out["same_pcs"] = attribution.result.pcs == r.result.pcs;
    return out;
}

py::array_t<uint32_t> oracleOf(const PyScene& s, long frame) {
    const Scene scene = s.at(frame);
    oracle::Truth truth;
    {
        py::gil_scoped_release release;
        truth = oracle::findIntersections(scene);
    }
    std::vector<uint32_t> rows;
    rows.reserve(truth.pairs.size() * 5);
    for (const oracle::IntersectingPair& p : truth.pairs)
        rows.insert(rows.end(), {p.objectA, p.triangleA, p.objectB, p.triangleB, uint32_t(p.cls)});
    return makeArray(rows, truth.pairs.size(), 5);
}

DepthFunc parseDepthFunc(const std::string& text) {
    static const char* names[] = {"never", "less", "equal", "lequal", "greater", "notequal", "gequal", "always"};
    for (int i = 0; i < 8; ++i)
        if (text == names[i]) return DepthFunc(i);
    fail("depth function: '" + text + "' is not one of never, less, equal, lequal, greater, notequal, gequal, always");
}

QueryKind parseQueryKind(const std::string& text) {
    if (text == "samples") return QueryKind::SamplesPassed;
    if (text == "any") return QueryKind::AnySamplesPassed;
    fail("query kind: '" + text + "' is not 'samples' or 'any'");
}

Vec3d vec3(const py::handle& obj, const std::string& name) {
    std::vector<double> v;
    try {
        v = obj.cast<std::vector<double>>();
    } catch (const py::cast_error&) {
        fail(name + ": not a sequence of 3 numbers");
    }
    if (v.size() != 3) fail(name + ": has " + std::to_string(v.size()) + " numbers, not 3");
    for (double x : v)
        if (!std::isfinite(x)) fail(name + ": has a NaN or infinite value");
    return {v[0], v[1], v[2]};
}

// A draw range bound from Python: 0..2^32-1 (CommandList then checks that first + count fits).
uint32_t rangeValue(long long v, const std::string& name) {
    if (v < 0 || v > 0xffffffffLL) fail(name + ": " + std::to_string(v) + " is not 0..4294967295");
    return uint32_t(v);
}

// The CPU reference backend with its geometry kept, so that set_geometry's validation covers
// every later draw range check (the backend's own execute() checks ranges).
struct PyCpuBackend {
    std::unique_ptr<raster::CpuBackend> backend;
    bool viewSet = false;
};

}  // namespace

PYBIND11_MODULE(_cullide, m) {
    m.doc() = "cullide's compiled core (use the package `cullide`, docs/python.md)";
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const InputError& e) {
            PyErr_SetString(PyExc_ValueError, e.what());
        }
    });

    m.def(
        "version", [] { return std::string(version()); }, "The cullide version (as `cullide --version`).");
    m.def(
        "set_resource_dir", [](const std::string& d) { setResourceDir(d); },
        "Sets the folder holding data/ and tools/ (the package does this at import).");
    m.def(
        "resource_dir", [] { return resourceDir().string(); }, "The folder holding data/ and tools/.");

    m.def(
        "load_mesh",
        [](const std::string& path) {
            Mesh mesh;
            {
                py::gil_scoped_release release;
                mesh = loadMesh(path);
            }
            return py::make_tuple(verticesArray(mesh), facesArray(mesh));
        },
        py::arg("path"),
        "Loads a mesh (.off, .obj, .ply, .stl) as (V float32 (n,3), F uint32 (m,3)); ValueError on a bad file.");

    py::class_<PyScene>(m, "Scene", "A scene: named objects (mesh and 4x4 transform), optionally animated frames.")
        .def(py::init<>(), "An empty scene.")
        .def(
            "add",
            [](PyScene& s, const std::string& name, const py::object& v, const py::object& f,
               const py::object& transform) {
                Object o;
                o.name = name;
                o.mesh = meshFromPython(v, f, "object '" + name + "'");
                o.transform = transformFromPython(transform, "object '" + name + "': transform");
                s.animation.scene.objects.push_back(std::move(o));
                // An animated scene: the new object keeps its mesh and transform in every frame.
                for (Frame& fr : s.animation.frames)
                    if (!fr.poses.empty()) fr.poses.emplace_back();
                return s.animation.scene.objects.size() - 1;
            },
            py::arg("name"), py::arg("vertices"), py::arg("faces") = py::none(), py::arg("transform") = py::none(),
            "Adds an object: vertices (n,3) real and faces (m,3) integer arrays, or one object with .vertices "
            "and .faces (a trimesh mesh) as `vertices`; transform: a 4x4 affine matrix (default identity). "
            "Vertices are stored as float32. Returns the object's index. ValueError on bad arrays.")
        .def_property_readonly(
            "object_count", [](const PyScene& s) { return s.animation.scene.objects.size(); }, "Number of objects.")
        .def_property_readonly(
            "frame_count", [](const PyScene& s) { return s.animation.frameCount(); },
            "Number of frames (1 for a still scene).")
        .def_property_readonly(
            "triangle_count", [](const PyScene& s) { return s.animation.scene.triangleCount(); },
            "Triangles over all objects.")
        .def_property_readonly(
            "names",
            [](const PyScene& s) {
                std::vector<std::string> n;
                for (const Object& o : s.animation.scene.objects) n.push_back(o.name);
                return n;
            },
            "The objects' names, in order.")
        .def(
            "world_mesh",
            [](const PyScene& s, long object, long frame) {
                const Scene scene = s.at(frame);
                if (object < 0 || size_t(object) >= scene.objects.size())
                    fail("object: " + std::to_string(object) + " is not an object of the scene (0.." +
                         std::to_string(long(scene.objects.size()) - 1) + ")");
                const Mesh w = scene.worldMesh(size_t(object));
                return py::make_tuple(verticesArray(w), facesArray(w));
            },
            py::arg("object"), py::arg("frame") = 0,
            "Object `object` at `frame` with its transform applied: (V float32 (n,3), F uint32 (m,3)).")
        .def("__len__", [](const PyScene& s) { return s.animation.scene.objects.size(); });

    m.def(
        "load_scene",
        [](const std::string& path) {
            PyScene s;
            s.source = path;
            py::gil_scoped_release release;
            s.animation = loadScene(path);
            return s;
        },
        py::arg("path"),
        "Loads a scene file (.json, docs/scene-format) or a mesh (one object) as a Scene; ValueError on a bad file.");

    py::class_<PyResult>(m, "PruneResult", "The outcome of prune(): the PCS and per-pass statistics.")
        .def_property_readonly(
            "pcs",
            [](const PyResult& r) {
                std::vector<uint32_t> v;
                for (const PcsTriangle& p : r.result.pcs) v.insert(v.end(), {p.object, p.triangle});
                return makeArray(v, r.result.pcs.size(), 2);
            },
            "The potentially colliding set: (k,2) uint32 [object, triangle], sorted.")
        .def_property_readonly(
            "passes",
            [](const PyResult& r) {
                const size_t n = r.result.passes.size();
                py::array_t<uint32_t> level(n), direction(n), round(n), views(n), tiles(n);
                py::array_t<int32_t> width(n), height(n);
                py::array_t<uint64_t> nodesIn(n), nodesOut(n), triIn(n), triOut(n), rendered(n), queries(n);
                py::array_t<double> seconds(n);
                py::array_t<double> vector({n, size_t(3)});  // the call's direction (chosen directions)
                for (size_t i = 0; i < n; ++i) {
                    const PassStats& p = r.result.passes[i];
                    level.mutable_at(i) = p.level, direction.mutable_at(i) = p.direction;
                    nodesIn.mutable_at(i) = p.nodesIn, nodesOut.mutable_at(i) = p.nodesOut;
                    triIn.mutable_at(i) = p.trianglesIn, triOut.mutable_at(i) = p.trianglesOut;
                    rendered.mutable_at(i) = p.trianglesRendered, queries.mutable_at(i) = p.queries;
                    width.mutable_at(i) = p.width, height.mutable_at(i) = p.height, round.mutable_at(i) = p.round;
                    seconds.mutable_at(i) = p.seconds, views.mutable_at(i) = p.views, tiles.mutable_at(i) = p.tiles;
                    for (int k = 0; k < 3; ++k) vector.mutable_at(i, size_t(k)) = p.dirVector[k];
                }
                py::dict d;
                d["level"] = level, d["direction"] = direction, d["nodes_in"] = nodesIn, d["nodes_out"] = nodesOut;
                d["triangles_in"] = triIn, d["triangles_out"] = triOut, d["triangles_rendered"] = rendered;
                d["queries"] = queries, d["width"] = width, d["height"] = height, d["round"] = round;
                d["seconds"] = seconds, d["views"] = views;  // views: clustered's groups drawn (else 1)
                d["tiles"] = tiles;  // executions: views, each once per tile (a backend's viewport limit)
                d["direction_vector"] = vector;
                return d;
            },
            "One entry per reducePCS call, as numpy columns (the keys of `prune --json`'s passes).")
        .def(
            "face_mask",
            [](const PyResult& r, long object) {
                if (object < 0 || size_t(object) >= r.scene.objects.size())
                    fail("object: " + std::to_string(object) + " is not an object of the scene (0.." +
                         std::to_string(long(r.scene.objects.size()) - 1) + ")");
                py::array_t<bool> mask(py::ssize_t(r.scene.objects[size_t(object)].mesh.triangleCount()));
                std::fill(mask.mutable_data(), mask.mutable_data() + mask.size(), false);
                for (const PcsTriangle& p : r.result.pcs)
                    if (p.object == uint32_t(object)) mask.mutable_data()[p.triangle] = true;
                return mask;
            },
            py::arg("object"), "A bool per face of object `object`: whether it is in the PCS.")
        .def_property_readonly(
            "total_seconds", [](const PyResult& r) { return r.result.totalSeconds; },
            "Wall time of the run, hierarchy and geometry upload included.")
        .def_property_readonly(
            "hierarchy_seconds", [](const PyResult& r) { return r.result.hierarchySeconds; },
            "Wall time spent building the hierarchies.")
        .def_property_readonly(
            "levels", [](const PyResult& r) { return r.result.levels; }, "Hierarchy levels visited.")
        .def_property_readonly(
            "switched_at_level",
            [](const PyResult& r) {
                return r.result.switchedAtLevel < 0 ? py::object(py::none()) : py::int_(r.result.switchedAtLevel);
            },
            "With exact_switch: the level at which pruning stopped early for the exact stage (None: it did not).")
        .def_property_readonly(
            "frame", [](const PyResult& r) { return r.frame; }, "The frame pruned.");

    m.def("prune", &prune, py::arg("scene"), py::arg("method") = "modified", py::arg("resolution") = py::int_(500),
          py::arg("depth") = "d24", py::arg("directions") = "axes", py::arg("hierarchy") = "connectivity",
          py::arg("leaf_size") = 16, py::arg("branching") = 4, py::arg("seed") = 1, py::arg("backend") = "cpu",
          py::arg("threads") = 0, py::arg("frame") = 0, py::arg("views") = "fit", py::arg("exact_switch") = "never",
          "Runs Cullide on one frame (see the package's prune).");

    m.def("oracle", &oracleOf, py::arg("scene"), py::arg("frame") = 0,
          "Exact intersecting pairs of one frame: (p,5) uint32 [objA, triA, objB, triB, class] "
          "(class 0 crossing, 1 touching), sorted.");
    m.def("check", &check, py::arg("result"), py::arg("pairs"), "False prunes of a result by class and cause.");

    m.def(
        "study",
        [](const std::vector<std::string>& scenes, const std::vector<std::string>& methods,
           const std::vector<std::string>& resolutions, const std::vector<std::string>& depths,
           const std::vector<std::string>& directions, const std::vector<std::string>& hierarchies,
           const std::vector<uint32_t>& leafSizes, const std::vector<std::string>& backends,
           const std::vector<int>& threads, int repeats, bool oracle, const std::string& out,
           const std::vector<std::string>& views, const std::vector<std::string>& exactSwitches) {
            if (scenes.empty()) fail("argument scenes: no scenes");
            if (repeats < 1) fail("argument repeats: must be >= 1");
            study::StudyOptions o;
            study::Spec& s = o.spec;
            s.names = pythonNames();
            s.names.resolution = "argument resolutions", s.names.depth = "argument depths";
            s.names.method = "argument methods", s.names.hierarchy = "argument hierarchies";
            s.names.leafSize = "argument leaf_sizes";
            if (views.empty()) fail("argument views: no view modes");
            s.views = views;
            s.scenes = scenes, s.methods = methods, s.resolutions = resolutions, s.depths = depths;
            s.directions = directions, s.hierarchies = hierarchies, s.leafSizes = leafSizes;
            s.backends = backends, s.threads = threads, s.repeats = repeats, s.oracle = oracle;
            s.exactSwitches = exactSwitches, s.names.exactSwitch = "argument exact_switches";
            for (const std::string& b : backends)
                if (!raster::isBackendName(b))
                    fail("argument backends: '" + b + "' is not a backend (" + raster::backendNameList() + ")");
            for (int t : threads) checkedThreads(t);
            o.out = out;
            std::vector<std::string> records;
            o.onRecord = [&](const nlohmann::ordered_json& r) { records.push_back(r.dump()); };
            {
                py::gil_scoped_release release;
                study::runStudy(o);
            }
            return records;
        },
        py::arg("scenes"), py::arg("methods"), py::arg("resolutions"), py::arg("depths"), py::arg("directions"),
        py::arg("hierarchies"), py::arg("leaf_sizes"), py::arg("backends"), py::arg("threads"), py::arg("repeats"),
        py::arg("oracle"), py::arg("out"), py::arg("views") = std::vector<std::string>{"fit"},
        py::arg("exact_switches") = std::vector<std::string>{"never"},
        "Runs a study (see the package's study); returns the records as JSON texts.");
    m.def(
        "study_columns", [] { return study::columns(); }, "The study CSV's columns, in order.");

    py::class_<CommandList>(m, "CommandList",
                            "A depth-only command list, as cullide::CommandList: what one reducePCS pass asks a "
                            "backend to do. Queries are numbered in the order of begin_query().")
        .def(py::init<>())
        .def("clear", &CommandList::clear, py::arg("depth") = 1.0, "Clears the depth buffer to `depth` in [0,1].")
        .def(
            "depth_func", [](CommandList& l, const std::string& f) { l.depthFunc(parseDepthFunc(f)); }, py::arg("func"),
            "Sets the depth function: never, less, equal, lequal, greater, notequal, gequal, always.")
        .def("depth_mask", &CommandList::depthMask, py::arg("write"), "Whether draws write depth.")
        .def(
            "begin_query", [](CommandList& l, const std::string& k) { return l.beginQuery(parseQueryKind(k)); },
            py::arg("kind") = "samples", "Opens a query ('samples' or 'any'); returns its index.")
        .def("end_query", &CommandList::endQuery, "Closes the open query.")
        .def(
            "draw",
            [](CommandList& l, long long first, long long count) {
                l.draw(rangeValue(first, "draw: first"), rangeValue(count, "draw: count"));
            },
            py::arg("first"), py::arg("count"), "Draws triangles [first, first+count) of the geometry.")
        .def("clear_intervals", &CommandList::clearIntervals, "Conservative mode: empties the interval buffer.")
        .def(
            "draw_conservative",
            [](CommandList& l, long long first, long long count, bool test, bool write) {
                l.drawConservative(rangeValue(first, "draw_conservative: first"),
                                   rangeValue(count, "draw_conservative: count"), test, write);
            },
            py::arg("first"), py::arg("count"), py::arg("test"), py::arg("write"),
            "Conservative mode: rasterizes [first, first+count) conservatively.")
        .def_property_readonly("query_count", &CommandList::queryCount, "Queries begun so far.")
        .def("reset", &CommandList::reset, "Empties the list.")
        .def("__len__", [](const CommandList& l) { return l.commands().size(); });

    py::class_<PyCpuBackend>(m, "CpuBackend", "The CPU reference backend (a deterministic software depth buffer).")
        .def(py::init([](int subpixelBits, int threads, int tileSize, bool scalarReference, bool simd, bool direct,
                         long long viewCacheBytes, const std::string& fillRule) {
                 raster::CpuBackendOptions o;
                 o.subpixelBits = subpixelBits;
                 o.threads = checkedThreads(threads);
                 o.tileSize = tileSize;
                 o.scalarReference = scalarReference;
                 o.simd = simd;
                 o.direct = direct;
                 if (viewCacheBytes < 0)
                     fail("argument view_cache_bytes: " + std::to_string(viewCacheBytes) + " is negative");
                 o.viewCacheBytes = size_t(viewCacheBytes);
                 const std::optional<raster::FillRule> rule = raster::parseFillRule(fillRule);
                 if (!rule) fail("argument fill_rule: '" + fillRule + "' is not " + raster::kFillRuleNames);
                 o.fillRule = *rule;
                 PyCpuBackend b;
                 b.backend = raster::makeCpuBackend(o);
                 return b;
             }),
             py::arg("subpixel_bits") = raster::kDefaultSubpixelBits, py::arg("threads") = 0,
             py::arg("tile_size") = raster::kDefaultTileSize, py::arg("scalar_reference") = false,
             py::arg("simd") = true, py::arg("direct") = true,
             py::arg("view_cache_bytes") = (long long)raster::CpuBackendOptions{}.viewCacheBytes,
             py::arg("fill_rule") = "bottom-left")
        .def(
            "describe", [](const PyCpuBackend& b) { return b.backend->describe(); }, "A short description.")
        .def_property_readonly(
            "last_stats",
            [](const PyCpuBackend& b) {
                const raster::RasterStats& s = b.backend->lastStats();
                py::dict d;
                d["draws"] = s.draws, d["triangles"] = s.triangles, d["rejected"] = s.rejected;
                d["clipped"] = s.clipped, d["zero_area"] = s.zeroArea, d["fragments"] = s.fragments;
                d["passed"] = s.passed;
                return d;
            },
            "Counters of the last execute() (RasterStats; per drawn triangle instance), the same on every path.")
        .def_property_readonly(
            "last_ran_direct", [](const PyCpuBackend& b) { return b.backend->lastRanDirect(); },
            "Whether the last execute() took the direct path (option direct).")
        .def_property_readonly(
            "last_replayed_view", [](const PyCpuBackend& b) { return b.backend->lastReplayedView(); },
            "Whether the last execute() replayed fragments kept under its view (option view_cache_bytes).")
        .def(
            "set_geometry",
            [](PyCpuBackend& b, const py::object& v, const py::object& f) {
                const Mesh mesh = meshFromPython(v, f, "geometry");
                b.backend->setGeometry(mesh.positions, mesh.triangles);
            },
            py::arg("vertices"), py::arg("faces") = py::none(),
            "Sets the triangles to draw: (n,3) vertices and (m,3) faces (validated), or one object with them.")
        .def(
            "set_view",
            [](PyCpuBackend& b, const py::object& direction, const py::object& box, int width, int height,
               const std::string& depth) {
                OrthoView v = OrthoView::looking(vec3(direction, "direction"));
                std::vector<double> bx;
                try {
                    bx = box.cast<std::vector<double>>();
                } catch (const py::cast_error&) {
                    fail("box: not a sequence of 6 numbers");
                }
                if (bx.size() != 6) fail("box: has " + std::to_string(bx.size()) + " numbers, not 6");
                v.xmin = bx[0], v.xmax = bx[1], v.ymin = bx[2], v.ymax = bx[3], v.znear = bx[4], v.zfar = bx[5];
                v.width = width, v.height = height;
                v.depth = DepthFormat::parse(depth);
                b.backend->setView(v);
                b.viewSet = true;
                py::dict frame;
                frame["right"] = py::make_tuple(v.right.x(), v.right.y(), v.right.z());
                frame["up"] = py::make_tuple(v.up.x(), v.up.y(), v.up.z());
                frame["dir"] = py::make_tuple(v.dir.x(), v.dir.y(), v.dir.z());
                return frame;
            },
            py::arg("direction"), py::arg("box"), py::arg("width") = 500, py::arg("height") = 500,
            py::arg("depth") = "d24",
            "Sets an orthographic view looking along `direction` (frame as OrthoView::looking); box = (xmin, xmax, "
            "ymin, ymax, znear, zfar) in that frame's view coordinates. Returns the frame (right, up, dir).")
        .def(
            "execute",
            [](PyCpuBackend& b, const CommandList& l) {
                if (!b.viewSet) fail("execute: call set_view first");
                std::vector<uint64_t> r;
                {
                    py::gil_scoped_release release;
                    r = b.backend->execute(l);
                }
                py::array_t<uint64_t> a(py::ssize_t(r.size()));
                if (!r.empty()) std::memcpy(a.mutable_data(), r.data(), r.size() * sizeof(uint64_t));
                return a;
            },
            py::arg("commands"), "Executes a CommandList; returns one uint64 result per query.")
        .def(
            "read_depth",
            [](PyCpuBackend& b) {
                if (!b.viewSet) fail("read_depth: call set_view first");
                const DepthImage img = b.backend->readDepth();
                return makeArray(img.values, size_t(img.height), size_t(img.width));
            },
            "The stored depth buffer as (h,w) uint32: unorm codes (or float bit patterns for d32f); row 0 is the "
            "bottom row (GL window coordinates).");
}
