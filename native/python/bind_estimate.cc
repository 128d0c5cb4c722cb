// Bindings of the video and initial-Sun stages.
#include <pybind11/eigen.h>
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <opencv2/core.hpp>

#include "arrays.h"
#include "sunlapse/initial/initial_sun.h"
#include "sunlapse/tracking/shadow_tracker.h"
#include "sunlapse/tracking/thesis_tracker.h"
#include "sunlapse/tracking/unmodelled_shadows.h"
#include "sunlapse/video/video_reader.h"

namespace sunlapse::python {
namespace {

py::array_t<uint8_t> MatToArray(const cv::Mat& m) {
  const cv::Mat c = m.isContinuous() ? m : m.clone();
  py::array_t<uint8_t> out({c.rows, c.cols, c.channels()});
  std::memcpy(out.mutable_data(), c.data, c.total() * c.elemSize());
  return out;
}

// A progress callable from Python: (fraction) -> bool|None; None = go on.
ProgressCallback WrapProgress(const py::object& fn) {
  if (fn.is_none()) return nullptr;
  return [fn](double fraction) {
    py::gil_scoped_acquire gil;
    const py::object r = fn(fraction);
    return r.is_none() || r.cast<bool>();
  };
}

InitialSunMethod ParseMethod(const std::string& m) {
  if (m == "thesis") return InitialSunMethod::kThesis;
  if (m == "default") return InitialSunMethod::kDefault;
  throw std::invalid_argument("method: expected 'thesis' or 'default', got '" + m + "'");
}

// A cv::Mat viewing (not copying) a checked numpy image: float32 (H,W), or
// (H,W,3) too with `colour`.
cv::Mat FloatView(const py::array& a, const char* name, bool colour = false) {
  const bool three = colour && a.ndim() == 3;
  const float* data = three ? CheckArray<float>(a, name, {-1, -1, 3})
                            : CheckArray<float>(a, name, {-1, -1});
  return cv::Mat(static_cast<int>(a.shape(0)), static_cast<int>(a.shape(1)),
                 CV_32FC(three ? 3 : 1), const_cast<float*>(data));
}

// The same for a uint8 (H,W) mask.
cv::Mat MaskView(const py::array& a, const char* name) {
  const uint8_t* data = CheckArray<uint8_t>(a, name, {-1, -1});
  return cv::Mat(static_cast<int>(a.shape(0)), static_cast<int>(a.shape(1)), CV_8UC1,
                 const_cast<uint8_t*>(data));
}

cv::Mat GrayArg(const py::object& frame) {
  if (frame.is_none()) return {};  // an undecodable frame
  return FloatView(frame.cast<py::array>(), "frame");
}


// initialize() and track() of a tracker class, with the GIL released.
template <typename Tracker, typename Class>
void BindTrackerMethods(Class& cls) {
  cls.def(
         "initialize",
         [](Tracker& t, const py::object& frame, const Eigen::Vector3d& sun) {
           const cv::Mat img = GrayArg(frame);
           py::gil_scoped_release release;
           return t.Initialize(img, sun);
         },
         py::arg("frame"), py::arg("sun_in_world"),
         "First frame (float32 (H,W) gray) and the Sun found on it.")
      .def(
          "track",
          [](Tracker& t, const py::object& frame) {
            const cv::Mat img = GrayArg(frame);
            py::gil_scoped_release release;
            return t.Track(img);
          },
          py::arg("frame"),
          "Next frame (float32 (H,W) gray, or None if it could not be decoded).");
}

}  // namespace

void BindEstimate(py::module_& m) {
  py::class_<ShadowTracker> shadow_tracker(m, "ShadowTracker",
                            "Follows the Sun through a clip by the model's cast shadows "
                            "on the ground (metric; see shadow_tracker.h).");
  shadow_tracker.def(py::init([](const Scene& scene, const Camera& camera,
                       std::vector<int32_t> ground_object_ids, int ignore_top_rows,
                       int ignore_bottom_rows, int band_radius_px, int max_band_pixels,
                       double min_contrast, int subsamples, bool normalize_albedo) {
             ShadowTrackerOptions o;
             o.ground_object_ids = std::move(ground_object_ids);
             o.ignore_top_rows = ignore_top_rows;
             o.ignore_bottom_rows = ignore_bottom_rows;
             o.band_radius_px = band_radius_px;
             o.max_band_pixels = max_band_pixels;
             o.min_contrast = min_contrast;
             o.subsamples = subsamples;
             o.normalize_albedo = normalize_albedo;
             return std::make_unique<ShadowTracker>(scene, camera, o);
           }),
           py::arg("scene"), py::arg("camera"), py::arg("ground_object_ids"),
           py::arg("ignore_top_rows") = 0, py::arg("ignore_bottom_rows") = 0,
           py::arg("band_radius_px") = 4, py::arg("max_band_pixels") = 800,
           py::arg("min_contrast") = 0.5, py::arg("subsamples") = 2,
           py::arg("normalize_albedo") = true,
           py::keep_alive<1, 2>(), py::keep_alive<1, 3>());
  BindTrackerMethods<ShadowTracker>(shadow_tracker);
  py::class_<ThesisTracker> thesis_tracker(m, "ThesisTracker",
                            "The thesis's tracker (five criteria + Algorithm 1), the baseline.");
  thesis_tracker.def(py::init([](const Scene& scene, const Camera& camera,
                       std::vector<int32_t> ground_object_ids, int ignore_top_rows) {
             ThesisTrackerOptions o;
             o.ground_object_ids = std::move(ground_object_ids);
             o.ignore_top_rows = ignore_top_rows;
             return std::make_unique<ThesisTracker>(scene, camera, o);
           }),
           py::arg("scene"), py::arg("camera"), py::arg("ground_object_ids"),
           py::arg("ignore_top_rows") = 0, py::keep_alive<1, 2>(), py::keep_alive<1, 3>());
  BindTrackerMethods<ThesisTracker>(thesis_tracker);
  py::class_<TrackedFrame>(m, "TrackedFrame")
      .def_readonly("ok", &TrackedFrame::ok)
      .def_readonly("reason", &TrackedFrame::reason)
      .def_readonly("zenith_deg", &TrackedFrame::zenith_deg)
      .def_readonly("azimuth_deg", &TrackedFrame::azimuth_deg)
      .def_readonly("sun_in_world", &TrackedFrame::sun_in_world)
      .def_readonly("confidence", &TrackedFrame::confidence)
      .def_readonly("contrast", &TrackedFrame::contrast)
      .def_readonly("band_pixels", &TrackedFrame::band_pixels)
      .def_readonly("rays", &TrackedFrame::rays)
      .def_readonly("evaluations", &TrackedFrame::evaluations)
      .def_readonly("shadow_start_px", &TrackedFrame::shadow_start_px)
      .def_readonly("shadow_end_px", &TrackedFrame::shadow_end_px)
      .def_readonly("seconds", &TrackedFrame::seconds);

  py::enum_<FrameStatus>(m, "FrameStatus", "What became of one frame a VideoReader returned.")
      .value("ok", FrameStatus::kOk)
      .value("undecodable", FrameStatus::kUndecodable)
      .value("size_changed", FrameStatus::kSizeChanged)
      .value("missing_file", FrameStatus::kMissingFile);
  py::class_<FrameReport>(m, "FrameReport")
      .def_readonly("index", &FrameReport::index)
      .def_readonly("status", &FrameReport::status)
      .def_readonly("width", &FrameReport::width)
      .def_readonly("height", &FrameReport::height)
      .def_readonly("message", &FrameReport::message);

  py::class_<VideoReader>(m, "VideoReader",
                          "Frames of a movie file or a numbered image sequence, streamed.")
      .def(py::init<const std::string&>(), py::arg("path"))
      .def_property_readonly("width", &VideoReader::width)
      .def_property_readonly("height", &VideoReader::height)
      .def_property_readonly("fps", &VideoReader::fps)
      .def_property_readonly("num_frames", &VideoReader::num_frames)
      .def_property_readonly("position", &VideoReader::position)
      .def_property_readonly("num_frames_exact", &VideoReader::num_frames_exact)
      .def_property_readonly("is_sequence", &VideoReader::is_sequence)
      .def_property_readonly("last_frame", &VideoReader::last_frame,
                             "FrameReport of the last read(): status, index, decoded size.")
      .def("count_frames", &VideoReader::CountFrames, py::call_guard<py::gil_scoped_release>(),
           "Counts a movie's frames in the file (no decoding); num_frames is exact after.")
      .def(
          "read",
          [](VideoReader& r) -> py::object {
            cv::Mat bgr;
            bool more;
            {
              py::gil_scoped_release release;
              more = r.Read(&bgr);
            }
            if (!more) throw py::stop_iteration();
            if (bgr.empty()) return py::none();
            return MatToArray(bgr);
          },
          "Next frame as uint8 (H,W,3) BGR; None for a frame that cannot be "
          "decoded; raises StopIteration at the end.")
      .def("seek", &VideoReader::Seek, py::arg("index"),
           py::call_guard<py::gil_scoped_release>())
      .def("__iter__", [](py::object self) { return self; })
      .def("__next__", [](py::object self) { return self.attr("read")(); });

  m.def(
      "detect_unmodelled_shadows",
      [](const py::array& frame, const py::object& background, const py::array& ground,
         const py::array& model_shadow, double dark_ratio, double max_chroma_ratio,
         int model_margin_px, double min_area_fraction, double min_edge_contrast,
         int registration_px) {
        // float32 (H,W) gray or (H,W,3) linear BGR; masks uint8 (H,W).
        const cv::Mat f = FloatView(frame, "frame", true);
        const cv::Mat b = background.is_none()
                              ? cv::Mat()
                              : FloatView(background.cast<py::array>(), "background", true);
        const cv::Mat g = MaskView(ground, "ground"), s = MaskView(model_shadow, "model_shadow");
        UnmodelledShadowOptions o;
        o.dark_ratio = dark_ratio;
        o.max_chroma_ratio = max_chroma_ratio;
        o.model_margin_px = model_margin_px;
        o.min_area_fraction = min_area_fraction;
        o.min_edge_contrast = min_edge_contrast;
        o.registration_px = registration_px;
        UnmodelledShadows r;
        {
          py::gil_scoped_release release;
          r = DetectUnmodelledShadows(f, b, g, s, o);
        }
        py::array_t<uint8_t> out_mask({r.mask.rows, r.mask.cols});
        std::memcpy(out_mask.mutable_data(), r.mask.data, r.mask.total());
        py::list regions;
        for (const UnmodelledShadow& u : r.regions) {
          py::dict d;
          d["area_px"] = u.area_px;
          d["box"] = py::make_tuple(u.box.x, u.box.y, u.box.width, u.box.height);
          d["centroid_px"] = py::make_tuple(u.centroid_px.x(), u.centroid_px.y());
          d["darkening"] = u.darkening;
          d["edge_contrast"] = u.edge_contrast;
          d["touches_model"] = u.touches_model;
          regions.append(d);
        }
        py::dict d;
        d["mask"] = out_mask;
        d["regions"] = regions;
        return d;
      },
      py::arg("frame").noconvert(), py::arg("background"),
      py::arg("ground").noconvert(), py::arg("model_shadow").noconvert(),
      py::arg("dark_ratio") = 0.7, py::arg("max_chroma_ratio") = 2.5,
      py::arg("model_margin_px") = 2, py::arg("min_area_fraction") = 2e-4,
      py::arg("min_edge_contrast") = 2.5, py::arg("registration_px") = 2,
      "Hard ground shadows the model does not explain: {'mask': uint8 (H,W) 255 on "
      "them, 'regions': [{'area_px', 'box', 'centroid_px', 'darkening', "
      "'edge_contrast', 'touches_model'}]}. frame/background float32 gray (H,W) or linear BGR (H,W,3), "
      "background None for the frame alone; "
      "ground/model_shadow uint8 (H,W) masks.");

  m.def(
      "to_linear_gray",
      [](const py::array& bgr, double gamma) {
        CheckArray<uint8_t>(bgr, "image", {-1, -1, 3});
        const cv::Mat in(static_cast<int>(bgr.shape(0)), static_cast<int>(bgr.shape(1)), CV_8UC3,
                         const_cast<void*>(bgr.data()));
        const cv::Mat g = ToLinearGray(in, gamma);
        py::array_t<float> out({g.rows, g.cols});
        std::memcpy(out.mutable_data(), g.data, g.total() * sizeof(float));
        return out;
      },
      py::arg("image").noconvert(), py::arg("gamma") = 2.2,
      "uint8 (H,W,3) BGR -> float32 (H,W) linear gray in [0,1] (value^gamma).");

  m.def(
      "estimate_initial_sun",
      [](const Scene& scene, const Camera& camera, const py::array& frame,
         const std::string& method, int max_pixels, int ignore_top_rows,
         int ignore_bottom_rows, int num_candidates, double loss_scale,
         bool per_object_albedo, int thesis_num_lights, const py::object& progress) {
        const cv::Mat img = FloatView(frame, "frame");
        InitialSunOptions o;
        o.method = ParseMethod(method);
        o.max_pixels = max_pixels;
        o.ignore_top_rows = ignore_top_rows;
        o.ignore_bottom_rows = ignore_bottom_rows;
        o.num_candidates = num_candidates;
        o.loss_scale = loss_scale;
        o.per_object_albedo = per_object_albedo;
        o.thesis_num_lights = thesis_num_lights;
        const ProgressCallback cb = WrapProgress(progress);
        InitialSunResult r;
        {
          py::gil_scoped_release release;
          r = EstimateInitialSun(scene, camera, img, o, cb);
        }
        py::dict d;
        d["success"] = r.success;
        d["message"] = r.message;
        d["zenith_deg"] = r.zenith_deg;
        d["azimuth_deg"] = r.azimuth_deg;
        d["sun_in_world"] = r.sun_in_world;
        d["sun_intensity"] = r.sun_intensity;
        d["ambient_intensity"] = r.ambient_intensity;
        d["light_intensities"] = r.light_intensities;
        d["albedo_per_object"] = r.albedo_per_object;
        d["residual_rms"] = r.residual_rms;
        d["inlier_fraction"] = r.inlier_fraction;
        d["loss_scale_abs"] = r.loss_scale_abs;
        d["spread_deg"] = r.spread_deg;
        d["confidence"] = r.confidence;
        d["num_pixels"] = r.num_pixels;
        d["seconds"] = r.seconds;
        return d;
      },
      py::arg("scene"), py::arg("camera"), py::arg("frame").noconvert(),
      py::arg("method") = "default", py::arg("max_pixels") = 12000,
      py::arg("ignore_top_rows") = 0, py::arg("ignore_bottom_rows") = 0,
      py::arg("num_candidates") = 300, py::arg("loss_scale") = 0.35,
      py::arg("per_object_albedo") = true, py::arg("thesis_num_lights") = 8,
      py::arg("progress") = py::none(),
      "Sun direction on one frame (float32 (H,W) linear gray, the camera's "
      "size). Azimuth is in the world frame (clockwise from +Y). Returns a "
      "dict; success False with a message when the frame cannot fix the Sun "
      "or the run was cancelled (progress returned False).");
}

}  // namespace sunlapse::python
