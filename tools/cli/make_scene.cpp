// `cullide make-scene KIND -o SCENE.json`: the paper's scenes, generated reproducibly.
// Same kind, options and seed: same bytes.
#include "commands.h"

#include "cullide/cloth.h"
#include "cullide/error.h"
#include "cullide/generators.h"
#include "cullide/mesh_io.h"
#include "cullide/nbody.h"
#include "cullide/resources.h"
#include "cullide/scene_io.h"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>

namespace cullide::cli {
namespace {

enum class Kind { Bunny, Cows, Cylinders, Twist, Sheets, Cloth, NBody };

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
    SelfCollision selfCollision = SelfCollision::Repulsion;  // cloth
};

// The field's sequences: cloth on a ball (makeCloth) and N-body (makeNBody) from the bundled
// meshes or --mesh.
Animation makeSequence(const MakeSceneOptions& o) {
    if (o.kind == Kind::Cloth)
        return makeCloth({.triangles = o.triangles, .frames = o.frames, .seed = o.seed, .selfCollision = o.selfCollision});
    std::vector<std::filesystem::path> paths = nbodyMeshPaths();
    if (!o.mesh.empty()) paths = {o.mesh};
    std::vector<Mesh> meshes;
    for (const auto& path : paths) meshes.push_back(loadMesh(path));
    const std::string source = o.mesh.empty() ? "the bundled meshes" : o.mesh;
    return makeNBody(meshes, {.count = o.count, .triangles = o.triangles, .frames = o.frames, .seed = o.seed}, source);
}

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
    if (o.kind == Kind::Cloth || o.kind == Kind::NBody) {
        animation = makeSequence(o);
    } else if (o.kind == Kind::Cylinders) {
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
            case Kind::Sheets:
            case Kind::Cloth:
            case Kind::NBody: break;
        }
    }
    writeScene(animation, o.out);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf("%s: %zu object(s), %zu triangles, %zu frame(s), seed %llu (%.2f s)\n", o.out.c_str(),
                animation.scene.objects.size(), animation.scene.triangleCount(), animation.frameCount(),
                static_cast<unsigned long long>(o.seed), seconds);
    return 0;
}

// An option the kind does not use is refused, not ignored.
void refuseInapplicable(const MakeSceneOptions& o, const CLI::App& sub) {
    auto only = [&](const char* option, bool applies, const char* why) {
        if (!applies && sub.count(option)) throw CLI::ValidationError(option, why);
    };
    const Kind k = o.kind;
    const bool cylinders = k == Kind::Cylinders, sheets = k == Kind::Sheets, cloth = k == Kind::Cloth,
               nbody = k == Kind::NBody;
    only("--mesh", !cylinders && !sheets && !cloth,
         "does not apply to 'cylinders', 'sheets' or 'cloth' (generated, not made from a mesh)");
    only("--count", cylinders || sheets || nbody, "applies to 'cylinders', 'sheets' and 'nbody' only");
    only("--seed", cylinders || sheets || cloth || nbody,
         "applies to 'cylinders', 'sheets', 'cloth' and 'nbody' only (the other kinds are not random)");
    only("--tilt", sheets, "applies to 'sheets' only");
    only("--frames", !sheets, "does not apply to 'sheets' (a still scene)");
    only("--self-collision", cloth, "applies to 'cloth' only");
}

