// Bindings of the model refinement stage (refine/model_refine.h).
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "arrays.h"
#include "images.h"
#include "options.h"
#include "sunlapse/refine/model_refine.h"

namespace sunlapse::python {

void BindRefine(py::module_& m) {
  OptionsClass<StableEdgesOptions>(m, "StableEdgesOptions",
                                   "Options of stable_edges.")
      .field("min_level_fraction", &StableEdgesOptions::min_level_fraction,
             "Frames darker than this share of the brightest frame's median "
             "are left out.")
      .field("min_log_gradient", &StableEdgesOptions::min_log_gradient,
             "Median gradient of log intensity an edge must reach.")
      .field("ignore_top_rows", &StableEdgesOptions::ignore_top_rows,
             "Rows at the top left out.");
  m.def(
      "stable_edges",
      [](const std::vector<py::object>& frames, const py::object& options,
         const py::kwargs& kwargs) {
        std::vector<cv::Mat> mats;
        for (const auto& f : frames) mats.push_back(GrayArg(f));
        const auto o = OptionsFrom<StableEdgesOptions>(options, kwargs);
        cv::Mat edges;
        {
          py::gil_scoped_release release;
          edges = StableEdges(mats, o);
        }
        return edges.empty() ? py::object(py::none())
                             : py::object(MatAsArray(edges));
      },
      py::arg("frames"), py::kw_only(), py::arg("options") = py::none(),
      "Edges (uint8 (H,W), 255 on an edge) that stay in most of the frames "
      "(float32 (H,W) linear gray, or None); None when fewer than two frames "
      "are usable.");

  OptionsClass<ModelRefineOptions>(m, "ModelRefineOptions",
                                   "Options of refine_model.")
      .field("max_move_m", &ModelRefineOptions::max_move_m,
             "Bound of an object's move (m).")
      .field("max_turn_deg", &ModelRefineOptions::max_turn_deg,
             "Bound of its turn (deg).")
      .field("max_scale_change", &ModelRefineOptions::max_scale_change,
             "Bound of its scale change per axis (fraction).")
      .field("max_camera_turn_deg", &ModelRefineOptions::max_camera_turn_deg,
             "Bound of the camera's turn (deg).")
      .field("max_focal_change", &ModelRefineOptions::max_focal_change,
             "Bound of the focal length's change (fraction).")
      .field("move_sigma_m", &ModelRefineOptions::move_sigma_m,
             "Prior of a move (m).")
      .field("max_move_fraction", &ModelRefineOptions::max_move_fraction,
             "Bound of a move as a fraction of the object's largest extent.")
      .field("move_sigma_fraction", &ModelRefineOptions::move_sigma_fraction,
             "Prior of a move as a fraction of the object's largest extent.")
      .field("turn_sigma_deg", &ModelRefineOptions::turn_sigma_deg,
             "Prior of a turn (deg).")
      .field("scale_sigma", &ModelRefineOptions::scale_sigma,
             "Prior of a scale change.")
      .field("camera_turn_sigma_deg",
             &ModelRefineOptions::camera_turn_sigma_deg,
             "Prior of the camera's turn (deg).")
      .field("focal_sigma", &ModelRefineOptions::focal_sigma,
             "Prior of the focal's change.")
      .field("edge_spacing_px", &ModelRefineOptions::edge_spacing_px,
             "Spacing of the model's edge points (px).")
      .field("edge_sigma_px", &ModelRefineOptions::edge_sigma_px,
             "Scale of the edge loss (px).")
      .field("max_edge_distance_px", &ModelRefineOptions::max_edge_distance_px,
             "Cap of an edge point's distance (px).")
      .field("crease_deg", &ModelRefineOptions::crease_deg,
             "Smallest crease (deg).")
      .field("min_points_per_object",
             &ModelRefineOptions::min_points_per_object,
             "Visible edge points an object needs to be refined.")
      .field("max_object_distance_px",
             &ModelRefineOptions::max_object_distance_px,
             "Mean distance (px) above which an object keeps its placement.")
      .field("min_distance_before_px",
             &ModelRefineOptions::min_distance_before_px,
             "Mean distance (px) of the model's edges below which it is left "
             "as is.")
      .field("min_distance_drop", &ModelRefineOptions::min_distance_drop,
             "Share of that distance the fit must remove to be used.");
  py::enum_<ModelRefineResult::Status>(m, "ModelRefineStatus")
      .value("REFINED", ModelRefineResult::Status::kRefined)
      .value("UNCHANGED", ModelRefineResult::Status::kUnchanged)
      .value("NO_EDGES", ModelRefineResult::Status::kNoEdges)
      .value("FAILED", ModelRefineResult::Status::kFailed);
  py::class_<ObjectCorrection>(m, "ObjectCorrection",
                               "One object's correction.")
      .def_readonly("object_id", &ObjectCorrection::object_id)
      .def_readonly("pivot_in_world", &ObjectCorrection::pivot_in_world)
      .def_readonly("axis_in_world", &ObjectCorrection::axis_in_world)
      .def_readonly("move_in_world_m", &ObjectCorrection::move_in_world_m)
      .def_readonly("turn_deg", &ObjectCorrection::turn_deg)
      .def_readonly("scale", &ObjectCorrection::scale)
      .def_readonly("refined", &ObjectCorrection::refined)
      .def_readonly("points", &ObjectCorrection::points)
      .def_readonly("distance_before_px", &ObjectCorrection::distance_before_px)
      .def_readonly("distance_after_px", &ObjectCorrection::distance_after_px)
      .def("transform", &ObjectCorrection::Transform,
           "4x4 world transform p -> p' (left-multiplies Blender's "
           "matrix_world)");
  py::class_<CameraCorrection>(m, "CameraCorrection",
                               "The camera's correction.")
      .def_readonly("turn_in_world", &CameraCorrection::turn_in_world)
      .def_readonly("turn_deg", &CameraCorrection::turn_deg)
      .def_readonly("focal_factor", &CameraCorrection::focal_factor);
  py::class_<ModelRefineResult>(m, "ModelRefineResult",
                                "A refined model (model_refine.h).")
      .def_readonly("status", &ModelRefineResult::status)
      .def_readonly("message", &ModelRefineResult::message)
      .def_readonly("camera", &ModelRefineResult::camera)
      .def_readonly("objects", &ModelRefineResult::objects)
      .def_readonly("points", &ModelRefineResult::points)
      .def_readonly("distance_before_px",
                    &ModelRefineResult::distance_before_px)
      .def_readonly("distance_after_px", &ModelRefineResult::distance_after_px);
  m.def(
      "refine_model",
      [](const Scene& scene, const Camera& camera,
         const std::vector<int32_t>& fixed_ids, const py::array& edges,
         const py::object& options, const py::kwargs& kwargs) {
        const cv::Mat e = MaskView(edges, "edges");
        const auto o = OptionsFrom<ModelRefineOptions>(options, kwargs);
        py::gil_scoped_release release;
        return RefineModel(scene, camera, fixed_ids, e, o);
      },
      py::arg("scene"), py::arg("camera"), py::arg("fixed_object_ids"),
      py::arg("edges"), py::kw_only(), py::arg("options") = py::none(),
      "The model's objects moved, turned and scaled, and the camera turned and "
      "zoomed, so that the model's visible edges fall on the clip's stable "
      "edges (of the camera's size). Returns a ModelRefineResult.");
  m.def("corrected_scene", &CorrectedScene, py::arg("scene"), py::arg("result"),
        "The scene with a ModelRefineResult's object corrections applied.");
  m.def("corrected_camera", &CorrectedCamera, py::arg("camera"),
        py::arg("correction"), "The camera with a CameraCorrection applied.");
}

}  // namespace sunlapse::python
