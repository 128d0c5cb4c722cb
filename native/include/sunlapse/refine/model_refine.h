// A hand-made model refined by the clip (issue 25 item 5).
//
// Users model by hand: casters sit 10-30 cm off, are a few percent too large
// or small and turned a degree or two; the camera is matched to 0.3 deg and
// 2% of focal. Every shadow the estimate predicts inherits those errors (a
// caster 10% too tall moves the zenith by up to 3 deg at 45 deg). The clip
// sees the model itself: its objects' outlines and creases are edges in
// every frame, where the moving shadows are not. This stage finds those
// stable edges over the reference frames and moves each object (along the
// ground, about the vertical), scales it along its own footprint's axes and
// turns and zooms the camera so that the model's visible edges fall on them:
// a bounded, robust least-squares fit (Ceres), with priors of the size of a
// hand-made model's errors, like a bundle adjustment whose points are the
// model's edges. The ground stays where the user put it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "sunlapse/scene/camera.h"
#include "sunlapse/scene/scene.h"

namespace sunlapse {

struct StableEdgesOptions {
  // Frames darker than this fraction of the brightest frame's median level
  // are left out (night, deep twilight: their gradients are noise).
  double min_level_fraction = 0.25;
  // The median (over the frames) gradient of log intensity, per pixel, that
  // an edge must reach. A face 1.3x brighter than its neighbour, blurred over
  // two pixels, gives about 0.1.
  double min_log_gradient = 0.06;
  // Rows at the top left out (a time stamp burnt into the footage).
  int ignore_top_rows = 0;

  void Check() const;
};

// Thin edges (CV_8U, 255 on an edge) that stay in most of the frames
// (CV_32F linear gray, all one size; empty ones are skipped). Moving shadow
// edges cross a pixel in few frames, so the median gradient leaves them out;
// the orientation comes from the gradients' summed structure tensor, whose
// sign does not flip when the light turns a face from brighter to darker.
// Returns an empty image when fewer than two frames are usable.
cv::Mat StableEdges(const std::vector<cv::Mat>& frames,
                    const StableEdgesOptions& options = {});

struct ModelRefineOptions {
  // Hard bounds of the corrections.
  double max_move_m = 0.5;
  double max_turn_deg = 6.0;
  double max_scale_change = 0.2;  // each axis within 1 +- this
  double max_camera_turn_deg = 1.0;
  double max_focal_change = 0.06;  // focal within 1 +- this
  // Priors: how far a hand-made model is typically off (issue 25).
  double move_sigma_m = 0.15;
  // A small object is modelled closer: its move's bound and prior are at
  // most these fractions of its largest extent (a sundial's 5 cm nodus
  // moved 0.3 m under the metres above, onto the gnomon's edges).
  double max_move_fraction = 0.3;
  double move_sigma_fraction = 0.15;
  double turn_sigma_deg = 2.0;
  double scale_sigma = 0.06;
  double camera_turn_sigma_deg = 0.3;
  double focal_sigma = 0.02;
  // Model edges are sampled every edge_spacing_px in the image; an edge
  // point's distance to the nearest stable edge counts up to
  // max_edge_distance_px, through a Cauchy loss of scale edge_sigma_px.
  double edge_spacing_px = 2.0;
  double edge_sigma_px = 1.5;
  double max_edge_distance_px = 12.0;
  // Edges between faces turned less than this are not edges.
  double crease_deg = 30.0;
  // An object with fewer visible edge points is not moved.
  int min_points_per_object = 24;
  // An object whose edge points stay further than this from the clip's
  // edges on average after the fit keeps the user's placement.
  double max_object_distance_px = 1.0;
  // The corrections are used only where the clip shows the model clearly
  // off and the fit clearly puts it back: its edges at least
  // min_distance_before_px from the clip's on average, and the fit removing
  // min_distance_drop of that. On the suite's true models the fit moved
  // edges already within 0.2-2 px by less than 30% and made the Sun worse
  // (0.2 -> 0.6 deg typical); on hand-made ones it removed 50-80%
  // (docs/accuracy.md, "Refining the model").
  double min_distance_before_px = 1.2;
  double min_distance_drop = 0.4;

  void Check() const;
};

// One object's correction, applied about its pivot (the centre of its
// footprint's smallest rectangle, at its lowest point): p' = pivot + move +
// Rz(turn) * A * diag(scale) * A^T * (p - pivot), A the footprint's axes.
struct ObjectCorrection {
  int32_t object_id = -1;
  Eigen::Vector3d pivot_in_world = Eigen::Vector3d::Zero();
  // The footprint's first axis (unit, horizontal, world frame); the second
  // is z x it.
  Eigen::Vector3d axis_in_world = Eigen::Vector3d::UnitX();
  Eigen::Vector2d move_in_world_m = Eigen::Vector2d::Zero();
  double turn_deg = 0.0;  // about world z, counter-clockwise seen from above
  Eigen::Vector3d scale = Eigen::Vector3d::Ones();  // along axis, z x axis, z
  // false: too few visible edge points, or the clip's edges do not confirm
  // the fit (max_object_distance_px): left as the user placed it.
  bool refined = false;
  int points = 0;  // visible edge points used
  // Mean distance (px, capped) of its edge points to the stable edges.
  double distance_before_px = 0.0;
  double distance_after_px = 0.0;

  // 4x4 world transform p -> p' (also for Blender's matrix_world).
  Eigen::Matrix4d Transform() const;
};

struct CameraCorrection {
  // The camera turned about its centre: world_from_camera' rotation =
  // turn_in_world * world_from_camera rotation.
  Eigen::Matrix3d turn_in_world = Eigen::Matrix3d::Identity();
  double turn_deg = 0.0;
  double focal_factor = 1.0;
};

struct ModelRefineResult {
  enum class Status {
    kRefined,    // corrections found and the fit is better with them
    kUnchanged,  // the model already fits, or the fit is not clearly better
    kNoEdges,    // no stable edges, or too few of the model's in view
    kFailed,     // the solver failed
  };
  Status status = Status::kFailed;
  bool ok() const { return status == Status::kRefined; }
  std::string message;
  CameraCorrection camera;
  std::vector<ObjectCorrection> objects;  // one per object in view
  int points = 0;
  double distance_before_px = 0.0;
  double distance_after_px = 0.0;
};

// scene and camera: the user's model and the camera of `edges` (its size);
// fixed_object_ids: objects never moved (the ground) and whose edges are
// not used. edges: StableEdges() of the clip.
ModelRefineResult RefineModel(const Scene& scene, const Camera& camera,
                              const std::vector<int32_t>& fixed_object_ids,
                              const cv::Mat& edges,
                              const ModelRefineOptions& options = {});

// The model with the corrections applied (objects not refined as they were).
Scene CorrectedScene(const Scene& scene, const ModelRefineResult& result);
// The camera turned and zoomed (any size: the focal factor scales K).
Camera CorrectedCamera(const Camera& camera, const CameraCorrection& c);

}  // namespace sunlapse
