// `cullide report`: one self-contained HTML page of a study (charts embedded, the Pareto-optimal
// configurations of each scene, provenance, the command that produced the data), written by
// tools/plot.py --report (matplotlib) with Debian's /usr/bin/python3, as `cullide plot` runs it.
// With --view-scene, the page also shows one frame in 3D (three.js, inlined by the script): this
// side loads the frame as the study does and runs the oracle on it, and hands the script the world
// mesh and the oracle's pairs as a temporary JSON file; the script reads a method's missed and
// spurious pairs from an audit (`cullide audit --json`, --view-audit).
#include "commands.h"

#include "cullide/error.h"
#include "cullide/file_io.h"
#include "cullide/oracle/oracle.h"
#include "cullide/scene.h"
#include "cullide/study/study.h"

#include <nlohmann/json.hpp>

#include <unistd.h>

#include <filesystem>
#include <string>
#include <system_error>

namespace cullide::cli {
namespace {

// The most triangles the 3D view takes: the page carries each with its vertices (about 40 bytes
// of base64), and the browser expands them into its own buffers. A larger frame is refused, not
// decimated: a decimated mesh would no longer hold the triangles the pairs name.
constexpr size_t kMaxViewTriangles = 300'000;

struct ReportOptions {
    std::vector<std::string> inputs;
    std::string out = "report";
    std::string method;
    std::string python;
    std::string viewScene;
    uint32_t viewFrame = 0;
    std::string viewAudit;
    std::string viewMethod;
};

// The frame the 3D view shows, as the script reads it (tools/plotting/view3d.py): the world mesh
// (every object's, flattened), each object's name and triangle count, the oracle's pairs.
std::string viewFrameJson(const ReportOptions& o) {
    const std::string source = "option --view-scene";
    const size_t frames = study::studyFrameCount(o.viewScene);
    if (o.viewFrame >= frames)
        throw InputError("option --view-frame", "scene '" + o.viewScene + "' has " + std::to_string(frames) +
                                                    " frame(s), no frame " + std::to_string(o.viewFrame));
    const Scene scene = study::loadStudyScene(o.viewScene, o.viewFrame);
    if (scene.triangleCount() > kMaxViewTriangles)
        throw InputError(source, "'" + o.viewScene + "' has " + std::to_string(scene.triangleCount()) +
                                     " triangles, over the 3D view's limit of " + std::to_string(kMaxViewTriangles));
    const FlatScene flat = flatten(scene);
    const oracle::Truth truth = oracle::findIntersections(scene);

    nlohmann::ordered_json j;
    j["scene"] = o.viewScene;
    j["frame"] = o.viewFrame;
    auto& objects = j["objects"] = nlohmann::ordered_json::array();
    for (const Object& obj : scene.objects)
        objects.push_back({{"name", obj.name}, {"triangles", obj.mesh.triangleCount()}});
    auto& positions = j["positions"] = nlohmann::ordered_json::array();
    for (const Vec3f& p : flat.mesh.positions) positions.insert(positions.end(), {p.x(), p.y(), p.z()});
    auto& triangles = j["triangles"] = nlohmann::ordered_json::array();
    for (const Triangle& t : flat.mesh.triangles) triangles.insert(triangles.end(), {t[0], t[1], t[2]});
    auto& pairs = j["pairs"] = nlohmann::ordered_json::array();
    for (const oracle::IntersectingPair& p : truth.pairs)
        pairs.push_back({p.objectA, p.triangleA, p.objectB, p.triangleB, oracle::toString(p.cls)});
    return j.dump();
}

// A file removed when the report is done, written or not.
struct TemporaryFile {
    std::filesystem::path path;
    ~TemporaryFile() {
        std::error_code ignored;
        if (!path.empty()) std::filesystem::remove(path, ignored);
    }
};

int runReport(const ReportOptions& o) {
    std::vector<std::string> args{"--report", "-o", o.out};
    if (!o.method.empty()) args.insert(args.end(), {"--method", o.method});
    std::vector<std::string> mustExist = o.inputs;
    TemporaryFile view;
    if (!o.viewScene.empty()) {
        if (!o.viewAudit.empty()) mustExist.push_back(o.viewAudit);  // refused by name before the oracle runs
        for (const std::string& in : mustExist)
            if (!std::filesystem::exists(in)) throw InputError(in, "no such file");
        const std::string json = viewFrameJson(o);
        view.path = std::filesystem::temp_directory_path() /
            ("cullide-report-view-" + std::to_string(getpid()) + ".json");
        writeFileAtomically(view.path, json);
        args.insert(args.end(), {"--view", view.path.string()});
        if (!o.viewAudit.empty()) args.insert(args.end(), {"--view-audit", o.viewAudit});
        if (!o.viewMethod.empty()) args.insert(args.end(), {"--view-method", o.viewMethod});
    }
    args.insert(args.end(), o.inputs.begin(), o.inputs.end());
    return runPlotScript(mustExist, args, o.python);
}

}  // namespace

void addReportCommand(CLI::App& app, Action& action) {
    auto o = std::make_shared<ReportOptions>();
    CLI::App* sub = app.add_subcommand(
        "report", "One self-contained HTML page of study results: charts, Pareto tables, provenance, command");
    sub->add_option("inputs", o->inputs, "Study outputs (.csv or .jsonl; the .jsonl beside a .csv is read)")
        ->required();
    sub->add_option("-o,--out", o->out, "Folder for report.html")->capture_default_str();
    sub->add_option("--method", o->method, "Method of the per-call charts (Figures 9-11), as plot --method");
    sub->add_option("--python", o->python, "Python with matplotlib (default $CULLIDE_PYTHON or /usr/bin/python3)");
    CLI::Option* scene = sub->add_option(
        "--view-scene", o->viewScene,
        "Show one frame of this scene in 3D in the page (as study --scenes: bunny:N, a file; at most 300000 "
        "triangles): its mesh and the oracle's pairs");
    sub->add_option("--view-frame", o->viewFrame, "The frame of --view-scene to show")
        ->capture_default_str()
        ->needs(scene);
    sub->add_option("--view-audit", o->viewAudit,
                    "Missed and spurious pairs to show on that frame: `cullide audit --json` output")
        ->needs(scene);
    sub->add_option("--view-method", o->viewMethod, "Name of the method the audit judged, for the page")
        ->needs(scene);
    sub->callback([o, &action] { action = [o] { return runReport(*o); }; });
}

}  // namespace cullide::cli
