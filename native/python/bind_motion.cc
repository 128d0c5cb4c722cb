// Bindings of the moving camera's resampling (motion/view_warp.h).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "images.h"
#include "options.h"
#include "sunlapse/motion/view_warp.h"

namespace sunlapse::python {

void BindMotion(py::module_& m) {
  OptionsClass<ViewWarpOptions>(m, "ViewWarpOptions",
                                "Options of ViewWarp (view_warp.h).")
      .field("min_seen_share", &ViewWarpOptions::min_seen_share,
             "a frame seeing less of the reference view's model is out of "
             "view")
      .field("hidden_share", &ViewWarpOptions::hidden_share,
             "a point is hidden when the camera's ray hits the model this "
             "share of its distance nearer")
      .field("depth_step", &ViewWarpOptions::depth_step,
             "the frame's distance to the model cast on every this many "
             "pixels (1: all)");

  py::enum_<ViewWarpResult::Status>(m, "ViewWarpStatus")
      .value("OK", ViewWarpResult::Status::kOk)
      .value("OUT_OF_VIEW", ViewWarpResult::Status::kOutOfView)
      .value("NO_FRAME", ViewWarpResult::Status::kNoFrame);

  py::class_<ViewWarp>(
      m, "ViewWarp",
      "A moving camera's frames resampled into one reference view through "
      "the model (view_warp.h).")
      .def(py::init<const Scene&, const Camera&, const ViewWarpOptions&>(),
           py::arg("scene"), py::arg("reference"),
           py::arg("options") = ViewWarpOptions(), py::keep_alive<1, 2>())
      .def_property_readonly("reference", &ViewWarp::reference)
      .def_property_readonly("model_pixels", &ViewWarp::model_pixels)
      .def(
          "warp",
          [](const ViewWarp& w, const py::object& frame, const Camera& camera) {
            const cv::Mat in = GrayArg(frame);
            cv::Mat out;
            ViewWarpResult r;
            {
              py::gil_scoped_release release;
              r = w.Warp(in, camera, &out);
            }
            py::object gray = py::none();
            if (r.status == ViewWarpResult::Status::kOk)
              gray = MatAsArray(std::move(out));
            return py::make_tuple(gray, r.status, r.message, r.seen_share);
          },
          py::arg("frame"), py::arg("camera"),
          "(gray in the reference view with NaN where the frame does not see "
          "the model, or None; ViewWarpStatus; why not; seen share) for a "
          "float32 gray frame (or None) taken by `camera`.");

  py::class_<WarpedSource, FrameSource>(
      m, "WarpedSource",
      "A FrameSource whose frames come resampled into a ViewWarp's reference "
      "view: the frame with index i was taken by cameras[i] (None: no pose, "
      "why_not[i] saying why when given); resampled ahead on a thread of its "
      "own, queue_frames at most waiting (0: on the caller's).")
      .def(py::init([](FrameSource& inner, const ViewWarp& warp,
                       const std::vector<std::optional<Camera>>& cameras,
                       const std::vector<std::string>& why_not,
                       int queue_frames) {
             return std::make_unique<WarpedSource>(&inner, &warp, cameras,
                                                   why_not, queue_frames);
           }),
           py::arg("source"), py::arg("warp"), py::arg("cameras"),
           py::arg("why_not") = std::vector<std::string>(),
           py::arg("queue_frames") = 2, py::keep_alive<1, 2>(),
           py::keep_alive<1, 3>())
      .def_property_readonly("seconds", &WarpedSource::seconds,
                             "seconds spent resampling so far");
}

}  // namespace sunlapse::python
