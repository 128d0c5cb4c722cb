#include "sunlapse/refine/model_refine.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <sstream>
#include <utility>

#include <ceres/ceres.h>
#include <ceres/cubic_interpolation.h>
#include <ceres/rotation.h>
#include <tbb/parallel_for.h>
#include <opencv2/imgproc.hpp>

#include "sunlapse/common/angles.h"
#include "sunlapse/common/order_statistics.h"
#include "sunlapse/common/require.h"

namespace sunlapse {
namespace {

// Median of a frame's level, from every 16th pixel (a frame's brightness).
double MedianLevel(const cv::Mat& f) {
  std::vector<float> v;
  v.reserve(f.total() / 16 + 1);
  for (int y = 0; y < f.rows; y += 4) {
    const float* row = f.ptr<float>(y);
    for (int x = 0; x < f.cols; x += 4) v.push_back(row[x]);
  }
  if (v.empty()) return 0.0;
  return MedianInPlace(&v);
}

// m at (x, y), bilinearly, for x and y inside the image (m >= 2x2).
float Bilinear(const cv::Mat& m, double x, double y) {
  const int x0 = std::min(static_cast<int>(x), m.cols - 2);
  const int y0 = std::min(static_cast<int>(y), m.rows - 2);
  const double fx = x - x0, fy = y - y0;
  return static_cast<float>((1 - fy) * ((1 - fx) * m.at<float>(y0, x0) +
                                        fx * m.at<float>(y0, x0 + 1)) +
                            fy * ((1 - fx) * m.at<float>(y0 + 1, x0) +
                                  fx * m.at<float>(y0 + 1, x0 + 1)));
}

// A footprint's axes (columns): its first axis (horizontal), z x it, z.
Eigen::Matrix3d FootprintAxes(const Eigen::Vector3d& axis) {
  const Eigen::Vector3d a = axis.normalized();
  Eigen::Matrix3d axes;
  axes.col(0) = a;
  axes.col(1) = Eigen::Vector3d::UnitZ().cross(a);
  axes.col(2) = Eigen::Vector3d::UnitZ();
  return axes;
}

// A point on one of the model's edges, in its object's footprint frame.
struct EdgePoint {
  int object = 0;         // index into the refined objects
  Eigen::Vector3d local;  // A^T (p - pivot)
};

struct ObjectFrame {
  Eigen::Vector3d pivot;
  Eigen::Matrix3d axes;  // columns: axis, z x axis, z
  double size_m = 0.0;   // its largest extent (bounding box)
  // How far it may move, and how far a hand-made one is typically off:
  // the options' metres, or less for a small object (ModelRefineOptions).
  double max_move_m = 0.0;
  double move_sigma_m = 0.0;
};

// An object's correction of a point given in its footprint frame (local =
// A^T (x - pivot), A the footprint's axes): scaled along the axes, turned
// about the vertical, moved along the ground. One definition for the fit
// (per point, in the residuals, for doubles and Ceres's Jets: no matrix
// built there) and for ObjectCorrection::Transform().
template <typename T>
Eigen::Matrix<T, 3, 1> CorrectedPoint(const Eigen::Vector3d& pivot,
                                      const Eigen::Matrix3d& axes,
                                      const T* move, const T& turn_rad,
                                      const T* scale,
                                      const Eigen::Vector3d& local) {
  using std::cos;
  using std::sin;
  const T c = cos(turn_rad), s = sin(turn_rad);
  Eigen::Matrix<T, 3, 1> a = Eigen::Matrix<T, 3, 1>::Zero();
  for (int j = 0; j < 3; ++j)
    a += axes.col(j).cast<T>() * (scale[j] * local[j]);
  return Eigen::Matrix<T, 3, 1>(T(pivot.x()) + move[0] + c * a.x() - s * a.y(),
                                T(pivot.y()) + move[1] + s * a.x() + c * a.y(),
                                T(pivot.z()) + a.z());
}

// The fit's parameters o = (move x, move y, turn, log scale along each axis).
template <typename T>
Eigen::Matrix<T, 3, 1> Corrected(const ObjectFrame& f,
                                 const Eigen::Vector3d& local, const T* o) {
  using std::exp;
  const T scale[3] = {exp(o[3]), exp(o[4]), exp(o[5])};
  return CorrectedPoint(f.pivot, f.axes, o, o[2], scale, local);
}

// The camera's pixel of a world point under a camera correction c = (turn
// as an angle-axis in the camera frame, log focal factor); false behind it.
// For doubles and Jets: the fit's derivatives are exact (automatic), not
// differences, which cost 20 residuals a point.
class Projector {
 public:
  explicit Projector(const Camera& camera) : camera_(camera) {}
  template <typename T>
  bool Project(const Eigen::Matrix<T, 3, 1>& p, const T* c,
               Eigen::Matrix<T, 2, 1>* px) const {
    using std::exp;
    const Eigen::Isometry3d& pose = camera_.cam_from_world();
    const Eigen::Matrix<T, 3, 1> in_cam =
        pose.linear().cast<T>() * p + pose.translation().cast<T>();
    Eigen::Matrix<T, 3, 1> x;
    ceres::AngleAxisRotatePoint(c, in_cam.data(), x.data());
    if (x.z() <= T(1e-6)) return false;
    *px = camera_.CamPointToPixel(x, T(exp(c[3])));
    return true;
  }

