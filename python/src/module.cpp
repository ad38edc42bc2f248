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
//     raster::makeBackend(backend, threads), Animation::sceneAt(frame), the pipeline's Pruner; so
//     the PCS is the command line's bit for bit.
//   - One file per part of the module: convert.h/.cpp (arrays and values in and out), types.h (the
//     module's objects), bind_scene.cpp, bind_prune.cpp, bind_study.cpp, bind_raster.cpp; this file
//     registers them.
#include "types.h"

#include "cullide/error.h"
#include "cullide/provenance.h"
#include "cullide/resources.h"

#include <pybind11/pybind11.h>

#include <exception>
#include <string>

namespace py = pybind11;
using namespace cullide;

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

    python::bindScene(m);
    python::bindPrune(m);
    python::bindStudy(m);
    python::bindCommandList(m);
    python::bindCpuBackend(m);
}
