// Bindings of the sky stage: whole-sky evidence per frame and the Sun's path.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <opencv2/core.hpp>

#include "arrays.h"
#include "images.h"
#include "options.h"
#include "sunlapse/sky/sky_evidence.h"
#include "sunlapse/sky/sun_circle.h"
#include "sunlapse/sky/sun_path.h"

namespace sunlapse::python {

namespace {

// (N, 3) directions toward the Sun (NaN rows: none) from any array-like.
std::vector<Eigen::Vector3d> SunsArg(const py::object& suns, const char* name) {
  const auto a =
      py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(
          suns);
  if (!a || a.ndim() != 2 || a.shape(1) != 3)
    throw py::value_error(std::string(name) +
                          ": expected an (N, 3) array of directions toward "
                          "the Sun (NaN rows: none)");
  const auto v = a.unchecked<2>();
  std::vector<Eigen::Vector3d> out;
  out.reserve(static_cast<size_t>(a.shape(0)));
  for (py::ssize_t i = 0; i < a.shape(0); ++i)
    out.emplace_back(v(i, 0), v(i, 1), v(i, 2));
  return out;
}

py::array_t<double> Rows3(const std::vector<Eigen::Vector3d>& d) {
  py::array_t<double> out({static_cast<py::ssize_t>(d.size()), py::ssize_t(3)});
  auto w = out.mutable_unchecked<2>();
  for (size_t i = 0; i < d.size(); ++i) {
    for (int k = 0; k < 3; ++k) w(i, k) = d[i][k];
  }
  return out;
}

void BindSunCircle(py::module_& m) {
  OptionsClass<SunCircleOptions>(m, "SunCircleOptions",
                                 "Options of fit_sun_circle (sun_circle.h).")
      .field("times_are_seconds", &SunCircleOptions::times_are_seconds,
             "Times are seconds (the rate is 15 deg/h) or frame numbers "
             "(False: the rate is fitted).")
      .field("iterations", &SunCircleOptions::iterations,
             "Levenberg-Marquardt iterations at most.")
      .field("reweight_every", &SunCircleOptions::reweight_every,
             "Iterations between refreshes of the robust (Huber) weights.")
      .field("settled_step_rad", &SunCircleOptions::settled_step_rad,
             "A step moving no parameter by more than this (radians) has "
             "settled.")
      .field("settled_weight", &SunCircleOptions::settled_weight,
             "Settled robust weights change by less than this.");

  OptionsClass<TrimmedCircleOptions>(
      m, "TrimmedCircleOptions",
      "Options of fit_trimmed_sun_circle (sun_circle.h).")
      .field("inlier_medians", &TrimmedCircleOptions::inlier_medians,
             "Suns further than this many times the inliers' median distance "
             "are left out.")
      .field("rounds", &TrimmedCircleOptions::rounds,
             "Trimming rounds at most.")
      .field("round_iterations", &TrimmedCircleOptions::round_iterations,
             "Iterations of each round's fit.")
      .field("max_fit_frames", &TrimmedCircleOptions::max_fit_frames,
             "Suns, spread over the segment, that take part in the rounds.")
      .field("min_frames", &TrimmedCircleOptions::min_frames,
             "Suns a trimmed fit needs.")
      .field("min_inlier_share", &TrimmedCircleOptions::min_inlier_share,
             "Share of the Suns a start's circle must hold to be a "
             "candidate.");

  py::enum_<SunCircleFit::Status>(m, "SunCircleStatus")
      .value("SUCCESS", SunCircleFit::Status::kSuccess)
      .value("TOO_FEW_SUNS", SunCircleFit::Status::kTooFewSuns)
      .value("SAME_TIMES", SunCircleFit::Status::kSameTimes)
      .value("NO_CIRCLE", SunCircleFit::Status::kNoCircle);

  py::class_<SunCircleFit>(m, "SunCircleFit",
                           "The Sun's small circle about the pole "
                           "(sun_circle.h); per-time arrays as numpy.")
      .def_readonly("status", &SunCircleFit::status)
      .def_readonly("message", &SunCircleFit::message)
      .def_readonly("latitude_deg", &SunCircleFit::latitude_deg)
      .def_readonly("declination_deg", &SunCircleFit::declination_deg)
      .def_readonly("north_offset_deg", &SunCircleFit::north_offset_deg)
      .def_readonly("rate_deg", &SunCircleFit::rate_deg)
      .def_readonly("residual_deg", &SunCircleFit::residual_deg)
      .def_property_readonly(
          "sun_in_world",
          [](const SunCircleFit& f) { return Rows3(f.sun_in_world); })
      .def_property_readonly("hour_angle_deg",
                             [](const SunCircleFit& f) {
                               return py::array_t<double>(
                                   f.hour_angle_deg.size(),
                                   f.hour_angle_deg.data());
                             })
      .def_property_readonly("off_deg",
                             [](const SunCircleFit& f) {
                               return py::array_t<double>(f.off_deg.size(),
                                                          f.off_deg.data());
                             })
      .def_readonly("inliers", &SunCircleFit::inliers);

  m.def(
      "fit_sun_circle",
      [](const std::vector<double>& times, const py::object& suns,
         const std::vector<double>& weights, const py::object& options,
         const py::kwargs& kwargs) {
        const SunCircleOptions o =
            OptionsFrom<SunCircleOptions>(options, kwargs);
        const std::vector<Eigen::Vector3d> s = SunsArg(suns, "suns_in_world");
        py::gil_scoped_release release;
        return FitSunCircle(times, s, weights, o);
      },
      py::arg("times"), py::arg("suns_in_world"),
      py::arg("weights") = std::vector<double>(),
      py::arg("options") = py::none(),
      "The Sun's small circle about the pole through the given Suns "
      "(sun_circle.h). times: seconds or frame numbers; suns_in_world: (N, 3) "
      "directions toward the Sun (NaN rows: none); weights: empty or one per "
      "Sun. Options as SunCircleOptions or its fields as keywords.");

  m.def(
      "fit_trimmed_sun_circle",
      [](const std::vector<double>& times, const py::object& suns,
         double floor_deg, const std::vector<double>& weights,
         const py::object& circle_options, const py::object& options) {
        const SunCircleOptions c =
            OptionsFrom<SunCircleOptions>(circle_options, py::kwargs());
        const TrimmedCircleOptions o =
            OptionsFrom<TrimmedCircleOptions>(options, py::kwargs());
        const std::vector<Eigen::Vector3d> s = SunsArg(suns, "suns_in_world");
        py::gil_scoped_release release;
        return FitTrimmedSunCircle(times, s, weights, floor_deg, c, o);
      },
      py::arg("times"), py::arg("suns_in_world"), py::arg("floor_deg"),
      py::arg("weights") = std::vector<double>(),
      py::arg("circle_options") = py::none(), py::arg("options") = py::none(),
      "The Sun's circle with the far Suns left out (sun_circle.h): the inlier "
      "limit never falls below floor_deg. off_deg and inliers are filled.");
}

}  // namespace

void BindSky(py::module_& m) {
  BindSunCircle(m);
  OptionsClass<SkyEvidenceOptions>(m, "SkyEvidenceOptions",
                                   "Options of SkyEvidence (sky_evidence.h).")
      .field("num_directions", &SkyEvidenceOptions::num_directions,
             "Sky directions scored per frame.")
      .field("max_zenith_deg", &SkyEvidenceOptions::max_zenith_deg,
             "Directions lower than this are not candidates, degrees from "
             "the zenith.")
      .field("max_samples", &SkyEvidenceOptions::max_samples,
             "Surface samples at most (at most 65,535).")
      .field("ignore_top_rows", &SkyEvidenceOptions::ignore_top_rows,
             "Rows at the top that are not scene content.")
      .field("ignore_bottom_rows", &SkyEvidenceOptions::ignore_bottom_rows,
             "Rows at the bottom that are not scene content.")
      .field("normal_bin_deg", &SkyEvidenceOptions::normal_bin_deg,
             "Samples grouped into planes by object and normal within this, "
             "degrees.")
      .field("band_steps", &SkyEvidenceOptions::band_steps,
             "Grid steps from a candidate's shadow boundary that are scored.")
      .field("min_side_samples", &SkyEvidenceOptions::min_side_samples,
             "Band samples a group needs on each side of a split to score.")
      .field("max_ratio", &SkyEvidenceOptions::max_ratio,
             "Intensity / reference ratios clipped to [0, max_ratio].")
      .field("reference_quantile", &SkyEvidenceOptions::reference_quantile,
             "A sample's reference level: this quantile over the reference "
             "frames.")
      .field("rival_exclusion_deg", &SkyEvidenceOptions::rival_exclusion_deg,
             "Directions within this of the best are not its rivals, "
             "degrees.")
      .field("samples_per_observation",
             &SkyEvidenceOptions::samples_per_observation,
             "Neighbouring samples counted as one observation in the costs.")
      .field("min_significance", &SkyEvidenceOptions::min_significance,
             "A frame has evidence when its best direction beats no shadows "
             "by this much (log-likelihood).");

  OptionsClass<SunPathOptions>(m, "SunPathOptions",
                               "Options of solve_sun_path (sun_path.h).")
      .field("evidence_weight", &SunPathOptions::evidence_weight,
             "Weight of the evidence's costs.")
      .field("step_weight", &SunPathOptions::step_weight,
             "Cost of a step of the whole allowed radius (grows with its "
             "square).")
      .field("jump_cost", &SunPathOptions::jump_cost,
             "Cost of a jump beyond the allowed radius; negative: no jumps.")
      .field("max_step_deg", &SunPathOptions::max_step_deg,
             "Largest Sun motion a frame without times, degrees.")
      .field("max_speed_deg_per_hour", &SunPathOptions::max_speed_deg_per_hour,
             "The Sun's apparent speed bound with times, degrees an hour.")
      .field("min_significance", &SunPathOptions::min_significance,
             "A measured frame's evidence beats no shadows by this much.")
      .field("min_margin", &SunPathOptions::min_margin,
             "A measured frame's direction leads its rivals by this much.")
      .field("rival_exclusion_deg", &SunPathOptions::rival_exclusion_deg,
             "Directions within this of the chosen one are not its rivals, "
             "degrees.")
      .field("prior_tolerance_deg", &SunPathOptions::prior_tolerance_deg,
             "Free distance from a frame's prior direction, degrees.")
      .field("prior_weight", &SunPathOptions::prior_weight,
             "Prior cost per squared degree beyond the tolerance.")
      .field("prior_max_cost", &SunPathOptions::prior_max_cost,
             "The prior's cost at most.")
      .field("keep_forward_mb", &SunPathOptions::keep_forward_mb,
             "The forward pass kept whole up to this many MB; beyond, "
             "checkpoints (the same path).");

  py::enum_<FrameEvidence::Status>(m, "FrameEvidenceStatus")
      .value("OK", FrameEvidence::Status::kOk)
      .value("NO_FRAME", FrameEvidence::Status::kNoFrame)
      .value("UNUSABLE", FrameEvidence::Status::kUnusable)
      .value("NO_SHADOWS", FrameEvidence::Status::kNoShadows);

  py::enum_<SunPathResult::Status>(m, "SunPathStatus")
      .value("SUCCESS", SunPathResult::Status::kSuccess)
      .value("NO_EVIDENCE", SunPathResult::Status::kNoEvidence);

  py::class_<SunPathResult>(
      m, "SunPathResult",
      "The Sun's path over the evidence's frames (sun_path.h); "
      "per-frame fields are lists.")
      .def_readonly("status", &SunPathResult::status)
      .def_readonly("message", &SunPathResult::message)
      .def_readonly("direction", &SunPathResult::direction)
      .def_property_readonly("jump_before",
                             [](const SunPathResult& r) {
                               return std::vector<bool>(r.jump_before.begin(),
                                                        r.jump_before.end());
                             })
      .def_property_readonly("measured",
                             [](const SunPathResult& r) {
                               return std::vector<bool>(r.measured.begin(),
                                                        r.measured.end());
                             })
      .def_readonly("explained", &SunPathResult::explained)
      .def_readonly("margin", &SunPathResult::margin)
      .def_readonly("significance", &SunPathResult::significance)
      .def_readonly("path_margin", &SunPathResult::path_margin)
      .def_readonly("cost", &SunPathResult::cost);

  py::class_<FrameEvidence>(m, "FrameEvidence")
      .def_readonly("status", &FrameEvidence::status)
      .def_readonly("message", &FrameEvidence::message)
      .def_readonly("best_direction", &FrameEvidence::best_direction)
      .def_readonly("best_explained", &FrameEvidence::best_explained)
      .def_readonly("margin", &FrameEvidence::margin)
      .def_readonly("significance", &FrameEvidence::significance)
      .def_readonly("exposure", &FrameEvidence::exposure)
      .def_readonly("shadow_view", &FrameEvidence::shadow_view)
      .def_readonly("seconds", &FrameEvidence::seconds);

  py::class_<SkyEvidence>(
      m, "SkyEvidence",
      "Whole-sky evidence per frame by table look-ups (sky_evidence.h).")
      .def(py::init([](const Scene& scene, const Camera& camera,
                       const SkyEvidenceOptions& o) {
             py::gil_scoped_release release;
             return std::make_unique<SkyEvidence>(scene, camera, o);
           }),
           py::arg("scene"), py::arg("camera"),
           py::arg("options") = SkyEvidenceOptions(), py::keep_alive<1, 2>(),
           py::keep_alive<1, 3>())
      .def_property_readonly("num_samples", &SkyEvidence::num_samples)
      .def_property_readonly("band_entries", &SkyEvidence::band_entries,
                             "band samples looked up per frame")
      .def_property_readonly("num_frames", &SkyEvidence::num_frames)
      .def_property_readonly("build_seconds", &SkyEvidence::build_seconds)
      .def_property_readonly(
          "spacing_deg",
          [](const SkyEvidence& e) { return e.grid().spacing_deg(); })
      .def_property_readonly(
          "directions",
          [](const SkyEvidence& e) { return Rows3(e.grid().directions()); })
      .def(
          "set_reference",
          [](SkyEvidence& e, const py::list& frames) {
            std::vector<cv::Mat> mats;
            for (const py::handle& f : frames)
              mats.push_back(GrayArg(py::reinterpret_borrow<py::object>(f)));
            py::gil_scoped_release release;
            return e.SetReference(mats);
          },
          py::arg("frames"),
          "Reference level of every sample from frames spread over the clip "
          "(float32 (H,W) "
          "linear gray, None skipped); returns how many were used.")
      .def(
          "add_frame",
          [](SkyEvidence& e, const py::object& frame) {
            const cv::Mat img = GrayArg(frame);
            py::gil_scoped_release release;
            return e.AddFrame(img);
          },
          py::arg("frame"),
          "Scores the next frame (float32 (H,W) linear gray, or None).")
      .def("cost", &SkyEvidence::Cost, py::arg("k"),
           "Each direction's cost on frame k.");

  m.def(
      "solve_sun_path",
      [](const SkyEvidence& e, const std::vector<double>& times_s,
         const std::vector<uint8_t>& segment_start, const SunPathOptions& o,
         const py::object& prior_in, const std::vector<uint8_t>& ignored) {
        const std::vector<Eigen::Vector3d> prior =
            prior_in.is_none() ? std::vector<Eigen::Vector3d>()
                               : SunsArg(prior_in, "prior");
        SunPathResult r;
        {
          py::gil_scoped_release release;
          r = SolveSunPath(e, times_s, segment_start, o, prior, ignored);
        }
        return r;
      },
      py::arg("evidence"), py::arg("times_s") = std::vector<double>(),
      py::arg("segment_start") = std::vector<uint8_t>(),
      py::arg("options") = SunPathOptions(), py::arg("prior") = py::none(),
      py::arg("ignored") = std::vector<uint8_t>(),
      "The Sun's path over the evidence's frames (sun_path.h): per frame a "
      "grid direction, "
      "jump flags, whether the frame's evidence supports it. prior: None or "
      "(N, 3) directions toward the Sun per frame (NaN rows: none); ignored: "
      "empty or 1 per frame whose evidence is not used.");
}

}  // namespace sunlapse::python
