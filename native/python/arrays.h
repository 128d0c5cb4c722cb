// numpy argument checks shared by the bindings: arrays come in without copies,
// so dtype, layout and shape are checked here and reported as ValueError
// naming the argument.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <initializer_list>
#include <sstream>
#include <stdexcept>
#include <string>

namespace sunlapse::python {

namespace py = pybind11;

template <typename T>
const char* DtypeName();
template <>
inline const char* DtypeName<float>() {
  return "float32";
}
template <>
inline const char* DtypeName<double>() {
  return "float64";
}
template <>
inline const char* DtypeName<int32_t>() {
  return "int32";
}
template <>
inline const char* DtypeName<uint8_t>() {
  return "uint8";
}

// Returns a pointer into `a` after checking dtype T, C order and shape
// (-1 in `shape` accepts any size on that axis).
template <typename T>
const T* CheckArray(const py::array& a, const char* name,
                    std::initializer_list<py::ssize_t> shape) {
  auto fail = [&](const std::string& what) {
    throw std::invalid_argument(std::string(name) + ": " + what);
  };
  if (!py::isinstance<py::array_t<T>>(a)) {
    fail(std::string("expected dtype ") + DtypeName<T>() + ", got " +
         std::string(py::str(a.dtype())) + " (use .astype(numpy." +
         DtypeName<T>() + "))");
  }
  if (!(a.flags() & py::array::c_style)) {
    fail("must be C-contiguous (use numpy.ascontiguousarray)");
  }
  if (a.ndim() != static_cast<py::ssize_t>(shape.size())) {
    std::ostringstream s;
    s << "expected " << shape.size() << " dimensions, got " << a.ndim();
    fail(s.str());
  }
  int axis = 0;
  for (py::ssize_t want : shape) {
    if (want >= 0 && a.shape(axis) != want) {
      std::ostringstream s;
      s << "axis " << axis << " must have size " << want << ", got "
        << a.shape(axis);
      fail(s.str());
    }
    ++axis;
  }
  return static_cast<const T*>(a.data());
}

}  // namespace sunlapse::python
