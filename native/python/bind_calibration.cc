// Bindings of the calibration stage (camera from marked points).
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "arrays.h"
#include "options.h"
#include "sunlapse/calibration/camera_solve.h"

namespace sunlapse::python {

void BindCalibration(py::module_& m) {
  OptionsClass<CameraSolveOptions>(m, "CameraSolveOptions",
                                   "Options of solve_camera.")
      .field("focal_px", &CameraSolveOptions::focal_px,
             "Focal length, pixels; <= 0 estimates it.")
      .field("principal_x_px", &CameraSolveOptions::principal_x_px,
             "Principal point x, OpenCV pixels; NaN: the image centre.")
      .field("principal_y_px", &CameraSolveOptions::principal_y_px,
             "Principal point y, OpenCV pixels; NaN: the image centre.");
  py::enum_<CameraSolveResult::Status>(m, "CameraSolveStatus")
      .value("SUCCESS", CameraSolveResult::Status::kSuccess)
      .value("TOO_FEW_POINTS", CameraSolveResult::Status::kTooFewPoints)
      .value("NOT_COPLANAR", CameraSolveResult::Status::kNotCoplanar)
      .value("NO_FOCAL", CameraSolveResult::Status::kNoFocal)
      .value("FAILED", CameraSolveResult::Status::kFailed)
      .value("BEHIND_CAMERA", CameraSolveResult::Status::kBehindCamera);

  py::class_<CameraSolveResult>(m, "CameraSolveResult",
                                "A camera from marked points (camera_solve.h).")
      .def_readonly("status", &CameraSolveResult::status)
      .def_readonly("message", &CameraSolveResult::message)
      .def_readonly("focal_px", &CameraSolveResult::focal_px)
      .def_readonly("K", &CameraSolveResult::K)
      .def_readonly("matrix_world", &CameraSolveResult::blender_matrix_world,
                    "Blender's Object.matrix_world for the camera")
      .def_readonly("rms_px", &CameraSolveResult::rms_px)
      .def_readonly("errors_px", &CameraSolveResult::errors_px);

  m.def(
      "solve_camera",
      [](const py::array& points, const py::array& pixels, int width,
         int height, const py::object& focal_px, const py::object& options,
         const py::kwargs& kwargs) {
        const double* w =
            CheckArray<double>(points, "points_in_world", {-1, 3});
        const double* p =
            CheckArray<double>(pixels, "pixels", {points.shape(0), 2});
        std::vector<Eigen::Vector3d> world;
        std::vector<Eigen::Vector2d> px;
        for (py::ssize_t i = 0; i < points.shape(0); ++i) {
          world.emplace_back(w[3 * i], w[3 * i + 1], w[3 * i + 2]);
          px.emplace_back(p[2 * i], p[2 * i + 1]);
        }
        CameraSolveOptions o = OptionsFrom<CameraSolveOptions>(options, kwargs);
        if (!focal_px.is_none()) o.focal_px = focal_px.cast<double>();
        const CameraSolveResult r = SolveCamera(world, px, width, height, o);
        return r;
      },
      py::arg("points_in_world").noconvert(), py::arg("pixels").noconvert(),
      py::arg("width"), py::arg("height"), py::arg("focal_px") = py::none(),
      py::kw_only(), py::arg("options") = py::none(),
      "Camera from marked points: world (N,3) float64, OpenCV pixels (N,2) "
      "float64. "
      "focal_px <= 0 or None estimates the focal length (>= 6 coplanar "
      "points); options=CameraSolveOptions and/or its fields as keyword "
      "arguments. "
      "Returns a CameraSolveResult.");
}

}  // namespace sunlapse::python
