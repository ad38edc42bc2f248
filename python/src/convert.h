// Python values to cullide's types and back, every value validated before the libraries see it
// (shape, dtype kind, finiteness, index range); a problem raises ValueError naming the argument.
#pragma once

#include "cullide/mesh.h"
#include "cullide/parse_number.h"
#include "cullide/scene.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>  // in every part of the module: the same casters everywhere

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace cullide::python {

namespace py = pybind11;

// Raises ValueError(what).
[[noreturn]] void fail(const std::string& what);

// A numpy array of the given shape (rows x cols) and dtype, owning a copy of `data`.
template <typename T>
py::array_t<T> makeArray(const std::vector<T>& data, size_t rows, size_t cols) {
    py::array_t<T> a({py::ssize_t(rows), py::ssize_t(cols)});
    if (!data.empty()) std::memcpy(a.mutable_data(), data.data(), data.size() * sizeof(T));
    return a;
}

py::array_t<float> verticesArray(const Mesh& m);
py::array_t<uint32_t> facesArray(const Mesh& m);

// The array as a C-contiguous array of T, after checking its dtype kind ('f' float, 'i'/'u' integer)
// and shape (rows unknown: -1). `name` names the argument in errors.
py::array checkedArray(const py::handle& obj, const std::string& name, int cols, bool integer);
// (V, F) -> Mesh, validated: V (n,3) real, finite; F (m,3) integers in [0, n).
Mesh meshFromArrays(const py::handle& vertices, const py::handle& faces, const std::string& name);
// (V, F) from either two arrays or one object with .vertices and .faces (trimesh, Open3D-like).
Mesh meshFromPython(const py::object& v, const py::object& f, const std::string& name);
// A 4x4 affine matrix (None: identity).
Transform transformFromPython(const py::object& obj, const std::string& name);
// A sequence of three finite numbers.
Vec3d vec3(const py::handle& obj, const std::string& name);
// The decimal text of an integer argument: a Python int, anything with __index__ (numpy
// integers), or a str as the user typed it; ValueError naming the argument for anything else
// (a bool, a float, None).
std::string integerText(const py::handle& obj, const std::string& name);
// An integer argument read by the core's strict parser (cullide/parse_number.h) into [min, max]:
// ValueError naming the argument otherwise, never a wrapped, clamped or truncated value.
template <typename T>
T integerArgument(const py::handle& obj, const std::string& name, T min, T max) {
    return parseNumber(integerText(obj, name), name, min, max);
}

// A draw range bound from Python: 0..2^32-1 (CommandList then checks that first + count fits).
uint32_t rangeValue(long long v, const std::string& name);

}  // namespace cullide::python