 private:
  const Camera& camera_;
};

using Interpolator = ceres::BiCubicInterpolator<ceres::Grid2D<double, 1>>;

struct EdgeResidual {
  EdgeResidual(const Projector* projector, const ObjectFrame* frame,
               Eigen::Vector3d local, const Interpolator* distance,
               double far_px, const double* sigma_px)
      : projector(projector),
        frame(frame),
        local(std::move(local)),
        distance(distance),
        far_px(far_px),
        sigma_px(sigma_px) {}
  template <typename T>
  bool operator()(const T* cam, const T* obj, T* r) const {
    Eigen::Matrix<T, 2, 1> px;
    T d(far_px);
    if (projector->Project(Corrected(*frame, local, obj), cam, &px))
      distance->Evaluate(px.y(), px.x(), &d);
    if (d < T(0.0)) d = T(0.0);
    if (d > T(far_px)) d = T(far_px);
    r[0] = d / *sigma_px;
    return true;
  }
  const Projector* projector;
  const ObjectFrame* frame;
  Eigen::Vector3d local;
  const Interpolator* distance;
  double far_px;
  const double* sigma_px;  // coarse, then fine (RefineModel)
};

// A parameter's prior: value / sigma.
struct Prior {
  Prior(int n, std::vector<double> inv_sigma)
      : n(n), inv_sigma(std::move(inv_sigma)) {}
  template <typename T>
  bool operator()(const T* p, T* r) const {
    for (int i = 0; i < n; ++i) r[i] = p[i] * inv_sigma[i];
    return true;
  }
  int n;
  std::vector<double> inv_sigma;
};

// The footprint's smallest rectangle: its centre (at the lowest point) and
// first axis, from the object's vertices.
ObjectFrame FrameOf(const std::vector<Eigen::Vector3d>& vertices) {
  std::vector<cv::Point2f> xy;
  double z_min = vertices.front().z();
  for (const auto& v : vertices) {
    xy.emplace_back(static_cast<float>(v.x()), static_cast<float>(v.y()));
    z_min = std::min(z_min, v.z());
  }
  const cv::RotatedRect rect = cv::minAreaRect(xy);
  const double a = rect.angle * kRadPerDeg;
  ObjectFrame f;
  f.pivot = Eigen::Vector3d(rect.center.x, rect.center.y, z_min);
  f.axes = FootprintAxes(Eigen::Vector3d(std::cos(a), std::sin(a), 0.0));
  Eigen::AlignedBox3d box;
  for (const auto& v : vertices) box.extend(v);
  f.size_m = box.sizes().maxCoeff();
  return f;
}

}  // namespace

void StableEdgesOptions::Check() const {
  Require(min_level_fraction >= 0.0 && min_level_fraction < 1.0,
          "min_level_fraction must be in [0, 1)");
  Require(min_log_gradient > 0.0, "min_log_gradient must be > 0");
  Require(ignore_top_rows >= 0, "ignore_top_rows must be >= 0");
}

cv::Mat StableEdges(const std::vector<cv::Mat>& frames,
                    const StableEdgesOptions& o) {
  o.Check();
  std::vector<const cv::Mat*> usable;
  std::vector<double> levels;
  for (const cv::Mat& f : frames) {
    if (f.empty()) continue;
    Require(f.type() == CV_32FC1, "frames must be CV_32FC1 gray");
    Require(usable.empty() || f.size() == usable.front()->size(),
            "frames must all have one size");
    usable.push_back(&f);
    levels.push_back(MedianLevel(f));
  }
  if (usable.size() < 2) return cv::Mat();
  const double brightest = *std::max_element(levels.begin(), levels.end());
  if (!(brightest > 0)) return cv::Mat();
  const cv::Size size = usable.front()->size();
  std::vector<size_t> lit;
  for (size_t i = 0; i < usable.size(); ++i)
    if (levels[i] >= o.min_level_fraction * brightest) lit.push_back(i);
  if (lit.size() < 2) return cv::Mat();
  // The frames on every core (the estimate waits for this stage): each
  // frame's gradient magnitude, and the structure tensor summed over a
  // fixed share of the frames per task, so that the sums (and the edges)
  // are the same whatever the cores.
  constexpr size_t kShares = 4;
  std::vector<std::array<cv::Mat, 3>> sums(kShares);
  std::vector<cv::Mat> magnitudes(lit.size());
  tbb::parallel_for(size_t(0), kShares, [&](size_t share) {
    std::array<cv::Mat, 3>& j = sums[share];
    for (cv::Mat& m : j) m = cv::Mat::zeros(size, CV_32F);
    for (size_t f = share; f < lit.size(); f += kShares) {
      const size_t i = lit[f];
      // Log intensity: an edge between two faces keeps its strength when
      // the exposure or the Sun's strength changes.
      cv::Mat logi;
      cv::max(*usable[i], 0.0, logi);
      logi += 0.25 * std::max(levels[i], 1e-12);
      cv::log(logi, logi);
      cv::GaussianBlur(logi, logi, cv::Size(0, 0), 1.0);
      cv::Mat gx, gy;
      cv::Sobel(logi, gx, CV_32F, 1, 0, 3, 0.125);
      cv::Sobel(logi, gy, CV_32F, 0, 1, 3, 0.125);
      cv::magnitude(gx, gy, magnitudes[f]);
      j[0] += gx.mul(gx);
      j[1] += gx.mul(gy);
      j[2] += gy.mul(gy);
    }
  });
  cv::Mat jxx = sums[0][0], jxy = sums[0][1], jyy = sums[0][2];
  for (size_t share = 1; share < kShares; ++share) {
    jxx += sums[share][0];
    jxy += sums[share][1];
    jyy += sums[share][2];
  }
  const int k = static_cast<int>(magnitudes.size());
  cv::Mat median(size, CV_32F);
  tbb::parallel_for(0, size.height, [&](int y) {
    std::vector<float> v(k);
    float* out = median.ptr<float>(y);
    for (int x = 0; x < size.width; ++x) {
      for (int i = 0; i < k; ++i) v[i] = magnitudes[i].at<float>(y, x);
      out[x] = MedianInPlace(&v);
    }
  });
  cv::Mat edges = cv::Mat::zeros(size, CV_8U);
  const int top = std::min(o.ignore_top_rows, size.height);
  tbb::parallel_for(std::max(1, top), size.height - 1, [&](int y) {
    for (int x = 1; x < size.width - 1; ++x) {
      const float m = median.at<float>(y, x);
      if (m < o.min_log_gradient) continue;
      // Across the edge: the structure tensor's main direction.
      const double theta =
          0.5 * std::atan2(2.0 * jxy.at<float>(y, x),
                           jxx.at<float>(y, x) - jyy.at<float>(y, x));
      const double dx = std::cos(theta), dy = std::sin(theta);
      if (m >= Bilinear(median, x + dx, y + dy) &&
          m > Bilinear(median, x - dx, y - dy))
        edges.at<uint8_t>(y, x) = 255;
    }
  });
  return edges;
}

void ModelRefineOptions::Check() const {
  Require(max_move_m > 0 && max_turn_deg > 0 && max_scale_change > 0 &&
              max_scale_change < 1 && max_camera_turn_deg > 0 &&
              max_focal_change > 0 && max_focal_change < 1,
          "the max_* bounds must be > 0 (scale and focal changes < 1)");
  Require(max_move_fraction > 0 && move_sigma_fraction > 0,
          "max_move_fraction and move_sigma_fraction must be > 0");
  Require(move_sigma_m > 0 && turn_sigma_deg > 0 && scale_sigma > 0 &&
              camera_turn_sigma_deg > 0 && focal_sigma > 0,
          "the *_sigma priors must be > 0");
  Require(
      edge_spacing_px > 0 && edge_sigma_px > 0 && max_edge_distance_px > 0,
      "edge_spacing_px, edge_sigma_px and max_edge_distance_px must be > 0");
  Require(crease_deg > 0 && crease_deg < 180, "crease_deg must be in (0, 180)");
  Require(min_points_per_object >= 1, "min_points_per_object must be >= 1");
  Require(max_object_distance_px > 0, "max_object_distance_px must be > 0");
  Require(min_distance_before_px >= 0, "min_distance_before_px must be >= 0");
  Require(min_distance_drop >= 0 && min_distance_drop < 1,
          "min_distance_drop must be in [0, 1)");
}

Eigen::Matrix4d ObjectCorrection::Transform() const {
  // The map is affine: its matrix from the images of the origin and the
  // unit points.
  const Eigen::Matrix3d axes = FootprintAxes(axis_in_world);
  auto image = [&](const Eigen::Vector3d& x) {
    return CorrectedPoint(pivot_in_world, axes, move_in_world_m.data(),
                          turn_deg * kRadPerDeg, scale.data(),
                          axes.transpose() * (x - pivot_in_world));
  };
  Eigen::Matrix4d t = Eigen::Matrix4d::Identity();
  const Eigen::Vector3d origin = image(Eigen::Vector3d::Zero());
  for (int j = 0; j < 3; ++j)
    t.block<3, 1>(0, j) = image(Eigen::Vector3d::Unit(j)) - origin;
  t.topRightCorner<3, 1>() = origin;
  return t;
}

ModelRefineResult RefineModel(const Scene& scene, const Camera& camera,
                              const std::vector<int32_t>& fixed_object_ids,
                              const cv::Mat& edges,
                              const ModelRefineOptions& o) {
  o.Check();
  ModelRefineResult out;
  if (edges.empty()) {
    out.status = ModelRefineResult::Status::kNoEdges;
    out.message = "the clip shows no edges that stay put";
    return out;
  }
  Require(edges.type() == CV_8UC1, "edges must be CV_8UC1");
  Require(edges.cols == camera.width() && edges.rows == camera.height(),
          "edges must be of the camera's size");

  // Distance (px) to the nearest stable edge, capped.
  cv::Mat distance;
  cv::distanceTransform(edges == 0, distance, cv::DIST_L2,
                        cv::DIST_MASK_PRECISE);
  cv::Mat capped;
  cv::min(distance, o.max_edge_distance_px, capped);
  cv::Mat distance64;
  capped.convertTo(distance64, CV_64F);
  ceres::Grid2D<double, 1> grid(distance64.ptr<double>(), 0, distance64.rows, 0,
                                distance64.cols);
  const Interpolator interpolate(grid);

  // Each object's triangles, and its frame.
  std::map<int32_t, std::vector<int64_t>> triangles_of;
  for (int64_t t = 0; t < scene.num_triangles(); ++t)
    triangles_of[scene.object_id_of_triangle(t)].push_back(t);
  const Eigen::Vector3d centre = camera.center_in_world();
  const float offset = scene.surface_offset();

  std::vector<ObjectFrame> frames;
  std::vector<int32_t> ids;
  std::vector<EdgePoint> points;
  for (const auto& [id, tris] : triangles_of) {
    if (std::find(fixed_object_ids.begin(), fixed_object_ids.end(), id) !=
        fixed_object_ids.end())
      continue;
    std::vector<Eigen::Vector3d> vertices;
    // Edge (v0 < v1) -> (normal, third vertex) of its triangles.
    std::map<std::pair<int, int>,
             std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>>>
        edge_faces;
    for (int64_t t : tris) {
      const Eigen::Vector3i tri = scene.triangle(t);
      Eigen::Vector3d p[3];
      for (int j = 0; j < 3; ++j) {
        p[j] = scene.vertex(tri[j]).cast<double>();
        vertices.push_back(p[j]);
      }
      const Eigen::Vector3d n = (p[1] - p[0]).cross(p[2] - p[0]);
      if (n.norm() < 1e-12) continue;
      for (int j = 0; j < 3; ++j) {
        const int a = tri[j], b = tri[(j + 1) % 3];
        edge_faces[{std::min(a, b), std::max(a, b)}].emplace_back(
            n.normalized(), p[(j + 2) % 3]);
      }
    }
    if (vertices.empty()) continue;
    ObjectFrame frame = FrameOf(vertices);
    frame.max_move_m =
        std::min(o.max_move_m, o.max_move_fraction * frame.size_m);
    frame.move_sigma_m =
        std::min(o.move_sigma_m, o.move_sigma_fraction * frame.size_m);
    const double cos_crease = std::cos(o.crease_deg * kRadPerDeg);
    std::vector<Eigen::Vector3d> samples;
    for (const auto& [edge, faces] : edge_faces) {
      const Eigen::Vector3d a = scene.vertex(edge.first).cast<double>();
      const Eigen::Vector3d b = scene.vertex(edge.second).cast<double>();
      bool feature = faces.size() != 2;  // an open border, or non-manifold
      if (!feature) {
        // A crease, or an outline: both faces on one side of the plane
        // through the camera and the edge. Neither depends on which way
        // the triangles are wound.
        const Eigen::Vector3d m = (a - centre).cross(b - centre);
        const double s0 = m.dot(faces[0].second - centre),
                     s1 = m.dot(faces[1].second - centre);
        feature = std::abs(faces[0].first.dot(faces[1].first)) < cos_crease ||
                  (s0 > 0) == (s1 > 0);
      }
      if (!feature) continue;
      Eigen::Vector2d pa, pb;
      if (!camera.WorldToPixel(a, &pa) || !camera.WorldToPixel(b, &pb))
        continue;
      const int n = std::min(
          2000,
          static_cast<int>(std::ceil((pb - pa).norm() / o.edge_spacing_px)));
      for (int i = 0; i < n; ++i)
        samples.push_back(a + (b - a) * ((i + 0.5) / n));
    }
    // Visible from the camera, and inside the image.
    std::vector<Eigen::Vector3d> kept;
    for (const auto& s : samples) {
      Eigen::Vector2d px;
      const double m = o.max_edge_distance_px;
      if (!camera.WorldToPixel(s, &px) || px.x() < m || px.y() < m ||
          px.x() > camera.width() - 1 - m || px.y() > camera.height() - 1 - m)
        continue;
      kept.push_back(s);
    }
    // Visible: the first hit from the camera toward the point is the point
    // (within a margin, so that a ray grazing the edge's own faces counts).
    std::vector<float> origins, directions, hit(kept.size());
    for (const auto& s : kept) {
      const Eigen::Vector3d d = (s - centre).normalized();
      for (int j = 0; j < 3; ++j) {
        origins.push_back(static_cast<float>(centre[j]));
        directions.push_back(static_cast<float>(d[j]));
      }
    }
    HitBuffers buffers;
    buffers.distance = hit.data();
    scene.Intersect(static_cast<int64_t>(kept.size()), origins.data(),
                    directions.data(), 0.0f,
                    std::numeric_limits<float>::infinity(), buffers);
    std::vector<uint8_t> occluded(kept.size(), 0);
    for (size_t i = 0; i < kept.size(); ++i) {
      const double dist = (kept[i] - centre).norm();
      occluded[i] = hit[i] < dist - std::max(0.02, 0.003 * dist) - offset;
    }
    const int index = static_cast<int>(frames.size());
    for (size_t i = 0; i < kept.size(); ++i) {
      if (occluded[i]) continue;
      points.push_back(
          {index, frame.axes.transpose() * (kept[i] - frame.pivot)});
    }
    frames.push_back(frame);
    ids.push_back(id);
  }

  // Objects with enough points are refined; the others keep their place.
  std::vector<int> count(frames.size(), 0);
  for (const auto& p : points) ++count[p.object];
  std::vector<std::array<double, 6>> params(frames.size(), {0, 0, 0, 0, 0, 0});
  std::array<double, 4> cam = {0, 0, 0, 0};
  const Projector projector(camera);
  // The loss's scale: wide first, so that edges several pixels off are
  // pulled in, then the edges' own sharpness.
  double sigma_px = o.edge_sigma_px;
  const double unit = 1.0;
  ceres::Problem problem;
  std::vector<const EdgePoint*> used;
  std::vector<std::vector<ceres::ResidualBlockId>> blocks(frames.size());
  for (const auto& p : points) {
    if (count[p.object] < o.min_points_per_object) continue;
    used.push_back(&p);
    auto* cost = new ceres::AutoDiffCostFunction<EdgeResidual, 1, 4, 6>(
        new EdgeResidual(&projector, &frames[p.object], p.local, &interpolate,
                         o.max_edge_distance_px, &sigma_px));
    blocks[p.object].push_back(problem.AddResidualBlock(
        cost, new ceres::CauchyLoss(1.0), cam.data(), params[p.object].data()));
  }
  out.points = static_cast<int>(used.size());
  if (used.empty()) {
    out.status = ModelRefineResult::Status::kNoEdges;
    out.message = "fewer than " + std::to_string(o.min_points_per_object) +
                  " of any object's edge points are in view";
    return out;
  }
  const double cam_sigma = o.camera_turn_sigma_deg * kRadPerDeg;
  problem.AddResidualBlock(
      new ceres::AutoDiffCostFunction<Prior, 4, 4>(
          new Prior(4, {1 / cam_sigma, 1 / cam_sigma, 1 / cam_sigma,
                        1 / std::log1p(o.focal_sigma)})),
      nullptr, cam.data());
  const double cam_max = o.max_camera_turn_deg * kRadPerDeg;
  for (int i = 0; i < 3; ++i) {
    problem.SetParameterLowerBound(cam.data(), i, -cam_max);
    problem.SetParameterUpperBound(cam.data(), i, cam_max);
  }
  problem.SetParameterLowerBound(cam.data(), 3,
                                 std::log1p(-o.max_focal_change));
  problem.SetParameterUpperBound(cam.data(), 3, std::log1p(o.max_focal_change));
  const double ls = std::log1p(o.scale_sigma);
  for (size_t k = 0; k < frames.size(); ++k) {
    if (count[k] < o.min_points_per_object) continue;
    double* q = params[k].data();
    problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<Prior, 6, 6>(new Prior(
            6, {1 / frames[k].move_sigma_m, 1 / frames[k].move_sigma_m,
                1 / (o.turn_sigma_deg * kRadPerDeg), 1 / ls, 1 / ls, 1 / ls})),
        nullptr, q);
    const double bounds[6] = {
        frames[k].max_move_m,           frames[k].max_move_m,
        o.max_turn_deg * kRadPerDeg,    std::log1p(o.max_scale_change),
        std::log1p(o.max_scale_change), std::log1p(o.max_scale_change)};
    for (int i = 0; i < 6; ++i) {
      problem.SetParameterLowerBound(
          q, i, i < 3 ? -bounds[i] : std::log1p(-o.max_scale_change));
      problem.SetParameterUpperBound(q, i, bounds[i]);
    }
  }

