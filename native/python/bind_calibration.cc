// Bindings of the calibration stage (camera from marked points).
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "arrays.h"
#include "sunlapse/calibration/camera_solve.h"

namespace sunlapse::python {

void BindCalibration(py::module_& m) {
  m.def(
      "solve_camera",
      [](const py::array& points, const py::array& pixels, int width,
         int height, double focal_px) {
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
        CameraSolveOptions o;
        o.focal_px = focal_px;
        const CameraSolveResult r = SolveCamera(world, px, width, height, o);
        py::dict d;
        d["success"] = r.success;
        d["message"] = r.message;
        d["focal_px"] = r.focal_px;
        d["K"] = r.K;
        d["matrix_world"] = r.blender_matrix_world;
        d["rms_px"] = r.rms_px;
        d["errors_px"] = r.errors_px;
        return d;
      },
      py::arg("points_in_world").noconvert(), py::arg("pixels").noconvert(),
      py::arg("width"), py::arg("height"), py::arg("focal_px") = 0.0,
      "Camera from marked points: world (N,3) float64, OpenCV pixels (N,2) "
      "float64. "
      "focal_px <= 0 estimates the focal length (>= 6 coplanar points). "
      "Returns a dict "
      "with success, message, focal_px, K, matrix_world (Blender camera), "
      "rms_px, errors_px.");
}

}  // namespace sunlapse::python
