// The Python module's own objects (a scene, a prune's result, the CPU backend as Python holds
// them) and the binding functions that module.cpp calls, one per part of the module.
#pragma once

#include "convert.h"

#include "cullide/cullide.h"
#include "cullide/options.h"
#include "cullide/raster/cpu_backend.h"
#include "cullide/scene.h"

#include <pybind11/pybind11.h>

#include <memory>
#include <string>
#include <unordered_set>

namespace cullide::python {

// A scene: cullide's Animation (a still scene has no frames).
struct PyScene {
    Animation animation;
    std::string source = "scene";
    std::unordered_set<std::string> names;  // the objects' names, each taken once (checkObjectName)

    // The scene at `frame`; ValueError for a frame it does not have, or a scene that cannot be
    // used (no objects: checkSceneObjects).
    Scene at(long frame) const {
        checkSceneObjects(animation.scene, source);
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

// The CPU reference backend with its geometry kept, so that set_geometry's validation covers
// every later draw range check (the backend's own execute() checks ranges).
struct PyCpuBackend {
    std::unique_ptr<raster::CpuBackend> backend;
    bool viewSet = false;
};

// Python's names for Cullide's options ("argument method", ...) in error messages.
OptionNames pythonNames();
// A worker-thread count from Python (checkThreads, named "argument threads").
int checkedThreads(long long threads);

// Scene, load_mesh, load_scene (bind_scene.cpp).
void bindScene(pybind11::module_& m);
// prune, PruneResult, oracle, check (bind_prune.cpp).
void bindPrune(pybind11::module_& m);
// study, study_columns (bind_study.cpp).
void bindStudy(pybind11::module_& m);
// CommandList and CpuBackend (bind_raster.cpp).
void bindCommandList(pybind11::module_& m);
void bindCpuBackend(pybind11::module_& m);

}  // namespace cullide::python