  // Mean capped distance per object under the current parameters.
  auto distances = [&](std::vector<double>* per_object) {
    per_object->assign(frames.size(), 0.0);
    double sum = 0.0;
    for (const EdgePoint* p : used) {
      double r = 0.0;
      EdgeResidual(&projector, &frames[p->object], p->local, &interpolate,
                   o.max_edge_distance_px,
                   &unit)(cam.data(), params[p->object].data(), &r);
      (*per_object)[p->object] += r;
      sum += r;
    }
    for (size_t k = 0; k < frames.size(); ++k)
      if (count[k] > 0) (*per_object)[k] /= count[k];
    return sum / used.size();
  };
  std::vector<double> before, after;
  out.distance_before_px = distances(&before);
  // An object's account before any correction, and the result's sentence.
  auto unrefined = [&](size_t k) {
    ObjectCorrection c;
    c.object_id = ids[k];
    c.pivot_in_world = frames[k].pivot;
    c.axis_in_world = frames[k].axes.col(0);
    c.points = count[k];
    c.distance_before_px = before[k];
    return c;
  };
  auto said = [&]() {
    std::ostringstream msg;
    msg.precision(3);
    msg << out.points << " edge points of the model, " << out.distance_before_px
        << " px from the clip's edges on average";
    return msg.str();
  };
  if (out.distance_before_px < o.min_distance_before_px) {
    // The model already fits: whatever the fit found would not be used
    // (below), so it is not run. Most models are, and the fit is most of
    // the stage's time (about 0.22 of 0.35 s on the 1080p bench clip).
    for (size_t k = 0; k < frames.size(); ++k) {
      if (count[k] == 0) continue;
      out.objects.push_back(unrefined(k));
      out.objects.back().distance_after_px = before[k];
    }
    out.distance_after_px = out.distance_before_px;
    out.status = ModelRefineResult::Status::kUnchanged;
    out.message = said() + "; the model already fits the clip";
    return out;
  }

