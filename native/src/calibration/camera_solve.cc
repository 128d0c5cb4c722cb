#include "sunlapse/calibration/camera_solve.h"
#include "sunlapse/common/require.h"

#include <cmath>
#include <stdexcept>

#include <Eigen/Eigenvalues>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

namespace sunlapse {
namespace {

// The best-fit plane of the points: its centre, its axes (rows: the two in
// the plane by decreasing spread, then the normal, right-handed), and how far
// the points leave it relative to their spread.
struct PlaneFit {
  Eigen::Vector3d mean;
  Eigen::Matrix3d plane_from_world;
  double flatness;
};

PlaneFit FitPlane(const std::vector<Eigen::Vector3d>& p) {
  PlaneFit f;
  f.mean.setZero();
  for (const auto& v : p) f.mean += v;
  f.mean /= p.size();
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& v : p) cov += (v - f.mean) * (v - f.mean).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
  f.plane_from_world.row(0) = es.eigenvectors().col(2).transpose();
  f.plane_from_world.row(1) = es.eigenvectors().col(1).transpose();
  f.plane_from_world.row(2) = es.eigenvectors().col(0).transpose();
  if (f.plane_from_world.determinant() < 0) f.plane_from_world.row(2) *= -1;
  f.flatness = std::sqrt(std::max(0.0, es.eigenvalues()[0]) /
                         std::max(1e-30, es.eigenvalues()[2]));
  return f;
}

}  // namespace

void CameraSolveOptions::Check() const {
  Require(std::isfinite(focal_px), "focal_px must be finite");
}

CameraSolveResult SolveCamera(const std::vector<Eigen::Vector3d>& world,
                              const std::vector<Eigen::Vector2d>& pixels,
                              int width, int height,
                              const CameraSolveOptions& o) {
  o.Check();
  Require(width > 0 && height > 0, "width and height must be > 0");
  Require(world.size() == pixels.size(),
          "points_in_world and pixels differ in length");
  for (const auto& p : world)
    Require(p.allFinite(), "points_in_world: not finite");
  for (const auto& p : pixels) Require(p.allFinite(), "pixels: not finite");
  CameraSolveResult out;
  const bool estimate_focal = !(o.focal_px > 0);
  const size_t need = estimate_focal ? 6 : 4;
  if (world.size() < need) {
    out.status = CameraSolveResult::Status::kTooFewPoints;
    out.message = "need at least " + std::to_string(need) + " marked points" +
                  (estimate_focal ? " to estimate the focal length" : "") +
                  ", got " + std::to_string(world.size());
    return out;
  }
  const double cx =
      std::isfinite(o.principal_x_px) ? o.principal_x_px : 0.5 * width - 0.5;
  const double cy =
      std::isfinite(o.principal_y_px) ? o.principal_y_px : 0.5 * height - 0.5;
  std::vector<cv::Point3f> obj;
  std::vector<cv::Point2f> img;
  for (size_t i = 0; i < world.size(); ++i) {
    obj.emplace_back(world[i].x(), world[i].y(), world[i].z());
    img.emplace_back(pixels[i].x(), pixels[i].y());
  }
  double f = o.focal_px;
  cv::Mat rvec, tvec;
  try {
    if (estimate_focal) {
      const PlaneFit plane = FitPlane(world);
      if (plane.flatness > 1e-3) {
        out.status = CameraSolveResult::Status::kNotCoplanar;
        out.message =
            "estimating the focal length needs coplanar points (e.g. all on "
            "the "
            "ground); give the focal length for points off one plane";
        return out;
      }
      // Planar calibration from one view: focal only (centre fixed, square
      // pixels, no distortion), in the points' own plane coordinates.
      std::vector<cv::Point3f> planar;
      for (const auto& v : world) {
        const Eigen::Vector3d q = plane.plane_from_world * (v - plane.mean);
        planar.emplace_back(q.x(), q.y(), 0.f);
      }
      cv::Mat K =
          (cv::Mat_<double>(3, 3) << width, 0, cx, 0, width, cy, 0, 0, 1);
      cv::Mat dist = cv::Mat::zeros(5, 1, CV_64F);
      std::vector<cv::Mat> rv, tv;
      cv::calibrateCamera(
          std::vector<std::vector<cv::Point3f>>{planar},
          std::vector<std::vector<cv::Point2f>>{img}, cv::Size(width, height),
          K, dist, rv, tv,
          cv::CALIB_USE_INTRINSIC_GUESS | cv::CALIB_FIX_PRINCIPAL_POINT |
              cv::CALIB_FIX_ASPECT_RATIO | cv::CALIB_ZERO_TANGENT_DIST |
              cv::CALIB_FIX_K1 | cv::CALIB_FIX_K2 | cv::CALIB_FIX_K3);
      f = K.at<double>(0, 0);
      if (!(f > 0) || !std::isfinite(f)) {
        out.status = CameraSolveResult::Status::kNoFocal;
        out.message =
            "the focal length could not be estimated (points too few or seen "
            "head-on): give the focal length";
        return out;
      }
    }
    const cv::Mat K = (cv::Mat_<double>(3, 3) << f, 0, cx, 0, f, cy, 0, 0, 1);
    cv::solvePnP(obj, img, K, cv::noArray(), rvec, tvec, false,
                 cv::SOLVEPNP_SQPNP);
    cv::solvePnPRefineLM(obj, img, K, cv::noArray(), rvec, tvec);
    std::vector<cv::Point2f> back;
    cv::projectPoints(obj, rvec, tvec, K, cv::noArray(), back);
    double sum2 = 0;
    for (size_t i = 0; i < img.size(); ++i) {
      const double e = std::hypot(back[i].x - img[i].x, back[i].y - img[i].y);
      out.errors_px.push_back(e);
      sum2 += e * e;
    }
    out.rms_px = std::sqrt(sum2 / img.size());
  } catch (const cv::Exception& e) {
    out.status = CameraSolveResult::Status::kFailed;
    out.message = std::string("the solve failed: ") + e.what();
    return out;
  }
  cv::Mat R;
  cv::Rodrigues(rvec, R);
  Eigen::Matrix3d r;
  Eigen::Vector3d t;
  cv::cv2eigen(R, r);
  cv::cv2eigen(tvec, t);
  out.focal_px = f;
  out.K << f, 0, cx, 0, f, cy, 0, 0, 1;
  out.cam_from_world.linear() = r;
  out.cam_from_world.translation() = t;
  const Eigen::Matrix3d world_from_cam = r.transpose();
  out.blender_matrix_world.block<3, 1>(0, 0) = world_from_cam.col(0);
  out.blender_matrix_world.block<3, 1>(0, 1) = -world_from_cam.col(1);
  out.blender_matrix_world.block<3, 1>(0, 2) = -world_from_cam.col(2);
  out.blender_matrix_world.block<3, 1>(0, 3) = -world_from_cam * t;
  // Every point must lie in front of the camera.
  for (const auto& p : world) {
    if ((r * p + t).z() <= 0) {
      out.status = CameraSolveResult::Status::kBehindCamera;
      out.message =
          "the solution puts marked points behind the camera: check the points";
      return out;
    }
  }
  out.status = CameraSolveResult::Status::kSuccess;
  if (out.rms_px > 3.0) {
    out.message = "reprojection error " +
                  std::to_string(out.rms_px).substr(0, 5) +
                  " px: some points may be marked or named wrongly";
  }
  return out;
}

}  // namespace sunlapse
