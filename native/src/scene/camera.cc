#include "sunlapse/scene/camera.h"
#include "sunlapse/common/require.h"

#include <Eigen/SVD>

#include <cmath>
#include <stdexcept>
#include <string>

namespace sunlapse {
namespace {

bool Finite(double v) { return std::isfinite(v); }

}  // namespace

void BlenderCameraParams::Check() const {
  Require(Finite(lens_mm) && lens_mm > 0, "lens_mm must be > 0");
  Require(Finite(sensor_width_mm) && sensor_width_mm > 0,
          "sensor_width_mm must be > 0");
  Require(Finite(sensor_height_mm) && sensor_height_mm > 0,
          "sensor_height_mm must be > 0");
  Require(Finite(shift_x) && Finite(shift_y), "shift_x/shift_y must be finite");
  Require(width > 0 && height > 0, "width and height must be > 0 pixels");
  Require(Finite(pixel_aspect_x) && pixel_aspect_x > 0 &&
              Finite(pixel_aspect_y) && pixel_aspect_y > 0,
          "pixel_aspect_x/pixel_aspect_y must be > 0");
  Require(world_from_camera_local.allFinite(),
          "world_from_camera_local must be finite");
  const Eigen::Matrix3d m = world_from_camera_local.topLeftCorner<3, 3>();
  for (int c = 0; c < 3; ++c) {
    Require(m.col(c).norm() > 1e-12,
            "world_from_camera_local has a zero scale axis");
  }
}

void PolynomialDistortion::Check() const {
  Require(Finite(focal_x_px) && focal_x_px > 0 && Finite(focal_y_px) &&
              focal_y_px > 0,
          "distortion focal length must be > 0 pixels");
  Require(Finite(principal_x_px) && Finite(principal_y_px),
          "distortion principal point must be finite");
  Require(Finite(k1) && Finite(k2) && Finite(k3),
          "distortion k1/k2/k3 must be finite");
}

Eigen::Vector2d PolynomialDistortion::Undistort(
    const Eigen::Vector2d& distorted_px) const {
  const double xd = (distorted_px.x() - principal_x_px) / focal_x_px;
  const double yd = (distorted_px.y() - principal_y_px) / focal_y_px;
  const double rd = std::hypot(xd, yd);
  if (rd < 1e-15) return distorted_px;
  // Solve g(r) = r (1 + k1 r^2 + k2 r^4 + k3 r^6) = rd for r by Newton.
  double r = rd;
  for (int it = 0; it < 50; ++it) {
    const double r2 = r * r;
    const double g = r * (1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))) - rd;
    const double dg = 1.0 + r2 * (3.0 * k1 + r2 * (5.0 * k2 + r2 * 7.0 * k3));
    if (dg <= 1e-12) break;  // past the fold of the polynomial: keep best r
    const double step = g / dg;
    r -= step;
    if (std::abs(step) < 1e-14) break;
  }
  const double s = r / rd;
  return {principal_x_px + focal_x_px * xd * s,
          principal_y_px + focal_y_px * yd * s};
}

Camera::Camera(const Eigen::Matrix3d& K,
               const Eigen::Isometry3d& cam_from_world, int width, int height)
    : K_(K),
      K_inv_(K.inverse()),
      cam_from_world_(cam_from_world),
      world_from_cam_(cam_from_world.inverse()),
      width_(width),
      height_(height) {
  Require(width > 0 && height > 0, "width and height must be > 0 pixels");
  Require(K.allFinite() && std::abs(K.determinant()) > 0,
          "K must be invertible");
}

Camera Camera::Resized(int width, int height) const {
  Require(width > 0 && height > 0, "width and height must be > 0 pixels");
  const double sx = static_cast<double>(width) / width_;
  const double sy = static_cast<double>(height) / height_;
  // u' = sx u + (sx - 1) / 2: a scale about the corner of the first pixel.
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
  S(0, 0) = sx, S(1, 1) = sy;
  S(0, 2) = 0.5 * (sx - 1.0), S(1, 2) = 0.5 * (sy - 1.0);
  Camera out(S * K_, cam_from_world_, width, height);
  if (distortion_) {
    PolynomialDistortion d = *distortion_;
    d.focal_x_px *= sx, d.focal_y_px *= sy;
    d.principal_x_px = sx * d.principal_x_px + 0.5 * (sx - 1.0);
    d.principal_y_px = sy * d.principal_y_px + 0.5 * (sy - 1.0);
    out.SetDistortion(d);
  }
  return out;
}

