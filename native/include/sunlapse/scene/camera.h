// Pinhole camera built from what Blender knows about a camera.
//
// Frames (docs/design.md §4): the world is Blender's (+Z up, metres). Inside
// this class the camera frame is OpenCV's: x right, y down, z forward
// (Blender's camera looks along its local -Z with +Y up, so cam = diag(1,-1,-1)
// * local). Pixels are OpenCV's: (0,0) is the centre of the top-left pixel.
#pragma once

#include <optional>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace sunlapse {

enum class SensorFit { kAuto, kHorizontal, kVertical };

// A camera as Blender describes it (bpy.types.Camera + render settings).
struct BlenderCameraParams {
  // Focal length in millimetres (Camera.lens).
  double lens_mm = 50.0;
  // Sensor size in millimetres (Camera.sensor_width / sensor_height).
  double sensor_width_mm = 36.0;
  double sensor_height_mm = 24.0;
  // Camera.sensor_fit. AUTO uses sensor_width along the larger image side.
  SensorFit sensor_fit = SensorFit::kAuto;
  // Camera.shift_x / shift_y, in units of the fitted sensor side.
  double shift_x = 0.0;
  double shift_y = 0.0;
  // Image size in pixels (render resolution with its percentage applied, or
  // the clip's size when it has the same aspect).
  int width = 1920;
  int height = 1080;
  // Render pixel aspect (pixel_aspect_x / pixel_aspect_y).
  double pixel_aspect_x = 1.0;
  double pixel_aspect_y = 1.0;
  // Object.matrix_world of the camera. Scale is removed the way
  // Matrix.normalized() does in bpy_extras.world_to_camera_view.
  Eigen::Matrix4d world_from_camera_local = Eigen::Matrix4d::Identity();

  // Throws std::invalid_argument naming the first bad field.
  void Check() const;
};

// Blender's polynomial lens distortion (MovieTrackingCamera with
// distortion_model 'POLYNOMIAL'): x_d = x_u (1 + k1 r^2 + k2 r^4 + k3 r^6) in
// coordinates normalised by the focal length, centred on the principal point.
struct PolynomialDistortion {
  // Focal length in pixels (MovieTrackingCamera.focal_length_pixels) and the
  // vertical focal length (focal * pixel_aspect).
  double focal_x_px = 1.0;
  double focal_y_px = 1.0;
  // Principal point in OpenCV pixels (Blender stores it from the bottom-left
  // corner; the glue, addon/blender/gather.py, converts).
  double principal_x_px = 0.0;
  double principal_y_px = 0.0;
  double k1 = 0.0, k2 = 0.0, k3 = 0.0;

  void Check() const;
  bool IsIdentity() const { return k1 == 0.0 && k2 == 0.0 && k3 == 0.0; }
  // Undistorted (ideal pinhole) pixel -> distorted (recorded) pixel.
  Eigen::Vector2d Distort(const Eigen::Vector2d& undistorted_px) const {
    return Distort(undistorted_px, 1.0);
  }
  // The same with both focal lengths scaled by focal_scale, for any scalar
  // (the model refinement differentiates it with Ceres's Jets).
  template <typename T>
  Eigen::Matrix<T, 2, 1> Distort(const Eigen::Matrix<T, 2, 1>& undistorted_px,
                                 const T& focal_scale) const {
    const T fx = focal_scale * focal_x_px, fy = focal_scale * focal_y_px;
    const T x = (undistorted_px.x() - principal_x_px) / fx;
    const T y = (undistorted_px.y() - principal_y_px) / fy;
    const T r2 = x * x + y * y;
    const T f = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
    return Eigen::Matrix<T, 2, 1>(principal_x_px + fx * x * f,
                                  principal_y_px + fy * y * f);
  }
  // Recorded pixel -> ideal pixel, by Newton iterations on the radius.
  Eigen::Vector2d Undistort(const Eigen::Vector2d& distorted_px) const;
};

class Camera {
 public:
  // K: 3x3 intrinsics in OpenCV pixels; cam_from_world: rigid transform.
  Camera(const Eigen::Matrix3d& K, const Eigen::Isometry3d& cam_from_world,
         int width, int height);

  // The one function that maps Blender's camera model to K and pose.
  static Camera FromBlender(const BlenderCameraParams& params);

  void SetDistortion(const PolynomialDistortion& distortion);
  const std::optional<PolynomialDistortion>& distortion() const {
    return distortion_;
  }

  // The same camera for its image resized to width x height (OpenCV's
  // resize: pixel centres scale about the image's corner, u' = (u + 0.5) *
  // width' / width - 0.5).
  Camera Resized(int width, int height) const;
  const Eigen::Matrix3d& K() const { return K_; }
  const Eigen::Isometry3d& cam_from_world() const { return cam_from_world_; }
  Eigen::Vector3d center_in_world() const;
  int width() const { return width_; }
  int height() const { return height_; }

  // Recorded pixel -> unit direction of the viewing ray in world frame.
  // Undistorts first when a distortion is set.
  Eigen::Vector3d PixelToRayInWorld(const Eigen::Vector2d& pixel) const;
  // World point -> recorded pixel (distorted when a distortion is set).
  // Returns false (and leaves *pixel unset) when the point is not in front.
  bool WorldToPixel(const Eigen::Vector3d& point_in_world,
                    Eigen::Vector2d* pixel) const;
  // A point in front of the camera, in the camera frame -> recorded pixel,
  // with both focal lengths scaled by focal_scale (1: this camera); for any
  // scalar (the model refinement differentiates it with Ceres's Jets).
  template <typename T>
  Eigen::Matrix<T, 2, 1> CamPointToPixel(
      const Eigen::Matrix<T, 3, 1>& point_in_cam, const T& focal_scale) const {
    const T& x = point_in_cam.x();
    const T& y = point_in_cam.y();
    const T& z = point_in_cam.z();
    const T w = K_(2, 0) * x + K_(2, 1) * y + K_(2, 2) * z;
    const Eigen::Matrix<T, 2, 1> ideal(
        (focal_scale * (K_(0, 0) * x + K_(0, 1) * y) + K_(0, 2) * z) / w,
        (focal_scale * (K_(1, 0) * x + K_(1, 1) * y) + K_(1, 2) * z) / w);
    return distortion_ ? distortion_->Distort(ideal, focal_scale) : ideal;
  }
  // Depth along the optical axis (metres, > 0 in front).
  double Depth(const Eigen::Vector3d& point_in_world) const;

 private:
  Eigen::Matrix3d K_;
  Eigen::Matrix3d K_inv_;
  Eigen::Isometry3d cam_from_world_;
  Eigen::Isometry3d world_from_cam_;
  int width_;
  int height_;
  std::optional<PolynomialDistortion> distortion_;
};

}  // namespace sunlapse
