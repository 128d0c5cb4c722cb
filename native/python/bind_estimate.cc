// Bindings of the video and initial-Sun stages.
#include <pybind11/eigen.h>
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <opencv2/core.hpp>

#include "arrays.h"
#include "images.h"
#include "options.h"
#include "progress.h"
#include "sunlapse/initial/initial_sun.h"
#include "sunlapse/tracking/shadow_tracker.h"
#include "sunlapse/tracking/thesis_tracker.h"
#include "sunlapse/tracking/unmodelled_shadows.h"
#include "sunlapse/video/frame_stream.h"
#include "sunlapse/video/video_reader.h"

namespace sunlapse::python {
namespace {

// The reader's next frame (BGR or gray) as numpy; None for a frame that
// cannot be decoded; StopIteration at the end.
py::object NextFrame(VideoReader& r, bool gray) {
  cv::Mat image;
  bool more;
  {
    py::gil_scoped_release release;
    more = gray ? r.ReadGray(&image) : r.Read(&image);
  }
  if (!more) throw py::stop_iteration();
  if (image.empty()) return py::none();
  return MatAsArray(std::move(image));
}

// DetectUnmodelledShadows' result with its mask as numpy.
struct UnmodelledShadowsResult {
  py::array mask;
  std::vector<UnmodelledShadow> regions;
};

InitialSunMethod ParseMethod(const std::string& m) {
  if (m == "thesis") return InitialSunMethod::kThesis;
  if (m == "default") return InitialSunMethod::kDefault;
  throw std::invalid_argument("method: expected 'thesis' or 'default', got '" +
                              m + "'");
}

std::string MethodName(InitialSunMethod m) {
  return m == InitialSunMethod::kThesis ? "thesis" : "default";
}

void BindOptions(py::module_& m) {
  OptionsClass<InitialSunOptions>(m, "InitialSunOptions",
                                  "Options of estimate_initial_sun.")
      .field_property(
          "method",
          [](const InitialSunOptions& o) { return MethodName(o.method); },
          [](InitialSunOptions& o, const std::string& name) {
            o.method = ParseMethod(name);
          },
          "'default' (ours) or 'thesis' (the baseline).")
      .field("max_pixels", &InitialSunOptions::max_pixels,
             "At most this many pixels are used (a regular grid).")
      .field("ignore_top_rows", &InitialSunOptions::ignore_top_rows,
             "Rows at the top that are not scene content (banners).")
      .field("ignore_bottom_rows", &InitialSunOptions::ignore_bottom_rows,
             "Rows at the bottom that are not scene content.")
      .field("min_intensity", &InitialSunOptions::min_intensity,
             "Pixels darker than this (linear, [0, 1]) are not used.")
      .field("max_intensity", &InitialSunOptions::max_intensity,
             "Pixels brighter than this (clipped) are not used.")
      .field("thesis_num_lights", &InitialSunOptions::thesis_num_lights,
             "Thesis method: lights on the hemisphere.")
      .field("thesis_light_elevation_deg",
             &InitialSunOptions::thesis_light_elevation_deg,
             "Thesis method: the lights' elevation, degrees.")
      .field("num_candidates", &InitialSunOptions::num_candidates,
             "Candidate directions on the upper hemisphere (Fibonacci).")
      .field("num_refine_starts", &InitialSunOptions::num_refine_starts,
             "Best separated candidates refined continuously.")
      .field("refine_tolerance_deg", &InitialSunOptions::refine_tolerance_deg,
             "Refinement stops below this step, degrees.")
      .field("loss_scale", &InitialSunOptions::loss_scale,
             "Cauchy scale as a fraction of the used pixels' median.")
      .field("per_object_albedo", &InitialSunOptions::per_object_albedo,
             "One albedo per object (else one for the whole model).")
      .field("max_zenith_deg", &InitialSunOptions::max_zenith_deg,
             "Candidate Suns lie at most this far from the zenith, degrees.");

  OptionsClass<ShadowTrackerOptions>(m, "ShadowTrackerOptions",
                                     "Options of ShadowTracker.")
      .field("ground_object_ids", &ShadowTrackerOptions::ground_object_ids,
             "Object ids of the ground the shadows fall on (at least one).")
      .field("all_surfaces", &ShadowTrackerOptions::all_surfaces,
             "Shadows tracked on every model surface in view, not the ground "
             "alone.")
      .field("surfaces_pin_deg", &ShadowTrackerOptions::surfaces_pin_deg,
             "Height left open by the ground beyond this: fitted again on "
             "every surface, degrees; 0 never.")
      .field("band_radius_px", &ShadowTrackerOptions::band_radius_px,
             "Half-width of the band around predicted shadow boundaries, px.")
      .field("max_band_pixels", &ShadowTrackerOptions::max_band_pixels,
             "At most this many band pixels per frame.")
      .field("search_step_deg", &ShadowTrackerOptions::search_step_deg,
             "Largest first search step around the predicted Sun, degrees.")
      .field("tolerance_deg", &ShadowTrackerOptions::tolerance_deg,
             "Final search step, degrees.")
      .field("loss_scale", &ShadowTrackerOptions::loss_scale,
             "Cauchy scale as a fraction of the band's median intensity.")
      .field("min_contrast", &ShadowTrackerOptions::min_contrast,
             "Shadow lost below this fitted sun/ambient contrast.")
      .field("subsamples", &ShadowTrackerOptions::subsamples,
             "Rays per band pixel along each axis.")
      .field("ignore_top_rows", &ShadowTrackerOptions::ignore_top_rows,
             "Rows at the top that are not scene content.")
      .field("ignore_bottom_rows", &ShadowTrackerOptions::ignore_bottom_rows,
             "Rows at the bottom that are not scene content.")
      .field("normalize_albedo", &ShadowTrackerOptions::normalize_albedo,
             "Per-pixel ground albedo from the first frame.");

  OptionsClass<ThesisTrackerOptions>(m, "ThesisTrackerOptions",
                                     "Options of ThesisTracker.")
      .field("ground_object_ids", &ThesisTrackerOptions::ground_object_ids,
             "Object ids of the ground the shadows fall on (at least one).")
      .field("max_direction_error_deg",
             &ThesisTrackerOptions::max_direction_error_deg,
             "Criterion 1: shadows further than this from the Sun's "
             "direction go, degrees.")
      .field("slope_start", &ThesisTrackerOptions::slope_start,
             "Algorithm 1: pixels whose direction starts the walk.")
      .field("slope_window", &ThesisTrackerOptions::slope_window,
             "Algorithm 1: last pixels compared with the start.")
      .field("max_slope_change_deg",
             &ThesisTrackerOptions::max_slope_change_deg,
             "Algorithm 1: the walk stops past this change, degrees.")
      .field("max_length_px", &ThesisTrackerOptions::max_length_px,
             "Hard stop for a walk, pixels.")
      .field("ignore_top_rows", &ThesisTrackerOptions::ignore_top_rows,
             "Rows at the top that are not scene content.");

  OptionsClass<UnmodelledShadowOptions>(m, "UnmodelledShadowOptions",
                                        "Options of detect_unmodelled_shadows.")
      .field("dark_ratio", &UnmodelledShadowOptions::dark_ratio,
             "Dark: frame / background below this share of the lit level.")
      .field("max_chroma_ratio", &UnmodelledShadowOptions::max_chroma_ratio,
             "Largest / smallest channel ratio at most this (colour input).")
      .field("level_window", &UnmodelledShadowOptions::level_window,
             "Lit level over windows of this share of the width.")
      .field("model_margin_px", &UnmodelledShadowOptions::model_margin_px,
             "The model's predicted shadow is widened by this many pixels.")
      .field("min_area_fraction", &UnmodelledShadowOptions::min_area_fraction,
             "Regions smaller than this share of the ground go.")
      .field("min_edge_contrast", &UnmodelledShadowOptions::min_edge_contrast,
             "Hard edge: rim energy at least this times the ground's median.")
      .field("registration_px", &UnmodelledShadowOptions::registration_px,
             "Compared with the darkest background within this many pixels.");
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
          "Next frame (float32 (H,W) gray, or None if it could not be "
          "decoded).");
}

}  // namespace

