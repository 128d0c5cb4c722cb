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

namespace {
// One figure of every frame of a pass as a numpy array of T.
template <typename T, typename Get>
py::array_t<T> PerFrame(const ClipPassResult& r, Get get) {
  py::array_t<T> out(static_cast<py::ssize_t>(r.frames.size()));
  auto v = out.template mutable_unchecked<1>();
  for (size_t k = 0; k < r.frames.size(); ++k)
    v(k) = static_cast<T>(get(r.frames[k]));
  return out;
}
}  // namespace

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

  // The pass's frames stay in native memory, asked for one at a time: a
  // Python object per frame and field costs kilobytes a frame on long
  // clips (issue 18: memory flat in the clip's length).
  py::class_<ClipPassResult>(m, "ClipPassResult",
                             "The frames of a clip pass (clip_pass.h).")
      .def_property_readonly("cancelled",
                             [](const ClipPassResult& r) {
                               return r.status ==
                                      ClipPassResult::Status::kCancelled;
                             })
      .def_readonly("tracker_started", &ClipPassResult::tracker_started)
      .def_readonly("tracking_seconds", &ClipPassResult::tracking_seconds)
      .def_readonly("start_seconds", &ClipPassResult::start_seconds)
      .def_readonly("seconds", &ClipPassResult::seconds)
      .def("__len__", [](const ClipPassResult& r) { return r.frames.size(); })
      .def_property_readonly(
          "status",
          [](const ClipPassResult& r) {
            return PerFrame<int8_t>(
                r, [](const ClipPassFrame& f) { return f.evidence.status; });
          },
          "int8 per frame: its FrameEvidenceStatus value")
      .def_property_readonly(
          "shadow_view",
          [](const ClipPassResult& r) {
            return PerFrame<float>(r, [](const ClipPassFrame& f) {
              return f.evidence.shadow_view;
            });
          },
          "float32 per frame: the share of the samples where shadows can show "
          "that the frame sees (below 1 for a moving camera's frame only)")
      .def(
          "reason",
          [](const ClipPassResult& r, size_t k) -> py::object {
            const ClipPassFrame& f = r.frames.at(k);
            const std::string& why =
                f.read_message.empty() ? f.evidence.message : f.read_message;
            if (why.empty()) return py::none();
            return py::str(why);
          },
          py::arg("k"), "why frame k has no evidence (None: no reason given)")
      .def(
          "track",
          [](const ClipPassResult& r, size_t k) -> py::object {
            const ClipPassFrame& f = r.frames.at(k);
            return f.tracked ? py::cast(f.track) : py::none();
          },
          py::arg("k"), "the tracker's Sun on frame k (TrackedFrame) or None")
      .def(
          "take_kept",
          [](ClipPassResult& r, size_t k) -> py::object {
            ClipPassFrame& f = r.frames.at(k);
            cv::Mat gray = f.Kept();
            f.kept_luma.release();
            f.kept_table.release();
            f.kept_gray.release();
            if (gray.empty()) return py::none();
            return MatAsArray(std::move(gray));
          },
          py::arg("k"),
          "frame k as the pass kept it (float32 linear gray), handed over "
          "(a second call gives None), or None when it was not kept");

  m.def(
      "run_clip_pass",
      [](FrameSource& source, const std::vector<int>& source_index,
         const py::list& kept, const std::vector<uint8_t>& segment_start,
         const Camera& camera, SkyEvidence& sky, ShadowTracker& tracker,
         const ClipPassOptions& options, const py::object& progress) {
        std::vector<cv::Mat> mats;
        for (const py::handle& f : kept)
          mats.push_back(GrayArg(py::reinterpret_borrow<py::object>(f)));
        const std::function<bool(double)> cb = WrapProgress(progress);
        ClipPassResult r;
        {
          py::gil_scoped_release release;
          r = RunClipPass(&source, source_index, mats, segment_start, camera,
                          &sky, &tracker, options, cb);
        }
        return r;
      },
      py::arg("source"), py::arg("source_index"), py::arg("kept"),
      py::arg("segment_start"), py::arg("camera"), py::arg("sky"),
      py::arg("tracker"), py::arg("options") = ClipPassOptions(),
      py::arg("progress") = py::none(),
      "The pass over a clip without Python's lock: each frame scored against "
      "the sky and followed by the tracker (clip_pass.h); a ClipPassResult. "
      "kept[k]: frame k already read (float32 gray) or None to take the "
      "source's next, whose index must be source_index[k]. "
      "progress(fraction) returning False cancels.");

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
