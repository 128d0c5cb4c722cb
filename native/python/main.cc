// The _native module: thin bindings of the native stages (docs/design.md §2).
#include <pybind11/pybind11.h>

namespace py = pybind11;

namespace sunlapse::python {
void BindScene(py::module_& m);
void BindEphemeris(py::module_& m);
void BindEstimate(py::module_& m);
void BindCalibration(py::module_& m);
void BindSky(py::module_& m);
void BindWholeClip(py::module_& m);
void BindVideo(py::module_& m);
void BindMotion(py::module_& m);
void BindRefine(py::module_& m);
}  // namespace sunlapse::python

PYBIND11_MODULE(_native, m) {
  m.doc() = "sunlapse native core: camera, scene ray casting, estimators";
  // From blender_manifest.toml through CMake (one source for the version).
  m.attr("__version__") = SUNLAPSE_VERSION;
  sunlapse::python::BindScene(m);
  sunlapse::python::BindEphemeris(m);
  sunlapse::python::BindEstimate(m);
  sunlapse::python::BindCalibration(m);
  sunlapse::python::BindSky(m);
  sunlapse::python::BindWholeClip(m);
  sunlapse::python::BindVideo(m);
  sunlapse::python::BindMotion(m);
  sunlapse::python::BindRefine(m);
}
