// The Python module: studies (study, study_columns).
#include "types.h"

#include "cullide/parse_number.h"
#include "cullide/raster/backends.h"
#include "cullide/study/study.h"

#include <string>
#include <vector>

namespace cullide::python {

void bindStudy(py::module_& m) {
    m.def(
        "study",
        [](const std::vector<std::string>& scenes, const std::vector<std::string>& methods,
           const std::vector<std::string>& resolutions, const std::vector<std::string>& depths,
           const std::vector<std::string>& directions, const std::vector<std::string>& hierarchies,
           const std::vector<py::object>& leafSizes, const std::vector<std::string>& backends,
           const std::vector<py::object>& threads, const py::object& repeats, bool oracle, const std::string& out,
           const std::vector<std::string>& views, const std::vector<std::string>& exactSwitches, double nearDistance,
           double tolerance) {
            if (scenes.empty()) fail("argument scenes: no scenes");
            study::StudyOptions o;
            study::Spec& s = o.spec;
            s.names = pythonNames();
            s.names.resolution = "argument resolutions", s.names.depth = "argument depths";
            s.names.method = "argument methods", s.names.hierarchy = "argument hierarchies";
            s.names.leafSize = "argument leaf_sizes";
            if (views.empty()) fail("argument views: no view modes");
            s.views = views;
            s.scenes = scenes, s.methods = methods, s.resolutions = resolutions, s.depths = depths;
            s.directions = directions, s.hierarchies = hierarchies;
            s.leafSizes.clear(), s.threads.clear();
            for (const py::object& l : leafSizes)
                s.leafSizes.push_back(integerArgument(l, "argument leaf_sizes", 1u, kMaxLeafSize));
            for (const py::object& t : threads) s.threads.push_back(integerArgument(t, "argument threads", 0, kMaxThreads));
            s.repeats = integerArgument(repeats, "argument repeats", 1, 1000);
            s.backends = backends, s.oracle = oracle;
            s.exactSwitches = exactSwitches, s.names.exactSwitch = "argument exact_switches";
            if (!(nearDistance >= 0 && nearDistance <= study::kMaxNearDistance))
                fail("argument near_distance: " + numberText(nearDistance) + " is out of range (0 to " +
                     numberText(study::kMaxNearDistance) + ")");
            if (nearDistance > 0 && !oracle) fail("argument near_distance: near contacts need the oracle (oracle=True)");
            s.nearDistance = nearDistance;
            if (!(tolerance >= 0 && tolerance <= study::kMaxTolerance))
                fail("argument tolerance: " + numberText(tolerance) + " is out of range (0 to " +
                     numberText(study::kMaxTolerance) + ")");
            s.tolerance = tolerance;
            for (const std::string& b : backends)
                if (!raster::isBackendName(b))
                    fail("argument backends: '" + b + "' is not a backend (" + raster::backendNameList() + ")");
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
        py::arg("exact_switches") = std::vector<std::string>{"never"}, py::arg("near_distance") = 0.0,
        py::arg("tolerance") = study::kDefaultTolerance,
        "Runs a study (see the package's study); returns the records as JSON texts.");
    m.def(
        "study_columns", [] { return study::columns(); }, "The study CSV's columns, in order.");

}

}  // namespace cullide::python
