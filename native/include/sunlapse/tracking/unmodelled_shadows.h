// Hard ground shadows of casters that are not in the model.
//
// The thesis finds hard shadows with Lalonde et al.'s learned detector (ECCV
// 2010), which we do not have. Our tracker needs no detector for the casters
// in the model: it ray casts their shadows. What the model lacks (a bin, a
// bush, a parked car) still casts shadows the artist will want to know about,
// and that the accuracy report scores against the rendered masks. They are
// found from three cues that need no training:
//  - darker than the lit ground around (a wide window's mean over the
//    lit-looking ground), so exposure drifts and vignetting do not matter;
//    divided first by the clip's shadow-free background when there is one
//    (a time-lapse's median, when its shadows moved enough), which cancels
//    dark paint and stains as well;
//  - darkened in every colour channel alike (within a tolerance: sky light
//    makes shade bluer, a dark object or a wet patch changes the colour far
//    more), when colour is given;
//  - bounded, at least in part, by a hard edge: the energy |dI/dx|+|dI/dy|
//    (the thesis's eq. 4.1) along the region's rim is well above the
//    ground's typical texture energy; clouds and haze darken softly.
// The model's own cast shadows (ray cast under the frame's Sun) are removed
// first: what remains is unexplained by the model.
#pragma once

#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace sunlapse {

struct UnmodelledShadowOptions {
  // Dark: ratio frame / background below this share of the lit level.
  double dark_ratio = 0.7;
  // Colour: largest / smallest channel ratio at most this (colour input only).
  double max_chroma_ratio = 2.5;
  // Lit level: median-like ratio over windows of this share of the width.
  double level_window = 0.1;
  // The model's predicted shadow is widened by this many pixels before it
  // is removed (its edge is only as good as the model and the Sun).
  int model_margin_px = 2;
  // Regions smaller than this share of the ground (and than 12 px) go.
  double min_area_fraction = 2e-4;
  // Hard edge: mean rim energy at least this many times the ground's median.
  double min_edge_contrast = 2.5;
  // The frame is compared with the darkest background within this many
  // pixels: a camera that shook a little between captures does not turn
  // dark paint or engravings into "shadows".
  int registration_px = 2;

  void Check() const;
};

struct UnmodelledShadow {
  int area_px = 0;
  cv::Rect box;
  Eigen::Vector2d centroid_px;
  double darkening = 0;      // mean ratio to the lit level inside (0..1)
  double edge_contrast = 0;  // rim energy / ground median energy
  // It borders the model's predicted shadow (within model_margin_px + 2):
  // it may be part of a modelled shadow that the Sun used puts a little off.
  bool touches_model = false;
};

struct UnmodelledShadows {
  cv::Mat1b mask;  // 255 on the kept regions
  std::vector<UnmodelledShadow> regions;
};

// frame, background: CV_32FC1 (gray) or CV_32FC3 (linear colour), same size
// and type; background may be empty (one frame alone). ground, model_shadow:
// CV_8UC1 masks (non-zero = on the ground / in the model's cast shadow under
// this frame's Sun). Throws std::invalid_argument on mismatched inputs.
UnmodelledShadows DetectUnmodelledShadows(
    const cv::Mat& frame, const cv::Mat& background, const cv::Mat& ground,
    const cv::Mat& model_shadow, const UnmodelledShadowOptions& options = {});

}  // namespace sunlapse
