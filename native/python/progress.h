// Progress callables from Python for the stages that report progress.
#pragma once

#include <pybind11/pybind11.h>

#include <functional>

namespace sunlapse::python {

namespace py = pybind11;

// (fraction) -> bool|None from Python (None = go on) as a C++ callback that
// takes Python's lock while it runs; empty for None.
inline std::function<bool(double)> WrapProgress(const py::object& fn) {
  if (fn.is_none()) return nullptr;
  return [fn](double fraction) {
    py::gil_scoped_acquire gil;
    const py::object r = fn(fraction);
    return r.is_none() || r.cast<bool>();
  };
}

}  // namespace sunlapse::python
