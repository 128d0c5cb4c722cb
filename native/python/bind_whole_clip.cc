// Bindings of the whole-clip pass (whole_clip/clip_pass.h).
#include <pybind11/eigen.h>
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "images.h"
#include "options.h"
#include "progress.h"
#include "sunlapse/video/video_reader.h"
#include "sunlapse/whole_clip/clip_pass.h"

namespace sunlapse::python {

void BindWholeClip(py::module_& m) {
  OptionsClass<ClipPassOptions>(m, "ClipPassOptions",
                                "Options of run_clip_pass (clip_pass.h).")
      .field("start_margin", &ClipPassOptions::start_margin,
             "evidence lead that starts the tracker (log-likelihood)")
      .field("steer_deg", &ClipPassOptions::steer_deg,
             "drift from unmistakable evidence that steers the tracker (deg)")
      .field("progress_every", &ClipPassOptions::progress_every,
             "frames between progress calls")
      .field("keep_off_deg", &ClipPassOptions::keep_off_deg,
             "keep frames tracked this far from their own evidence (deg)")
      .field("keep_max_frames", &ClipPassOptions::keep_max_frames,
             "keep at most this many frames for the check");

  py::class_<ClipPassFrame>(m, "ClipPassFrame", "One frame of a clip pass.")
      .def_readonly("index", &ClipPassFrame::index)
      .def_readonly("read_message", &ClipPassFrame::read_message)
      .def_readonly("evidence", &ClipPassFrame::evidence)
      .def_property_readonly("track",
                             [](const ClipPassFrame& f) -> py::object {
                               return f.tracked ? py::cast(f.track)
                                                : py::none();
                             })
      .def_property_readonly("gray", [](const ClipPassFrame& f) -> py::object {
        if (f.gray.empty()) return py::none();
        return MatAsArray(f.gray);
      });

  m.def(
      "run_clip_pass",
      [](FrameSource& source, const std::vector<int>& source_index,
         const py::list& kept, const std::vector<uint8_t>& segment_start,
         const Camera& camera, SkyEvidence& sky, ShadowTracker& tracker,
         const Camera& tracker_camera, const ClipPassOptions& options,
         const py::object& progress) {
        std::vector<cv::Mat> mats;
        for (const py::handle& f : kept)
          mats.push_back(GrayArg(py::reinterpret_borrow<py::object>(f)));
        const std::function<bool(double)> cb = WrapProgress(progress);
        ClipPassResult r;
        {
          py::gil_scoped_release release;
          r = RunClipPass(&source, source_index, mats, segment_start, camera,
                          &sky, &tracker, tracker_camera, options, cb);
        }
        py::dict out;
        out["cancelled"] = r.status == ClipPassResult::Status::kCancelled;
        out["frames"] = py::cast(std::move(r.frames));
        out["tracker_started"] = r.tracker_started;
        out["tracking_seconds"] = r.tracking_seconds;
        out["start_seconds"] = r.start_seconds;
        out["seconds"] = r.seconds;
        return out;
      },
      py::arg("source"), py::arg("source_index"), py::arg("kept"),
      py::arg("segment_start"), py::arg("camera"), py::arg("sky"),
      py::arg("tracker"), py::arg("tracker_camera"),
      py::arg("options") = ClipPassOptions(), py::arg("progress") = py::none(),
      "The pass over a clip without Python's lock: each frame scored against "
      "the sky and followed by the tracker (clip_pass.h). kept[k]: frame k "
      "already read (float32 gray) or None to take the source's next, whose "
      "index must be source_index[k]. progress(fraction) returning False "
      "cancels.");

  m.def(
      "resized_gray",
      [](const py::array& frame, int width, int height) -> py::object {
        const cv::Mat img = FloatView(frame, "frame");
        cv::Mat out;
        {
          py::gil_scoped_release release;
          // A copy even at the same size: the result must not share the
          // caller's array.
          out = AreaReduced(img, cv::Size(width, height)).clone();
        }
        return MatAsArray(std::move(out));
      },
      py::arg("frame"), py::arg("width"), py::arg("height"),
      "float32 (H,W) gray resized (area average) to width x height.");

  m.def(
      "start_tracker",
      [](ShadowTracker& tracker, const py::array& frame,
         const Eigen::Vector3d& sun_in_world, double refine_max_deg) {
        const cv::Mat img = FloatView(frame, "frame");
        TrackedFrame refined;
        bool started;
        {
          py::gil_scoped_release release;
          started = StartTracker(&tracker, img, sun_in_world, refine_max_deg,
                                 &refined);
        }
        return py::make_tuple(
            started, refined.ok ? py::cast(refined) : py::object(py::none()));
      },
      py::arg("tracker"), py::arg("frame"), py::arg("sun_in_world"),
      py::arg("refine_max_deg"),
      "Starts the tracker on a frame under a grid direction, refined once: "
      "(started, its refined TrackedFrame or None).");
}

}  // namespace sunlapse::python
