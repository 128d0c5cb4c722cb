// The Sun's direction on the first frame from the scene's coarse 3D model,
// the matched camera and the image as shading (thesis chapter 3).
//
// kThesis (the baseline, faithful to thesis §3.3): a hemisphere of point
// lights ("spotlights") around the model plus an ambient term; per-pixel
// point, normal and light visibility by ray casting; the Lambertian model
// S = Ia + sum_i Ii max(0, Li.N) vis_i fitted with non-negative intensities by
// Levenberg-Marquardt (Ceres); the Sun is the intensity-weighted centre of
// the lights' directions.
//
// kDefault (ours): the same Lambertian model, with these departures, each
// because the thesis's version cannot reach a few degrees:
//  - a dense set of candidate Sun directions, then a continuous refinement of
//    the direction itself (a weighted mean of fixed lights is biased toward
//    the hemisphere's middle and cannot resolve anything between lights);
//  - one albedo per object (the image is albedo x shading; the thesis reads a
//    dark object as a shadow);
//  - cast shadows as the main cue: visibility toward the candidate Sun is what
//    fixes the azimuth on flat ground, where N.L alone gives only the zenith;
//  - a Cauchy loss, so objects missing from the model, people and specular
//    spots do not drag the answer; pixels are subsampled so that 4K frames
//    cost the same as small ones;
//  - a confidence from the residual and from how wide the set of nearly as
//    good directions is, and a message when the scene cannot fix the Sun.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "sunlapse/scene/camera.h"
#include "sunlapse/scene/scene.h"

namespace sunlapse {

enum class InitialSunMethod { kThesis, kDefault };

struct InitialSunOptions {
  InitialSunMethod method = InitialSunMethod::kDefault;
  // At most this many pixels are used (a regular grid over the frame).
  int max_pixels = 12000;
  // Rows at the top / bottom of the frame that are not scene content
  // (burned-in time stamps, banners).
  int ignore_top_rows = 0;
  int ignore_bottom_rows = 0;
  // Pixels outside [min_intensity, max_intensity] (clipped) are not used.
  // The image is expected linear in [0, 1] (see ToLinearGray).
  double min_intensity = 0.002;
  double max_intensity = 0.98;
  // kThesis: number of lights on the hemisphere and their elevation (deg).
  int thesis_num_lights = 8;
  double thesis_light_elevation_deg = 45.0;
  // kDefault: candidate directions on the upper hemisphere (Fibonacci).
  int num_candidates = 300;
  // kDefault: best separated candidates refined continuously.
  int num_refine_starts = 3;
  // kDefault: refinement stops below this step (degrees).
  double refine_tolerance_deg = 0.02;
  // Cauchy loss scale as a fraction of the median intensity of the used
  // pixels, so that it follows the frame's exposure: a fixed scale that suits
  // a bright frame reads the real lit/shadow contrast of a dim or low-Sun
  // frame as outliers (seen on the nordic_autumn preset).
  double loss_scale = 0.35;
  // kDefault: one albedo per object (else one for the whole model).
  bool per_object_albedo = true;
  // Candidate Suns lie at most this far from the zenith (degrees).
  double max_zenith_deg = 89.0;

  // Throws std::invalid_argument naming the bad field.
  void Check() const;
};

struct InitialSunResult {
  enum class Status {
    kSuccess,       // a Sun (the message may warn it is poorly determined)
    kTooFewPixels,  // too few usable pixels see the model
    kNoLight,       // no light explains the image
    kCancelled,     // the progress callback asked to stop
  };
  Status status = Status::kTooFewPixels;
  bool ok() const { return status == Status::kSuccess; }
  // Why it failed, or a warning about a poorly determined Sun.
  std::string message;
  // Direction toward the Sun in the world frame; azimuth clockwise from +Y
  // toward +X (geographic only when +Y is north).
  double zenith_deg = 0.0;
  double azimuth_deg = 0.0;
  Eigen::Vector3d sun_in_world = Eigen::Vector3d::UnitZ();
  // Fitted intensities (linear image units; albedo of the largest object = 1).
  double sun_intensity = 0.0;
  double ambient_intensity = 0.0;
  // kThesis: intensity per light; kDefault: empty.
  std::vector<double> light_intensities;
  // Albedo per object id (1 for objects no pixel sees).
  std::vector<double> albedo_per_object;
  // RMS of the residuals of inlier pixels (linear intensity units).
  double residual_rms = 0.0;
  // The Cauchy scale used, in linear intensity units.
  double loss_scale_abs = 0.0;
  // Fraction of used pixels the fit explains (|r| < 3 x loss scale).
  double inlier_fraction = 0.0;
  // Angular radius of the set of directions nearly as good as the best.
  double spread_deg = 180.0;
  // 0..1, from the spread and the inlier fraction.
  double confidence = 0.0;
  int num_pixels = 0;
  double seconds = 0.0;
};

// Called with the fraction done; return false to cancel.
using ProgressCallback = std::function<bool(double)>;

// frame: CV_32F single channel, linear intensity, the camera's size.
InitialSunResult EstimateInitialSun(const Scene& scene, const Camera& camera,
                                    const cv::Mat& frame,
                                    const InitialSunOptions& options,
                                    const ProgressCallback& progress = nullptr);

}  // namespace sunlapse