  // Each object starts from its best move on a grid over the bounds (a
  // chamfer search): the continuous fit alone stops at the nearest edges,
  // which for a box several pixels off are often not its own.
  {
    std::vector<std::vector<const EdgePoint*>> of(frames.size());
    for (const EdgePoint* p : used) of[p->object].push_back(p);
    for (size_t k = 0; k < frames.size(); ++k) {
      if (of[k].empty()) continue;
      const double sigma = frames[k].move_sigma_m, step = 0.25 * sigma;
      const int n = static_cast<int>(std::floor(frames[k].max_move_m / step));
      // Each row of the grid on any core; the first best move in the
      // grid's order is taken, as one core would.
      const int side = 2 * n + 1;
      std::vector<double> costs(static_cast<size_t>(side) * side);
      tbb::parallel_for(-n, n + 1, [&](int i) {
        std::array<double, 6> q = params[k];
        for (int j = -n; j <= n; ++j) {
          q[0] = i * step;
          q[1] = j * step;
          double cost = 0.0;
          for (const EdgePoint* p : of[k]) {
            double r = 0.0;
            EdgeResidual(&projector, &frames[k], p->local, &interpolate,
                         o.max_edge_distance_px,
                         &sigma_px)(cam.data(), q.data(), &r);
            cost += std::log1p(r * r);  // the Cauchy loss
          }
          // The prior on the move, as the fit weighs it.
          costs[static_cast<size_t>(i + n) * side + (j + n)] =
              0.5 * cost + 0.5 * (q[0] * q[0] + q[1] * q[1]) / (sigma * sigma);
        }
      });
      double best = std::numeric_limits<double>::infinity();
      std::array<double, 6> chosen = params[k];
      for (int i = -n; i <= n; ++i) {
        for (int j = -n; j <= n; ++j) {
          const double cost =
              costs[static_cast<size_t>(i + n) * side + (j + n)];
          if (cost < best) {
            best = cost;
            chosen[0] = i * step;
            chosen[1] = j * step;
          }
        }
      }
      params[k] = chosen;
    }
  }

  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_QR;
  solver.max_num_iterations = 60;
  solver.num_threads = 1;
  solver.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  sigma_px = 4.0 * o.edge_sigma_px;
  ceres::Solve(solver, &problem, &summary);
  if (summary.IsSolutionUsable()) {
    sigma_px = o.edge_sigma_px;
    ceres::Solve(solver, &problem, &summary);
  }
  if (!summary.IsSolutionUsable()) {
    out.status = ModelRefineResult::Status::kFailed;
    out.message = "the solver failed: " + summary.message;
    return out;
  }
  // An object whose edges still miss the clip's after the fit is not
  // confirmed by it (edges it does not show, or not its own): it keeps the
  // user's placement, and the rest is fitted again without it moving.
  std::vector<bool> confirmed(frames.size(), false);
  distances(&after);
  bool reset = false;
  for (size_t k = 0; k < frames.size(); ++k) {
    if (count[k] < o.min_points_per_object) continue;
    confirmed[k] = after[k] <= o.max_object_distance_px;
    if (!confirmed[k]) {
      // Its edges no longer pull the camera either.
      for (ceres::ResidualBlockId b : blocks[k]) problem.RemoveResidualBlock(b);
      params[k].fill(0.0);
      problem.SetParameterBlockConstant(params[k].data());
      reset = true;
    }
  }
  if (reset && std::count(confirmed.begin(), confirmed.end(), true) > 0) {
    ceres::Solve(solver, &problem, &summary);
    if (!summary.IsSolutionUsable()) {
      out.status = ModelRefineResult::Status::kFailed;
      out.message = "the solver failed: " + summary.message;
      return out;
    }
  }
  out.distance_after_px = distances(&after);

