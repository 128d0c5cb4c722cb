// The Sun's path without place or date: a small circle about the pole.
//
// Over a day the Sun turns about the celestial pole at 15 deg per hour on a
// circle of constant declination. Fitted to the measured Suns (world frame),
// that circle gives, with no place, date or compass known (in the spirit of
// Junejo & Foroosh, ECCV 2008, geo-temporal localisation from shadows): the
// pole's elevation (the latitude), its azimuth in the scene (true north), the
// circle's angular radius (the declination) and the hour angle at each frame.
// Its values at the frames are a smoothing that knows how the Sun moves: the
// whole-clip path's prior and the check of each frame's Sun against the path.
//
// FitSunCircle: a small Levenberg-Marquardt with Huber weights (on the
// angle). FitTrimmedSunCircle: the same, with the far Suns left out, so that
// a run of wrong Suns does not bend it. A plain fit, even a robust one, is
// pulled several degrees by a third of a segment's Suns lying to one side of
// the true path: the sky grid's evidence along a long thin shadow drifts
// toward a lower Sun on low-Sun frames, and the shadow tracker, started
// there, stays with it. The trimmed fit leaves out the Suns further from the
// circle than inlier_medians times the inliers' median distance (never less
// than the caller's floor, the Suns' own precision) and fits again, until the
// inliers no longer change. When a fit of all of them leaves some out, each
// half of the segment is tried as the start too (the wrong Suns are usually
// one stretch: the low-Sun end), and the start whose circle holds the most
// Suns within the tightest start's limit wins; a circle holding fewer than
// half of them is no candidate. (Starting from the best half of a fit of all
// did worse: a bent fit's closest half holds the wrong Suns that happen to
// lie along its bend.) It holds while the wrong Suns scatter; a block of Suns
// all shifted alike at one end of an untimed clip looks like another circle
// (pole, declination and rate are free) and is not found.
//
// These fits were numpy code until issue 28: over a 1,000-frame clip the
// prior's 24 trimmed fits (175 circle fits) took 0.8 s of the run's 12.8.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace sunlapse {

struct SunCircleOptions {
  // Times are seconds (the hour angle then turns 15 deg per hour) or frame
  // numbers (false: the rate is fitted too).
  bool times_are_seconds = true;
  // Levenberg-Marquardt iterations at most.
  int iterations = 60;
  // The robust (Huber) weights are refreshed every this many iterations.
  int reweight_every = 10;
  // A fit has settled when a step moves no parameter (radians, or radians per
  // time unit) by more than settled_step_rad and its robust weights change by
  // less than settled_weight when refreshed: the steps left would change its
  // Suns by less than 1e-7 deg.
  double settled_step_rad = 1e-10;
  double settled_weight = 1e-9;

  void Check() const;
};

struct SunCircleFit {
  enum class Status {
    kSuccess,
    kTooFewSuns,  // fewer than 4 measured Suns (trimmed: min_frames)
    kSameTimes,   // the measured Suns all have the same time
    kNoCircle,    // trimmed: no circle holds min_inlier_share of the Suns
  };
  Status status = Status::kTooFewSuns;
  // Why not, or (kSuccess) a caveat: the pole near the zenith.
  std::string message;
  double latitude_deg = 0.0;
  double declination_deg = 0.0;
  // World azimuth of true north (the scene's +Y turned by this from north,
  // as the Sun Position add-on's north offset: world = geographic + it).
  double north_offset_deg = 0.0;
  // Westward hour angle rate (deg per second with times: 15/h; else per
  // frame, fitted).
  double rate_deg = 0.0;
  // Median distance of the measured (trimmed: inlier) Suns from the circle.
  double residual_deg = 0.0;
  // Per given time: the circle's Sun (world frame) and the hour angle (deg,
  // 0 at solar noon, positive in the afternoon, in [-180, 180)).
  std::vector<Eigen::Vector3d> sun_in_world;
  std::vector<double> hour_angle_deg;
  // Trimmed fits: per given time, how far the given Sun is from the circle
  // (deg; NaN where none was given), and the inliers (indices, ascending).
  std::vector<double> off_deg;
  std::vector<int> inliers;
};

// times: one per Sun (seconds or frame numbers, as options say);
// suns_in_world: directions toward the Sun (any length; a non-finite one: no
// Sun at that time, predicted all the same); weights: empty (all 1) or one
// per Sun (<= 0 or not finite: left out).
SunCircleFit FitSunCircle(const std::vector<double>& times,
                          const std::vector<Eigen::Vector3d>& suns_in_world,
                          const std::vector<double>& weights,
                          const SunCircleOptions& options);

struct TrimmedCircleOptions {
  // Suns further from the circle than this many times the inliers' median
  // distance are left out (never nearer than the caller's floor).
  double inlier_medians = 2.0;
  // Trimming rounds at most.
  int rounds = 8;
  // Iterations of each round's fit (the final fit keeps
  // SunCircleOptions::iterations): the trimmed inliers come out the same with
  // 20, at a third of the time. A closed-form fit (the plane through the
  // Suns, the angle about its normal linear in time) was faster still but
  // chose worse inliers on short arcs (suite scene 23: a 17 deg arc).
  int round_iterations = 20;
  // At most this many Suns, spread over the segment, take part in the
  // rounds (the final fit takes them all).
  int max_fit_frames = 300;
  // Suns a trimmed fit needs.
  int min_frames = 8;
  // A start's circle is a candidate when it holds this share of the Suns (a
  // short arc's subsets each fit a circle of their own).
  double min_inlier_share = 0.5;

  void Check() const;
};

// The circle through the given Suns with the far ones left out (above).
// floor_deg: the inlier limit never falls below this.
SunCircleFit FitTrimmedSunCircle(
    const std::vector<double>& times,
    const std::vector<Eigen::Vector3d>& suns_in_world,
    const std::vector<double>& weights, double floor_deg,
    const SunCircleOptions& circle_options,
    const TrimmedCircleOptions& options);

}  // namespace sunlapse
