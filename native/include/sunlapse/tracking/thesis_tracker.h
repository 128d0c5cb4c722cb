// The thesis's shadow tracker (Balcı 2015, §4.1-4.2), kept as the baseline.
//
// Frame 1: candidate hard ground shadows, then the five selection criteria in
// order (direction within 10 deg of the Sun's, no end on the frame border,
// energy above average, length above average, exactly one end touching a
// modelled object, then none, then the strongest). Every later frame:
// Algorithm 1 on the energy image e = |dI/dx| + |dI/dy| (Avidan & Shamir):
// move the start pixel to the energy centre of mass of its 5x5 neighbourhood
// when its energy changed, walk in the search direction to the highest-energy
// candidate pixel, stop below half the initial shadow energy or when the last
// 10 pixels' direction departs from the first 15 pixels', then turn the
// shadow's pixel length and image angle into zenith and azimuth.
//
// Where we depart from the text, and why:
//  - Candidates: the thesis uses Lalonde et al.'s learned detector (ECCV
//    2010), which we do not have; the candidates are the shadows the model
//    casts under the initial Sun (foot of each caster to its top's shadow).
//  - Zenith: eq. 4.3/4.8 read literally (l_v = l_s tan z, z = atan(l_v/l_s))
//    make a longer shadow mean a higher Sun. The physical relation is
//    l_s = l_v tan z, so l_v = l_s0 / tan z0 and z = atan(l_s / l_v).
//  - Azimuth: eq. 4.9 adds the change of the image angle theta (counter-
//    clockwise); seen from above, a Sun turning clockwise (azimuth growing)
//    turns the shadows clockwise too, so the change is subtracted.
//  - Centre of mass: eq. 4.5-4.6 omit the division by the total energy.
//  - Slope test: "differs by a third" is read as the direction of the last 10
//    pixels departing by more than 20 deg from that of the first 15.
#pragma once

#include <memory>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "sunlapse/scene/camera.h"
#include "sunlapse/scene/scene.h"
#include "sunlapse/tracking/shadow_tracker.h"  // TrackedFrame

namespace sunlapse {

struct ThesisTrackerOptions {
  std::vector<int32_t> ground_object_ids;
  // Criterion 1: shadows further than this from the Sun's direction go.
  double max_direction_error_deg = 10.0;
  // Algorithm 1: stop when the direction of the last `slope_window` pixels
  // departs from that of the first `slope_start` pixels by this much.
  int slope_start = 15;
  int slope_window = 10;
  double max_slope_change_deg = 20.0;
  // Hard stop for a walk (pixels).
  int max_length_px = 4000;
  int ignore_top_rows = 0;

  void Check() const;
};

// A candidate shadow on frame 1 and what the criteria measured of it.
struct ShadowCandidate {
  Eigen::Vector2d start_px, end_px;  // at the caster, at the tip
  double direction_error_deg = 0;    // vs the Sun's direction in the image
  bool on_border = false;
  double energy = 0;  // mean energy along the segment
  double length_px = 0;
  int ends_on_model = 0;  // 0, 1 or 2
};

// The five criteria, in order; returns the index of the kept shadow or -1.
// `dropped_by[i]` says which criterion (1-5) dropped candidate i (0: kept).
int SelectShadow(const std::vector<ShadowCandidate>& candidates,
                 double max_direction_error_deg, std::vector<int>* dropped_by);

// e = |dI/dx| + |dI/dy| with central differences (CV_32F).
cv::Mat EnergyImage(const cv::Mat& gray);

class ThesisTracker {
 public:
  ThesisTracker(const Scene& scene, const Camera& camera,
                const ThesisTrackerOptions& options);
  ~ThesisTracker();
  // First frame (CV_32F gray) with the initial Sun.
  TrackedFrame Initialize(const cv::Mat& frame,
                          const Eigen::Vector3d& sun_in_world);
  TrackedFrame Track(const cv::Mat& frame);
  const std::vector<ShadowCandidate>& candidates() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sunlapse
