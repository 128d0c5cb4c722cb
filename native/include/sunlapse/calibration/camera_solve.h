// Matching a camera to footage from points the user marks on a frame whose
// positions in the scene are known (a plate's corners, a dial's lines, the
// foot of a post): what every user with real footage must do before the
// estimators can run. OpenCV's planar calibration finds the focal length from
// one view (when the points are coplanar and seen obliquely), PnP the pose.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace sunlapse {

struct CameraSolveOptions {
  // Focal length in pixels; <= 0: estimate it (needs >= 6 coplanar points
  // seen at an angle, or >= 6 non-coplanar points).
  double focal_px = 0.0;
  // Principal point (OpenCV pixels); NaN: the image centre.
  double principal_x_px = NAN;
  double principal_y_px = NAN;

  void Check() const;
};

struct CameraSolveResult {
  enum class Status {
    kSuccess,       // a camera (the message may warn of a large error)
    kTooFewPoints,  // fewer marked points than the solve needs
    kNotCoplanar,   // the focal length needs points on one plane
    kNoFocal,       // the focal length could not be estimated
    kFailed,        // the solver itself failed
    kBehindCamera,  // the solution puts marked points behind the camera
  };
  Status status = Status::kFailed;
  bool ok() const { return status == Status::kSuccess; }
  std::string message;
  double focal_px = 0.0;
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();
  Eigen::Isometry3d cam_from_world =
      Eigen::Isometry3d::Identity();  // OpenCV camera
  // Blender's Object.matrix_world for the camera (local -Z forward, +Y up).
  Eigen::Matrix4d blender_matrix_world = Eigen::Matrix4d::Identity();
  double rms_px = 0.0;            // reprojection error
  std::vector<double> errors_px;  // per point
};

// points_in_world: N x 3 (world frame, metres); pixels: N x 2 (OpenCV pixels).
CameraSolveResult SolveCamera(
    const std::vector<Eigen::Vector3d>& points_in_world,
    const std::vector<Eigen::Vector2d>& pixels, int width, int height,
    const CameraSolveOptions& options = {});

}  // namespace sunlapse