// The sequences' own defaults and ranges (the field's sizes), checked by option name.
void setSequenceDefaults(MakeSceneOptions& o, const CLI::App& sub) {
    if (o.kind == Kind::Sheets && !sub.count("--count")) o.count = 8;
    if (o.kind != Kind::Cloth && o.kind != Kind::NBody) return;
    const bool cloth = o.kind == Kind::Cloth;
    if (!sub.count("--triangles")) o.triangles = cloth ? ClothRequest{}.triangles : NBodyRequest{}.triangles;
    if (!sub.count("--frames")) o.frames = cloth ? ClothRequest{}.frames : NBodyRequest{}.frames;
    if (!sub.count("--count")) o.count = NBodyRequest{}.count;
    const size_t maxFrames = cloth ? kMaxClothFrames : kMaxNBodyFrames;
    if (o.frames < 1 || o.frames > maxFrames)
        throw InputError("option --frames", std::to_string(o.frames) + " is out of range for '" +
                                                (cloth ? "cloth" : "nbody") + "' (1 to " + std::to_string(maxFrames) +
                                                ")");
    if (cloth && o.triangles <= kMaxClothTriangles && o.triangles * o.frames > kMaxClothTriangleFrames)
        throw InputError("option --frames", std::to_string(o.frames) + " frames of " + std::to_string(o.triangles) +
                                                " triangles: 'cloth' holds every frame in memory, so triangles x "
                                                "frames must be at most " +
                                                std::to_string(kMaxClothTriangleFrames));
    if (cloth && o.triangles > kMaxClothTriangles)
        throw InputError("option --triangles", std::to_string(o.triangles) + " is out of range for 'cloth' (100 to " +
                                                   std::to_string(kMaxClothTriangles) + ")");
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
        "axes), 'cloth' (a cloth falling onto a sphere, draping and folding: simulated), 'nbody' (rigid bodies "
        "flying through each other in a box); docs/scenes.md");
    const std::map<std::string, Kind> kinds{{"bunny", Kind::Bunny},
                                            {"cows", Kind::Cows},
                                            {"cylinders", Kind::Cylinders},
                                            {"twist", Kind::Twist},
                                            {"sheets", Kind::Sheets},
                                            {"cloth", Kind::Cloth},
                                            {"nbody", Kind::NBody}};
    sub->add_option("kind", o->kind, "bunny | cows | cylinders | twist | sheets | cloth | nbody")
        ->required()
        ->transform(CLI::CheckedTransformer(kinds, CLI::ignore_case));
    sub->add_option("-o,--out", o->out, "Scene file to write (.json); meshes are written beside it")->required();
    addNumber(sub, "--triangles", o->triangles,
              "Requested triangle count, about (100 to 5,000,000; default 5000, for 'twist' the source mesh's, "
              "'cloth' 92,000 (the cloth's; at most 2,000,000), 'nbody' 146,000)",
              size_t(100), size_t(5'000'000));
    addNumber(sub, "--seed", o->seed,
              "Random seed of 'cylinders', 'sheets', 'cloth' and 'nbody' (same seed, same bytes; the other kinds "
              "are not random)");
    addNumber(sub, "--frames", o->frames,
              "Frames of animation (0: a still scene; at most 10,000); 'cloth' (default 94) and 'nbody' (default "
              "76): 1 to 1000 samples of the same motion",
              size_t(0), size_t(10'000));
    addNumber(sub, "--count", o->count,
              "Number of cylinders for 'cylinders' (default 100), of sheets for 'sheets' (default 8), of bodies for "
              "'nbody' (default 100); 1 to 10,000",
              size_t(1), size_t(10'000));
    sub->add_option("--self-collision", o->selfCollision,
                    "'cloth': repulsion (the default: cloth particles kept apart, as a simulator's output) | none (the "
                    "cloth passes through itself)")
        ->transform(CLI::CheckedTransformer(
            std::map<std::string, SelfCollision>{{"repulsion", SelfCollision::Repulsion}, {"none", SelfCollision::None}},
            CLI::ignore_case));
    addNumber(sub, "--tilt", o->tilt,
              "'sheets': degrees by which the sheets are tilted from the xy plane, each by 0.5 to 1.5 times "
              "this (0 to 59; default 3)",
              0.0, 59.0);
    sub->add_option("--mesh", o->mesh,
                    "Source mesh of 'bunny', 'cows', 'twist', 'nbody' (default: the bundled bunny, the cow for 'cows', both "
                    "for 'nbody')");
    sub->callback([o, sub, &action] {
        if (o->out.size() < 5 || o->out.substr(o->out.size() - 5) != ".json")
            throw CLI::ValidationError("--out", "the scene file must end in .json: " + o->out);
        refuseInapplicable(*o, *sub);
        setSequenceDefaults(*o, *sub);
        o->resampleTwist = o->kind == Kind::Twist && sub->count("--triangles") > 0;
        action = [o] { return runMakeScene(*o); };
    });
}

}  // namespace cullide::cli
