// Following the Sun through the clip by its cast shadows on the ground
// (thesis chapter 4), done metrically with the scene's model.
//
// The thesis tracks one hard shadow in the image (Algorithm 1) and turns its
// pixel length and image angle into zenith and azimuth, which is exact only
// for a camera looking straight down. Here the same idea is kept (shadows on
// the ground, found again frame after frame near where they were) but each
// frame's Sun is the direction whose cast shadows, ray cast from the model
// onto the ground, best explain the image in a thin band around the shadows'
// boundaries. That is metric by construction (3D points from the camera and
// the model, no pixel lengths, no object heights: the casters' tops are in the
// model), follows every modelled shadow at once, weighted by how much of its
// boundary is seen, and costs only the band's rays per frame.
//
// The thesis's own tracker lives in thesis_tracker.h as the baseline.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "sunlapse/scene/camera.h"
#include "sunlapse/scene/scene.h"

namespace sunlapse {

struct ShadowTrackerOptions {
  // Object ids of the ground the shadows fall on (at least one).
  std::vector<int32_t> ground_object_ids;
  // Shadows are tracked on every model surface in view (walls and roofs the
  // casters shade), not on the ground alone; the rest still cast.
  bool all_surfaces = false;
  // On the ground alone (all_surfaces false): a frame whose Sun's height the
  // ground's shadows pin no closer than this (deg; TrackedFrame::
  // elevation_pinned_deg) is fitted again on every surface in view, and
  // takes that Sun where the walls pin it this close. 0: never.
  double surfaces_pin_deg = 2.0;
  // Half-width of the band around predicted shadow boundaries (pixels).
  int band_radius_px = 4;
  // At most this many band pixels are used per frame (a regular subsample):
  // the search's cost is proportional. On the 1080p benchmark 600 to 1500
  // give the same accuracy (0.2-0.25 deg worst).
  int max_band_pixels = 800;
  // Largest first search step around the predicted Sun, and the final step
  // (deg); the search's parabolas place the minimum within the last step and
  // the result is good to about 0.1 deg, so finer steps buy nothing.
  double search_step_deg = 0.5;
  double tolerance_deg = 0.04;
  // Cauchy scale as a fraction of the band's median intensity.
  double loss_scale = 0.35;
  // Shadow lost when the fitted sun/ambient contrast falls below this (sunny
  // ground shows 3-10; overcast fits find noise around 0.1-0.2).
  double min_contrast = 0.5;
  // Rays per band pixel along each axis: 2 predicts a pixel's lit fraction
  // from 2x2 sub-pixel rays, as the sensor averages over the pixel, which
  // gives the boundaries sub-pixel precision. 0: 2 for frames narrower than
  // 1280 pixels, 1 from there (pixels that small need no sub-pixel rays:
  // bench_tracking at 1080p is as accurate with a third of the rays).
  int subsamples = 0;
  // Rows at the top / bottom that are not scene content (banners).
  int ignore_top_rows = 0;
  int ignore_bottom_rows = 0;
  // Per-pixel ground albedo from the first frame cancels the ground's texture.
  bool normalize_albedo = true;

  void Check() const;
};

struct TrackedFrame {
  // What became of the frame; reason says it in words for the user.
  enum class Status {
    kTracked,
    kUnusableFrame,     // not decodable, another size, black or overexposed
    kNoGroundInView,    // the ground is not in view (on this frame)
    kNoShadowInView,    // the model casts no shadow on the ground in view
                        // under the Sun asked about: the frame cannot show it
    kBandOutOfView,     // a moving camera's frame misses the shadows' band
    kBandOnGroundOnly,  // (every surface) the band lies on the ground alone
    kNoMatch,           // no fit near the predicted Sun
    kNoContrast,        // the shadows' edges show no sun/shade step
  };
  // False: no estimate on this frame (status and reason say why); the angles
  // then hold the prediction the tracker keeps following.
  bool ok = false;
  Status status = Status::kNoMatch;
  std::string reason;
  double zenith_deg = 0.0;  // world frame, azimuth clockwise from +Y
  double azimuth_deg = 0.0;
  Eigen::Vector3d sun_in_world = Eigen::Vector3d::UnitZ();
  double confidence = 0.0;  // 0..1
  double contrast = 0.0;    // fitted sun / ambient on the ground band
  int band_pixels = 0;
  // Share of the band's pixels the fitted Sun leaves a whole lit/shaded
  // step off (a mixture of noise and of such pixels, fitted to the
  // residuals): boundaries the model cannot put where the frame shows them.
  // A few percent with the true model; a hand-made model's misplaced
  // casters leave 10-40% whatever the Sun (docs/accuracy.md).
  double misfit = 0.0;
  // How far (deg) the Sun's elevation can move either way before the fit
  // gets significantly worse: the smallest of 0.5, 1, 2, 4, 8 at which both
  // sides cost kPinChi2 more (in the band's noise), else infinity. Shadows
  // whose far ends (the casters' tops) are out of view pin the azimuth only:
  // any lower Sun lengthens them out of view alike.
  double elevation_pinned_deg = 0.0;
  int rays = 0;         // shadow rays cast this frame (the tracker's cost)
  int evaluations = 0;  // candidate Suns scored this frame
  // The longest modelled shadow on this frame: caster foot and shadow tip, in
  // OpenCV pixels (NaN when no caster's shadow falls in view).
  Eigen::Vector2d shadow_start_px{NAN, NAN};
  Eigen::Vector2d shadow_end_px{NAN, NAN};
  double seconds = 0.0;  // tracking only, decoding excluded
};

class ShadowTracker {
 public:
  // The scene and camera must outlive the tracker.
  ShadowTracker(const Scene& scene, const Camera& camera,
                const ShadowTrackerOptions& options);
  ~ShadowTracker();

  // Maps the ground in view and finds the casters (the scene and camera
  // alone decide them), unless done already; Initialize does it otherwise.
  // A run calls it while its reference frames decode, on another thread:
  // no other call to this tracker may overlap it.
  void Prepare();
  // First frame (CV_32F linear gray, the camera's size) with the Sun found
  // by the initial estimate: maps the ground (Prepare), its albedo and the
  // shadows.
  TrackedFrame Initialize(const cv::Mat& frame,
                          const Eigen::Vector3d& sun_in_world);
  // The next frame. An empty Mat marks a frame that could not be decoded.
  TrackedFrame Track(const cv::Mat& frame);
  // The same, searching around a given Sun instead of the tracker's own
  // prediction (the whole-clip path's direction: sky/sun_path.h).
  TrackedFrame Track(const cv::Mat& frame,
                     const Eigen::Vector3d& predicted_sun_in_world);

 private:
  TrackedFrame TrackImpl(const cv::Mat& frame,
                         const Eigen::Vector3d* predicted);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sunlapse