void BindEstimate(py::module_& m) {
  py::enum_<InitialSunResult::Status>(m, "InitialSunStatus")
      .value("SUCCESS", InitialSunResult::Status::kSuccess)
      .value("TOO_FEW_PIXELS", InitialSunResult::Status::kTooFewPixels)
      .value("NO_LIGHT", InitialSunResult::Status::kNoLight)
      .value("CANCELLED", InitialSunResult::Status::kCancelled);

  py::class_<InitialSunResult>(m, "InitialSunResult",
                               "The initial Sun on one frame (initial_sun.h).")
      .def_readonly("status", &InitialSunResult::status)
      .def_readonly("message", &InitialSunResult::message)
      .def_readonly("zenith_deg", &InitialSunResult::zenith_deg)
      .def_readonly("azimuth_deg", &InitialSunResult::azimuth_deg,
                    "world azimuth, clockwise from +Y")
      .def_readonly("sun_in_world", &InitialSunResult::sun_in_world)
      .def_readonly("sun_intensity", &InitialSunResult::sun_intensity)
      .def_readonly("ambient_intensity", &InitialSunResult::ambient_intensity)
      .def_readonly("light_intensities", &InitialSunResult::light_intensities)
      .def_readonly("albedo_per_object", &InitialSunResult::albedo_per_object)
      .def_readonly("residual_rms", &InitialSunResult::residual_rms)
      .def_readonly("inlier_fraction", &InitialSunResult::inlier_fraction)
      .def_readonly("loss_scale_abs", &InitialSunResult::loss_scale_abs)
      .def_readonly("spread_deg", &InitialSunResult::spread_deg)
      .def_readonly("confidence", &InitialSunResult::confidence)
      .def_readonly("num_pixels", &InitialSunResult::num_pixels)
      .def_readonly("seconds", &InitialSunResult::seconds);

  py::class_<UnmodelledShadow>(m, "UnmodelledShadow",
                               "A hard ground shadow the model does not cast.")
      .def_readonly("area_px", &UnmodelledShadow::area_px)
      .def_property_readonly("box",
                             [](const UnmodelledShadow& u) {
                               return py::make_tuple(u.box.x, u.box.y,
                                                     u.box.width, u.box.height);
                             })
      .def_property_readonly("centroid_px",
                             [](const UnmodelledShadow& u) {
                               return py::make_tuple(u.centroid_px.x(),
                                                     u.centroid_px.y());
                             })
      .def_readonly("darkening", &UnmodelledShadow::darkening)
      .def_readonly("edge_contrast", &UnmodelledShadow::edge_contrast)
      .def_readonly("touches_model", &UnmodelledShadow::touches_model);

  py::class_<UnmodelledShadowsResult>(m, "UnmodelledShadows")
      .def_readonly("mask", &UnmodelledShadowsResult::mask,
                    "uint8 (H,W), 255 on the regions")
      .def_readonly("regions", &UnmodelledShadowsResult::regions);

  BindOptions(m);
  py::class_<ShadowTracker> shadow_tracker(
      m, "ShadowTracker",
      "Follows the Sun through a clip by the model's cast shadows "
      "on the ground (metric; see shadow_tracker.h).");
  shadow_tracker.def(
      py::init([](const Scene& scene, const Camera& camera,
                  const py::object& ground_object_ids,
                  const py::object& options, const py::kwargs& kwargs) {
        ShadowTrackerOptions o =
            OptionsFrom<ShadowTrackerOptions>(options, py::kwargs());
        if (!ground_object_ids.is_none()) {
          o.ground_object_ids = ground_object_ids.cast<std::vector<int32_t>>();
        }
        return std::make_unique<ShadowTracker>(scene, camera,
                                               OptionsFrom(o, kwargs));
      }),
      py::arg("scene"), py::arg("camera"),
      py::arg("ground_object_ids") = py::none(), py::kw_only(),
      py::arg("options") = py::none(), py::keep_alive<1, 2>(),
      py::keep_alive<1, 3>(),
      "ShadowTracker(scene, camera, ground_object_ids, options=None, "
      "**fields of ShadowTrackerOptions).");
  BindTrackerMethods<ShadowTracker>(shadow_tracker);
  shadow_tracker.def("prepare", &ShadowTracker::Prepare,
                     py::call_guard<py::gil_scoped_release>(),
                     "Maps the ground and finds the casters now (else the "
                     "first initialize does); releases Python's lock.");
  shadow_tracker.def(
      "track_toward",
      [](ShadowTracker& t, const py::object& frame,
         const Eigen::Vector3d& predicted) {
        const cv::Mat img = GrayArg(frame);
        py::gil_scoped_release release;
        return t.Track(img, predicted);
      },
      py::arg("frame"), py::arg("predicted_sun_in_world"),
      "Next frame, searched around the given Sun (the whole-clip path's) "
      "instead of the tracker's own prediction.");
  py::class_<ThesisTracker> thesis_tracker(
      m, "ThesisTracker",
      "The thesis's tracker (five criteria + Algorithm 1), the baseline.");
  thesis_tracker.def(
      py::init([](const Scene& scene, const Camera& camera,
                  const py::object& ground_object_ids,
                  const py::object& options, const py::kwargs& kwargs) {
        ThesisTrackerOptions o =
            OptionsFrom<ThesisTrackerOptions>(options, py::kwargs());
        if (!ground_object_ids.is_none()) {
          o.ground_object_ids = ground_object_ids.cast<std::vector<int32_t>>();
        }
        return std::make_unique<ThesisTracker>(scene, camera,
                                               OptionsFrom(o, kwargs));
      }),
      py::arg("scene"), py::arg("camera"),
      py::arg("ground_object_ids") = py::none(), py::kw_only(),
      py::arg("options") = py::none(), py::keep_alive<1, 2>(),
      py::keep_alive<1, 3>(),
      "ThesisTracker(scene, camera, ground_object_ids, options=None, "
      "**fields of ThesisTrackerOptions).");
  BindTrackerMethods<ThesisTracker>(thesis_tracker);
  py::enum_<TrackedFrame::Status>(m, "TrackedFrameStatus",
                                  "What became of a tracked frame.")
      .value("tracked", TrackedFrame::Status::kTracked)
      .value("unusable_frame", TrackedFrame::Status::kUnusableFrame)
      .value("no_ground_in_view", TrackedFrame::Status::kNoGroundInView)
      .value("no_shadow_in_view", TrackedFrame::Status::kNoShadowInView)
      .value("band_out_of_view", TrackedFrame::Status::kBandOutOfView)
      .value("band_on_ground_only", TrackedFrame::Status::kBandOnGroundOnly)
      .value("no_match", TrackedFrame::Status::kNoMatch)
      .value("no_contrast", TrackedFrame::Status::kNoContrast);
  py::class_<TrackedFrame>(m, "TrackedFrame")
      .def_readonly("ok", &TrackedFrame::ok)
      .def_readonly("status", &TrackedFrame::status)
      .def_readonly("reason", &TrackedFrame::reason)
      .def_readonly("zenith_deg", &TrackedFrame::zenith_deg)
      .def_readonly("azimuth_deg", &TrackedFrame::azimuth_deg)
      .def_readonly("sun_in_world", &TrackedFrame::sun_in_world)
      .def_readonly("confidence", &TrackedFrame::confidence)
      .def_readonly("contrast", &TrackedFrame::contrast)
      .def_readonly("band_pixels", &TrackedFrame::band_pixels)
      .def_readonly("misfit", &TrackedFrame::misfit)
      .def_readonly("elevation_pinned_deg", &TrackedFrame::elevation_pinned_deg)
      .def_readonly("rays", &TrackedFrame::rays)
      .def_readonly("evaluations", &TrackedFrame::evaluations)
      .def_readonly("shadow_start_px", &TrackedFrame::shadow_start_px)
      .def_readonly("shadow_end_px", &TrackedFrame::shadow_end_px)
      .def_readonly("seconds", &TrackedFrame::seconds);

  py::enum_<FrameStatus>(m, "FrameStatus",
                         "What became of one frame a VideoReader returned.")
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

  py::class_<VideoReader>(
      m, "VideoReader",
      "Frames of a movie file or a numbered image sequence, streamed.")
      .def(py::init<const std::string&>(), py::arg("path"))
      .def_property_readonly("width", &VideoReader::width)
      .def_property_readonly("height", &VideoReader::height)
      .def_property_readonly("fps", &VideoReader::fps)
      .def_property_readonly("num_frames", &VideoReader::num_frames)
      .def_property_readonly("position", &VideoReader::position)
      .def_property_readonly("num_frames_exact", &VideoReader::num_frames_exact)
      .def_property_readonly("is_sequence", &VideoReader::is_sequence)
      .def_property_readonly(
          "last_frame", &VideoReader::last_frame,
          "FrameReport of the last read(): status, index, decoded size.")
      .def("count_frames", &VideoReader::CountFrames,
           py::call_guard<py::gil_scoped_release>(),
           "Counts a movie's frames in the file (no decoding); num_frames is "
           "exact after.")
      .def(
          "read", [](VideoReader& r) { return NextFrame(r, false); },
          "Next frame as uint8 (H,W,3) BGR; None for a frame that cannot be "
          "decoded; raises StopIteration at the end.")
      .def(
          "read_gray", [](VideoReader& r) { return NextFrame(r, true); },
          "Next frame as uint8 (H,W) gray (the luma as decoded, no colour "
          "conversion); None for a frame that cannot be decoded; raises "
          "StopIteration at the end.")
      .def("seek", &VideoReader::Seek, py::arg("index"),
           py::call_guard<py::gil_scoped_release>())
      .def("__iter__", [](py::object self) { return self; })
      .def("__next__", [](py::object self) { return self.attr("read")(); });

  py::enum_<StreamedFrame::Status>(m, "StreamedFrameStatus")
      .value("ok", StreamedFrame::Status::kOk)
      .value("unusable", StreamedFrame::Status::kUnusable)
      .value("past_end", StreamedFrame::Status::kPastEnd);
  py::class_<StreamedFrame>(m, "StreamedFrame", "One frame of a FrameStream.")
      .def_readonly("index", &StreamedFrame::index)
      .def_readonly("status", &StreamedFrame::status)
      .def_readonly("report", &StreamedFrame::report)
      .def_readonly("message", &StreamedFrame::message)
      .def_property_readonly("gray",
                             [](const StreamedFrame& f) -> py::object {
                               if (f.gray.empty()) return py::none();
                               return MatAsArray(f.gray);
                             })
      .def_property_readonly("bgr", [](const StreamedFrame& f) -> py::object {
        if (f.bgr.empty()) return py::none();
        return MatAsArray(f.bgr);
      });
  OptionsClass<FrameStreamOptions>(m, "FrameStreamOptions",
                                   "Options of FrameStream (frame_stream.h).")
      .field("queue_frames", &FrameStreamOptions::queue_frames,
             "decoded frames waiting at most")
      .field("gamma", &FrameStreamOptions::gamma, "linear gray is value^gamma")
      .field("keep_bgr", &FrameStreamOptions::keep_bgr,
             "also hand out the uint8 BGR frame")
      .field("bgr_width", &FrameStreamOptions::bgr_width,
             "keep_bgr: BGR scaled to this width (0: as decoded)")
      .field("bgr_height", &FrameStreamOptions::bgr_height,
             "keep_bgr: BGR scaled to this height (0: as decoded)")
      .field("near", &FrameStreamOptions::near,
             "each frame the cheapest to reach at or before the one asked")
      .field("near_min_frames", &FrameStreamOptions::near_min_frames,
             "near: key frames alone when at least this many")
      .field("width", &FrameStreamOptions::width,
             "gray frames reduced to this width (0: as decoded)")
      .field("height", &FrameStreamOptions::height,
             "gray frames reduced to this height (0: as decoded)")
      .field("decode_threads", &FrameStreamOptions::decode_threads,
             "threads decoding an image sequence side by side (0: one per "
             "core)");
  py::class_<FrameSource>(m, "FrameSource",
                          "Where a pass over a clip takes its frames from.");
  py::class_<FrameList, FrameSource>(
      m, "FrameList",
      "Frames already in memory as a FrameSource (tests, synthetic clips).")
      .def(py::init([](const py::list& items) {
             // (index, float32 (H,W) gray | None | reason str) per frame;
             // the frames are copied.
             std::vector<StreamedFrame> frames;
             for (const py::handle& h : items) {
               const py::tuple t = h.cast<py::tuple>();
               StreamedFrame f;
               f.index = t[0].cast<int>();
               const py::object v = t[1];
               if (py::isinstance<py::str>(v)) {
                 f.status = StreamedFrame::Status::kUnusable;
                 f.message = v.cast<std::string>();
               } else if (v.is_none()) {
                 f.status = StreamedFrame::Status::kUnusable;
                 f.message = "frame not decodable";
               } else {
                 f.status = StreamedFrame::Status::kOk;
                 f.gray = FloatView(v.cast<py::array>(), "frame").clone();
               }
               frames.push_back(std::move(f));
             }
             return std::make_unique<FrameList>(std::move(frames));
           }),
           py::arg("frames"));
  py::class_<FrameStream, FrameSource>(
      m, "FrameStream",
      "Frames decoded ahead on a thread of their own, as linear gray, in the "
      "order asked (0-based clip indices). Iterate for StreamedFrame.")
      .def(py::init<const std::string&, std::vector<int>,
                    const FrameStreamOptions&>(),
           py::arg("path"), py::arg("indices"),
           py::arg("options") = FrameStreamOptions())
      .def_property_readonly("width", &FrameStream::width)
      .def_property_readonly("height", &FrameStream::height)
      .def_property_readonly("frames_independent",
                             &FrameStream::frames_independent,
                             "Each frame decodes on its own (an image "
                             "sequence, an intra-only codec).")
      .def_property_readonly("wait_seconds", &FrameStream::wait_seconds)
      .def("__len__", &FrameStream::size)
      .def("__iter__", [](py::object self) { return self; })
      .def("__next__", [](FrameStream& s) {
        StreamedFrame f;
        bool more;
        {
          py::gil_scoped_release release;
          more = s.Next(&f);
        }
        if (!more) throw py::stop_iteration();
        return f;
      });

  m.def(
      "detect_unmodelled_shadows",
      [](const py::array& frame, const py::object& background,
         const py::array& ground, const py::array& model_shadow,
         const py::object& options, const py::kwargs& kwargs) {
        // float32 (H,W) gray or (H,W,3) linear BGR; masks uint8 (H,W).
        const cv::Mat f = FloatView(frame, "frame", true);
        const cv::Mat b =
            background.is_none()
                ? cv::Mat()
                : FloatView(background.cast<py::array>(), "background", true);
        const cv::Mat g = MaskView(ground, "ground"),
                      s = MaskView(model_shadow, "model_shadow");
        const UnmodelledShadowOptions o =
            OptionsFrom<UnmodelledShadowOptions>(options, kwargs);
        UnmodelledShadows r;
        {
          py::gil_scoped_release release;
          r = DetectUnmodelledShadows(f, b, g, s, o);
        }
        return UnmodelledShadowsResult{MatAsArray(r.mask),
                                       std::move(r.regions)};
      },
      py::arg("frame").noconvert(), py::arg("background"),
      py::arg("ground").noconvert(), py::arg("model_shadow").noconvert(),
      py::kw_only(), py::arg("options") = py::none(),
      "Options: options=UnmodelledShadowOptions and/or its fields as keyword "
      "arguments. Hard ground shadows the model does not explain: an "
      "UnmodelledShadows (mask: uint8 (H,W), 255 on them; regions: "
      "UnmodelledShadow list). frame/background float32 gray "
      "(H,W) or linear BGR (H,W,3), "
      "background None for the frame alone; "
      "ground/model_shadow uint8 (H,W) masks.");

  m.def(
      "linear_block_means",
      [](const py::array& image, int stride, const py::array& table) {
        CheckArray<uint8_t>(image, "image", {-1, -1, 3});
        const float* t = CheckArray<float>(table, "table", {256});
        const cv::Mat in(static_cast<int>(image.shape(0)),
                         static_cast<int>(image.shape(1)), CV_8UC3,
                         const_cast<void*>(image.data()));
        const cv::Mat lut(1, 256, CV_32F, const_cast<float*>(t));
        cv::Mat out;
        {
          py::gil_scoped_release release;
          out = CentredBlockMeans(in, stride, lut);
        }
        return MatAsArray(out);
      },
      py::arg("image").noconvert(), py::arg("stride"),
      py::arg("table").noconvert(),
      "uint8 (H,W,3) -> float32 of the size of image[::stride, ::stride]: "
      "each value read through `table` (256 float32, e.g. sRGB -> linear) "
      "and averaged over the stride x stride block centred on full-size "
      "pixel (i*stride, j*stride), the border repeated.");

  m.def(
      "to_linear_gray",
      [](const py::array& bgr, double gamma) {
        CheckArray<uint8_t>(bgr, "image", {-1, -1, 3});
        const cv::Mat in(static_cast<int>(bgr.shape(0)),
                         static_cast<int>(bgr.shape(1)), CV_8UC3,
                         const_cast<void*>(bgr.data()));
        return MatAsArray(ToLinearGray(in, gamma));
      },
      py::arg("image").noconvert(), py::arg("gamma") = kDisplayGamma,
      "uint8 (H,W,3) BGR -> float32 (H,W) linear gray in [0,1] (value^gamma).");

  m.def(
      "estimate_initial_sun",
      [](const Scene& scene, const Camera& camera, const py::array& frame,
         const py::object& progress, const py::object& options,
         const py::kwargs& kwargs) {
        const cv::Mat img = FloatView(frame, "frame");
        const InitialSunOptions o =
            OptionsFrom<InitialSunOptions>(options, kwargs);
        const ProgressCallback cb = WrapProgress(progress);
        InitialSunResult r;
        {
          py::gil_scoped_release release;
          r = EstimateInitialSun(scene, camera, img, o, cb);
        }
        return r;
      },
      py::arg("scene"), py::arg("camera"), py::arg("frame").noconvert(),
      py::kw_only(), py::arg("progress") = py::none(),
      py::arg("options") = py::none(),
      "Options: options=InitialSunOptions and/or its fields as keyword "
      "arguments (method='default' or 'thesis', ...). Sun direction on one "
      "frame (float32 (H,W) linear gray, the camera's "
      "size). Azimuth is in the world frame (clockwise from +Y). Returns a "
      "dict; success False with a message when the frame cannot fix the Sun "
      "or the run was cancelled (progress returned False).");
}

}  // namespace sunlapse::python