  const Eigen::Vector3d aa(cam[0], cam[1], cam[2]);
  const double angle = aa.norm();
  const Eigen::Matrix3d turn_in_cam =
      angle > 0 ? Eigen::AngleAxisd(angle, aa / angle).toRotationMatrix()
                : Eigen::Matrix3d::Identity();
  const Eigen::Matrix3d r0 = camera.cam_from_world().linear();
  out.camera.turn_in_world = r0.transpose() * turn_in_cam.transpose() * r0;
  out.camera.turn_deg = angle / kRadPerDeg;
  out.camera.focal_factor = std::exp(cam[3]);
  for (size_t k = 0; k < frames.size(); ++k) {
    ObjectCorrection c = unrefined(k);
    c.refined = confirmed[k];
    c.distance_after_px = after[k];
    if (c.refined) {
      const auto& q = params[k];
      c.move_in_world_m = Eigen::Vector2d(q[0], q[1]);
      c.turn_deg = q[2] / kRadPerDeg;
      c.scale = Eigen::Vector3d(std::exp(q[3]), std::exp(q[4]), std::exp(q[5]));
    }
    if (c.points > 0) out.objects.push_back(c);
  }
  const double drop =
      1.0 - out.distance_after_px / std::max(out.distance_before_px, 1e-300);
  std::ostringstream msg;
  msg.precision(3);
  msg << said() << ", " << out.distance_after_px << " px refined";
  const int kept =
      static_cast<int>(std::count(confirmed.begin(), confirmed.end(), true));
  if (kept == 0) {
    out.status = ModelRefineResult::Status::kUnchanged;
    msg << "; no object's edges are confirmed by the clip's";
    out.camera = CameraCorrection();
  } else if (drop < o.min_distance_drop) {
    out.status = ModelRefineResult::Status::kUnchanged;
    msg << "; not better enough to be used";
  } else {
    out.status = ModelRefineResult::Status::kRefined;
  }
  out.message = msg.str();
  return out;
}

