// `cullide make-scene KIND -o SCENE.json`: the paper's scenes, generated reproducibly.
// Same kind, options and seed: same bytes.
#include "commands.h"

#include "cullide/error.h"
#include "cullide/generators.h"
#include "cullide/mesh_io.h"
#include "cullide/resources.h"
#include "cullide/scene_io.h"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>

namespace cullide::cli {
namespace {

enum class Kind { Bunny, Cows, Cylinders, Twist, Sheets };

struct MakeSceneOptions {
    Kind kind = Kind::Bunny;
    std::string out;
    std::string mesh;  // source mesh; default per kind from the bundled data
    size_t triangles = 5000;
    uint64_t seed = 1;
    size_t frames = 0;
    size_t count = 100;  // cylinders; sheets: 8 unless given
    double tilt = 3;  // sheets: degrees from the xy plane
    bool resampleTwist = false;  // --triangles given for 'twist': resample the source mesh first
};

std::string defaultMesh(Kind k) {
    const std::string dir = (dataDir() / "meshes").string() + "/";
    return k == Kind::Cows ? dir + "cow.off" : dir + "bunny.off";
}

int runMakeScene(const MakeSceneOptions& o) {
    const auto start = std::chrono::steady_clock::now();
    SceneRequest request;
    request.triangles = o.triangles;
    request.seed = o.seed;
    request.frames = o.frames;

    Animation animation;
    if (o.kind == Kind::Cylinders) {
        animation = makeCylinders(o.count, request);
    } else if (o.kind == Kind::Sheets) {
        animation = makeSheets(o.count, o.tilt, request);
    } else {
        const std::string source = o.mesh.empty() ? defaultMesh(o.kind) : o.mesh;
        const Mesh mesh = loadMesh(source);
        switch (o.kind) {
            case Kind::Bunny: animation = makeDeformedBunny(mesh, request, source); break;
            case Kind::Cows: animation = makeTwoCows(mesh, request, source); break;
            case Kind::Twist:
                // As the study's twist:N: the mesh resampled to the request, then twisted; without
                // --triangles the source mesh as it is.
                animation = makeTwistAnimation(o.resampleTwist ? resample(mesh, o.triangles) : mesh, request, source);
                break;
            case Kind::Cylinders:
            case Kind::Sheets: break;
        }
    }
    writeScene(animation, o.out);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf("%s: %zu object(s), %zu triangles, %zu frame(s), seed %llu (%.2f s)\n", o.out.c_str(),
                animation.scene.objects.size(), animation.scene.triangleCount(), animation.frameCount(),
                static_cast<unsigned long long>(o.seed), seconds);
    return 0;
}

}  // namespace

void addMakeSceneCommand(CLI::App& app, Action& action) {
    auto o = std::make_shared<MakeSceneOptions>();
    CLI::App* sub = app.add_subcommand(
        "make-scene",
        "Generate one of the paper's scenes reproducibly: 'bunny' (a deformed Stanford bunny with one "
        "self-intersection area), 'cows' (two cows merged into one object, many self-intersections), "
        "'cylinders' (many deforming cylinders, as in CULLIDE), 'twist' (a twisting mesh), 'sheets' (nearly parallel "
        "flat sheets tilted a few degrees from the xy plane, some crossing: seen nearly edge-on from the x and y "
        "axes)");
    const std::map<std::string, Kind> kinds{{"bunny", Kind::Bunny},
                                            {"cows", Kind::Cows},
                                            {"cylinders", Kind::Cylinders},
                                            {"twist", Kind::Twist},
                                            {"sheets", Kind::Sheets}};
    sub->add_option("kind", o->kind, "bunny | cows | cylinders | twist | sheets")
        ->required()
        ->transform(CLI::CheckedTransformer(kinds, CLI::ignore_case));
    sub->add_option("-o,--out", o->out, "Scene file to write (.json); meshes are written beside it")->required();
    addNumber(sub, "--triangles", o->triangles,
              "Requested triangle count, about (100 to 5,000,000; default 5000, for 'twist' the source mesh's)",
              size_t(100), size_t(5'000'000));
    addNumber(sub, "--seed", o->seed,
              "Random seed of 'cylinders' and 'sheets' (same seed, same bytes; the other kinds are not random)");
    addNumber(sub, "--frames", o->frames, "Frames of animation (0: a still scene; at most 10,000)", size_t(0),
              size_t(10'000));
    addNumber(sub, "--count", o->count,
              "Number of cylinders for 'cylinders' (default 100), of sheets for 'sheets' (default 8); 1 to 10,000",
              size_t(1), size_t(10'000));
    addNumber(sub, "--tilt", o->tilt,
              "'sheets': degrees by which the sheets are tilted from the xy plane, each by 0.5 to 1.5 times "
              "this (0 to 59; default 3)",
              0.0, 59.0);
    sub->add_option("--mesh", o->mesh,
                    "Source mesh of 'bunny', 'cows', 'twist' (default: the bundled bunny, or the cow for 'cows')");
    sub->callback([o, sub, &action] {
        if (o->out.size() < 5 || o->out.substr(o->out.size() - 5) != ".json")
            throw CLI::ValidationError("--out", "the scene file must end in .json: " + o->out);
        // An option the kind does not use is refused, not ignored.
        const bool cylinders = o->kind == Kind::Cylinders, sheets = o->kind == Kind::Sheets;
        if ((cylinders || sheets) && sub->count("--mesh"))
            throw CLI::ValidationError("--mesh",
                                       "does not apply to 'cylinders' or 'sheets' (generated, not made from "
                                       "a mesh)");
        if (!cylinders && !sheets && sub->count("--count"))
            throw CLI::ValidationError("--count", "applies to 'cylinders' and 'sheets' only");
        if (!cylinders && !sheets && sub->count("--seed"))
            throw CLI::ValidationError("--seed",
                                       "applies to 'cylinders' and 'sheets' only (the other kinds are not random)");
        if (!sheets && sub->count("--tilt")) throw CLI::ValidationError("--tilt", "applies to 'sheets' only");
        if (sheets && sub->count("--frames"))
            throw CLI::ValidationError("--frames", "does not apply to 'sheets' (a still scene)");
        if (sheets && !sub->count("--count")) o->count = 8;
        o->resampleTwist = o->kind == Kind::Twist && sub->count("--triangles") > 0;
        action = [o] { return runMakeScene(*o); };
    });
}

}  // namespace cullide::cli