Camera Camera::FromBlender(const BlenderCameraParams& p) {
  p.Check();
  const double W = p.width, H = p.height;
  const double size_x = p.pixel_aspect_x * W, size_y = p.pixel_aspect_y * H;
  // BKE_camera_sensor_size: AUTO and HORIZONTAL use sensor_width.
  const double sensor = p.sensor_fit == SensorFit::kVertical
                            ? p.sensor_height_mm
                            : p.sensor_width_mm;
  bool horizontal = p.sensor_fit == SensorFit::kHorizontal;
  if (p.sensor_fit == SensorFit::kAuto) horizontal = size_x >= size_y;
  // Pixel height over pixel width, as Blender's ycor.
  const double ycor = p.pixel_aspect_y / p.pixel_aspect_x;
  const double viewfac = horizontal ? W : ycor * H;
  const double fx = p.lens_mm * viewfac / sensor;
  const double fy = fx / ycor;
  // Shift moves the view plane by shift * viewfac pixels; the -0.5 moves the
  // origin from the image corner to the centre of the top-left pixel.
  const double cx = 0.5 * W - p.shift_x * viewfac - 0.5;
  const double cy = 0.5 * H + p.shift_y * viewfac / ycor - 0.5;
  Eigen::Matrix3d K;
  K << fx, 0, cx, 0, fy, cy, 0, 0, 1;

  Eigen::Matrix3d axes = p.world_from_camera_local.topLeftCorner<3, 3>();
  for (int c = 0; c < 3; ++c) axes.col(c).normalize();
  Require((axes.transpose() * axes - Eigen::Matrix3d::Identity())
                  .cwiseAbs()
                  .maxCoeff() < 1e-5,
          "world_from_camera_local has shear (non-uniform scale on a rotated "
          "parent); apply the scale to the camera");
  // Blender stores matrices in float32: snap to the nearest rotation so that
  // projection and back-projection are exact inverses.
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(
      axes, Eigen::ComputeFullU | Eigen::ComputeFullV);
  axes = svd.matrixU() * svd.matrixV().transpose();
  // Blender camera local (+Y up, looking along -Z) -> OpenCV camera.
  Eigen::Matrix3d world_from_cam_rot;
  world_from_cam_rot << axes.col(0), -axes.col(1), -axes.col(2);
  Eigen::Isometry3d world_from_cam = Eigen::Isometry3d::Identity();
  world_from_cam.linear() = world_from_cam_rot;
  world_from_cam.translation() = p.world_from_camera_local.block<3, 1>(0, 3);
  return Camera(K, world_from_cam.inverse(), p.width, p.height);
}

void Camera::SetDistortion(const PolynomialDistortion& distortion) {
  distortion.Check();
  if (distortion.IsIdentity()) {
    distortion_.reset();
  } else {
    distortion_ = distortion;
  }
}

Eigen::Vector3d Camera::center_in_world() const {
  return world_from_cam_.translation();
}

Eigen::Vector3d Camera::PixelToRayInWorld(const Eigen::Vector2d& pixel) const {
  const Eigen::Vector2d ideal =
      distortion_ ? distortion_->Undistort(pixel) : pixel;
  const Eigen::Vector3d ray_in_cam = K_inv_ * ideal.homogeneous();
  return (world_from_cam_.linear() * ray_in_cam).normalized();
}

double Camera::Depth(const Eigen::Vector3d& point_in_world) const {
  return (cam_from_world_ * point_in_world).z();
}

bool Camera::WorldToPixel(const Eigen::Vector3d& point_in_world,
                          Eigen::Vector2d* pixel) const {
  const Eigen::Vector3d point_in_cam = cam_from_world_ * point_in_world;
  if (!(point_in_cam.z() > 0)) return false;
  *pixel = CamPointToPixel(point_in_cam, 1.0);
  return true;
}

}  // namespace sunlapse