Scene CorrectedScene(const Scene& scene, const ModelRefineResult& result) {
  std::map<int32_t, Eigen::Matrix4d> transform;
  for (const auto& c : result.objects)
    if (c.refined) transform[c.object_id] = c.Transform();
  std::vector<Eigen::Vector3f> vertices(scene.num_vertices());
  for (int64_t v = 0; v < scene.num_vertices(); ++v)
    vertices[v] = scene.vertex(v);
  std::vector<Eigen::Vector3i> triangles(scene.num_triangles());
  std::vector<int32_t> ids(scene.num_triangles());
  // A vertex moves with the first object whose triangle uses it.
  std::vector<uint8_t> moved(vertices.size(), 0);
  for (int64_t t = 0; t < scene.num_triangles(); ++t) {
    triangles[t] = scene.triangle(t);
    ids[t] = scene.object_id_of_triangle(t);
    const auto it = transform.find(ids[t]);
    for (int j = 0; j < 3; ++j) {
      const int v = triangles[t][j];
      if (moved[v]) continue;
      moved[v] = 1;
      if (it == transform.end()) continue;
      const Eigen::Vector4d p(vertices[v].x(), vertices[v].y(), vertices[v].z(),
                              1.0);
      vertices[v] = (it->second * p).head<3>().cast<float>();
    }
  }
  return Scene(vertices, triangles, ids);
}

Camera CorrectedCamera(const Camera& camera, const CameraCorrection& c) {
  Eigen::Matrix3d K = camera.K();
  K(0, 0) *= c.focal_factor;
  K(0, 1) *= c.focal_factor;
  K(1, 1) *= c.focal_factor;
  // The camera turns about its centre: cam' = R0 T^T R0^T cam.
  const Eigen::Isometry3d& old = camera.cam_from_world();
  const Eigen::Vector3d centre = camera.center_in_world();
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = old.linear() * c.turn_in_world.transpose();
  pose.translation() = -pose.linear() * centre;
  Camera out(K, pose, camera.width(), camera.height());
  if (camera.distortion()) {
    PolynomialDistortion d = *camera.distortion();
    d.focal_x_px *= c.focal_factor;
    d.focal_y_px *= c.focal_factor;
    out.SetDistortion(d);
  }
  return out;
}

}  // namespace sunlapse
