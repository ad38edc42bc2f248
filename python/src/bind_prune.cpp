// The Python module: prune (through the Pruner, as `cullide prune` runs one frame), its result, the
// oracle and check.
#include "types.h"

#include "cullide/error.h"
#include "cullide/oracle/oracle.h"
#include "cullide/pipeline/pruner.h"
#include "cullide/raster/backends.h"
#include "cullide/study/causes.h"
#include "cullide/study/measures.h"

#include <algorithm>
#include <vector>

namespace cullide::python {
namespace {

// An int as its decimal text, so that the option parser sees the number as given (a cast to a
// C++ integer first would wrap or overflow).
std::string resolutionText(const py::object& r) {
    if (py::isinstance<py::str>(r)) return r.cast<std::string>();
    if (py::isinstance<py::bool_>(r) || !py::isinstance<py::int_>(r))
        fail("argument resolution: give an integer N or a text 'N', 'WxH', 'auto' or 'auto:K'");
    return py::str(r);
}

std::unique_ptr<DepthBackend> makeBackendChecked(const std::string& name, int threads) {
    if (!raster::isBackendName(name))
        fail("argument backend: '" + name + "' is not a backend (" + raster::backendNameList() + ")");
    if (name != "cpu" && threads != 0) fail("argument threads: applies to backend 'cpu' only");
    return raster::makeBackend(name, threads);
}

PyResult prune(const PyScene& s, const std::string& method, const py::object& resolution, const std::string& depth,
               const std::string& directions, const std::string& hierarchy, const py::object& leafSizeArg,
               const py::object& branchingArg, const py::object& seedArg, const std::string& backendName,
               const py::object& threadsArg, long frame, const std::string& views, const std::string& exactSwitch) {
    OptionText text;
    text.method = method;
    text.resolution = resolutionText(resolution);
    text.depth = depth;
    text.directions = directions;
    text.hierarchy = hierarchy;
    text.views = views;
    text.leafSize = integerArgument(leafSizeArg, "argument leaf_size", 1u, kMaxLeafSize);
    text.branching = integerArgument(branchingArg, "argument branching", kMinBranching, kMaxBranching);
    text.seed = integerArgument(seedArg, "argument seed", uint64_t(0), UINT64_MAX);
    const int threads = integerArgument(threadsArg, "argument threads", 0, kMaxThreads);
    text.exactSwitch = exactSwitch;
    PyResult r;
    r.options = parseCullideOptions(text, pythonNames());
    r.backend = backendName;
    r.threads = checkedThreads(threads);
    r.frame = frame;
    r.scene = s.at(frame);
    std::unique_ptr<DepthBackend> backend = makeBackendChecked(backendName, threads);
    py::gil_scoped_release release;
    PruneSettings settings;
    settings.cullide = r.options;
    Pruner pruner(settings, *backend);
    r.result = pruner.prune(r.scene).cull;
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

}  // namespace

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

int checkedThreads(long long threads) {
    return checkThreads(threads, "argument threads");
}

void bindPrune(py::module_& m) {
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

}

}  // namespace cullide::python
