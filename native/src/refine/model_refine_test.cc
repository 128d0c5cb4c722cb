#include "sunlapse/refine/model_refine.h"

#include <cmath>
#include <stdexcept>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "sunlapse/common/angles.h"
#include "synthetic.h"

namespace sunlapse {
namespace {

const Eigen::Vector3d kEye(4, -12, 9);

Camera TrueCamera() { return testing::LookAt(kEye, {0, 0, 0}, 640, 480); }

// Frames of the true model under a Sun moving over an afternoon.
std::vector<cv::Mat> Frames(const Scene& scene, const Camera& camera, int n) {
  std::vector<cv::Mat> frames;
  for (int i = 0; i < n; ++i) {
    const double zenith = 35.0 + 30.0 * i / (n - 1),
                 azimuth = 200.0 + 60.0 * i / (n - 1);
    testing::RenderOptions o;
    o.seed = 7 + i;
    o.albedo = [](int id, const Eigen::Vector3f&) {
      return id == 0 ? 0.3 : id == 1 ? 0.6 : 0.45;
    };
    frames.push_back(testing::RenderLambertian(
        scene, camera, SunInWorldFromAngles(zenith, azimuth), o));
  }
  return frames;
}

// Pixels of the ground on the boundary of one frame's shadow.
std::vector<cv::Point> ShadowBoundary(const Scene& scene, const Camera& camera,
                                      const Eigen::Vector3d& toward_sun) {
  cv::Mat shade(camera.height(), camera.width(), CV_8U, cv::Scalar(0));
  std::vector<Eigen::Vector2d> pixels;
  for (int y = 0; y < camera.height(); ++y)
    for (int x = 0; x < camera.width(); ++x) pixels.emplace_back(x, y);
  const Hits hits = scene.IntersectPixels(camera, pixels);
  std::vector<float> origins, dirs;
  std::vector<size_t> which;
  for (size_t i = 0; i < pixels.size(); ++i) {
    if (!hits.hit(i) || hits.object_id[i] != 0) continue;
    const Eigen::Vector3f p = hits.point(i) + 0.01f * Eigen::Vector3f::UnitZ();
    // Not where the shadows meet their casters: there they never move.
    if ((p.head<2>() - Eigen::Vector2f(2.575f, -2.525f)).norm() < 1.0f ||
        (p.x() > -2.5f && p.x() < 1.5f && p.y() > -2.0f && p.y() < 2.2f))
      continue;
    origins.insert(origins.end(), {p.x(), p.y(), p.z()});
    which.push_back(i);
  }
  std::vector<uint8_t> occluded(which.size());
  scene.OccludedToward(static_cast<int64_t>(which.size()), origins.data(),
                       toward_sun.cast<float>(), 0.0f, 1e4f, occluded.data());
  for (size_t j = 0; j < which.size(); ++j)
    if (occluded[j])
      shade.at<uint8_t>(static_cast<int>(pixels[which[j]].y()),
                        static_cast<int>(pixels[which[j]].x())) = 255;
  cv::Mat grown;
  cv::dilate(shade, grown, cv::Mat());
  std::vector<cv::Point> out;
  for (size_t j = 0; j < which.size(); ++j) {
    const int x = static_cast<int>(pixels[which[j]].x()),
              y = static_cast<int>(pixels[which[j]].y());
    // Lit ground next to shade, away from the objects themselves.
    if (!occluded[j] && grown.at<uint8_t>(y, x) && x > 20 && y > 20 &&
        x < camera.width() - 20 && y < camera.height() - 20)
      out.emplace_back(x, y);
  }
  return out;
}

double FractionNearEdges(const cv::Mat& edges,
                         const std::vector<cv::Point>& points) {
  int near = 0;
  for (const auto& p : points) {
    bool any = false;
    for (int dy = -1; dy <= 1 && !any; ++dy)
      for (int dx = -1; dx <= 1 && !any; ++dx)
        any = edges.at<uint8_t>(p.y + dy, p.x + dx) > 0;
    near += any;
  }
  return points.empty() ? 0.0 : static_cast<double>(near) / points.size();
}

TEST(StableEdges, KeepTheModelsOutlinesAndLeaveMovingShadowsOut) {
  const Scene scene = testing::BoxAndPole().Build();
  const Camera camera = TrueCamera();
  const auto frames = Frames(scene, camera, 9);
  const cv::Mat edges = StableEdges(frames);
  ASSERT_EQ(edges.size(), frames[0].size());
  const auto shadow =
      ShadowBoundary(scene, camera, SunInWorldFromAngles(50.0, 230.0));
  ASSERT_GT(shadow.size(), 100u);
  // One frame's edges hold its shadow's boundary: the check can fail.
  const cv::Mat one = StableEdges({frames[4], frames[4]});
  EXPECT_GT(FractionNearEdges(one, shadow), 0.6);
  EXPECT_LT(FractionNearEdges(edges, shadow), 0.25);
  // The box's top corners are on edges.
  int corners = 0;
  for (const Eigen::Vector3d& c :
       {Eigen::Vector3d(-1.5, -1, 1.6), Eigen::Vector3d(0.5, -1, 1.6),
        Eigen::Vector3d(0.5, 1.2, 1.6)}) {
    Eigen::Vector2d px;
    ASSERT_TRUE(camera.WorldToPixel(c, &px));
    corners +=
        FractionNearEdges(
            edges, {cv::Point(static_cast<int>(std::lround(px.x())),
                              static_cast<int>(std::lround(px.y())))}) > 0;
  }
  EXPECT_EQ(corners, 3);
}

TEST(StableEdges, NeedTwoFrames) {
  EXPECT_TRUE(StableEdges({}).empty());
  EXPECT_TRUE(StableEdges({cv::Mat(10, 10, CV_32F, cv::Scalar(0.5))}).empty());
  EXPECT_THROW(StableEdges({cv::Mat(10, 10, CV_8U), cv::Mat(10, 10, CV_8U)}),
               std::invalid_argument);
}

// The true model's objects as a hand-made model puts them.
testing::Mesh Rough(const testing::Mesh& truth) {
  ObjectCorrection box, pole;
  box.pivot_in_world = {-0.5, 0.1, 0};
  box.move_in_world_m = {0.16, -0.11};
  box.turn_deg = 2.0;
  box.scale = {1.07, 0.96, 0.94};
  pole.pivot_in_world = {2.575, -2.525, 0};
  pole.move_in_world_m = {-0.12, 0.1};
  pole.scale = {1.0, 1.0, 1.08};
  testing::Mesh m = truth;
  std::vector<bool> done(m.v.size(), false);
  for (size_t t = 0; t < m.t.size(); ++t) {
    if (m.ids[t] == 0) continue;
    const Eigen::Matrix4d tr = (m.ids[t] == 1 ? box : pole).Transform();
    for (int j = 0; j < 3; ++j) {
      const int v = m.t[t][j];
      if (done[v]) continue;
      done[v] = true;
      m.v[v] = (tr * Eigen::Vector4d(m.v[v].x(), m.v[v].y(), m.v[v].z(), 1))
                   .head<3>()
                   .cast<float>();
    }
  }
  return m;
}

double MaxVertexError(const Scene& a, const testing::Mesh& truth) {
  double worst = 0;
  for (size_t t = 0; t < truth.t.size(); ++t) {
    if (truth.ids[t] == 0) continue;
    for (int j = 0; j < 3; ++j) {
      const int v = truth.t[t][j];
      worst = std::max(worst,
                       static_cast<double>((a.vertex(v) - truth.v[v]).norm()));
    }
  }
  return worst;
}

// The largest distance (px) between where two (model, camera) pairs show
// the objects' corners: what the clip can check of a model.
double MaxImageError(const Scene& a, const Camera& camera_a,
                     const testing::Mesh& truth, const Camera& camera_truth) {
  double worst = 0;
  for (size_t t = 0; t < truth.t.size(); ++t) {
    if (truth.ids[t] == 0) continue;
    for (int j = 0; j < 3; ++j) {
      const int v = truth.t[t][j];
      Eigen::Vector2d pa, pb;
      if (camera_a.WorldToPixel(a.vertex(v).cast<double>(), &pa) &&
          camera_truth.WorldToPixel(truth.v[v].cast<double>(), &pb))
        worst = std::max(worst, (pa - pb).norm());
    }
  }
  return worst;
}

// The renderer samples each pixel at its centre: its edges are a pixel
// rougher than a camera's, so an object's fit is confirmed within 2 px.
ModelRefineOptions Loose() {
  ModelRefineOptions o;
  o.max_object_distance_px = 2.0;
  return o;
}

TEST(RefineModel, PutsAHandMadeModelAndCameraBackWhereTheClipShowsThem) {
  const testing::Mesh truth = testing::BoxAndPole();
  const Scene true_scene = truth.Build();
  const Camera true_camera = TrueCamera();
  const cv::Mat edges = StableEdges(Frames(true_scene, true_camera, 9));
  const Scene rough = Rough(truth).Build();
  CameraCorrection off;
  off.turn_in_world =
      Eigen::AngleAxisd(0.3 * kRadPerDeg,
                        Eigen::Vector3d(1, 2, -0.5).normalized())
          .toRotationMatrix();
  off.focal_factor = 1.02;
  const Camera rough_camera = CorrectedCamera(true_camera, off);
  ASSERT_GT(MaxVertexError(rough, truth), 0.15);
  ASSERT_GT(MaxImageError(rough, rough_camera, truth, true_camera), 8.0);

  const ModelRefineResult r =
      RefineModel(rough, rough_camera, {0}, edges, Loose());
  ASSERT_EQ(r.status, ModelRefineResult::Status::kRefined) << r.message;
  EXPECT_LT(r.distance_after_px, 0.5 * r.distance_before_px);
  ASSERT_EQ(r.objects.size(), 2u);
  for (const auto& o : r.objects) EXPECT_TRUE(o.refined);
  // The clip shows the model through the camera: that is what is put back.
  // (All objects a little larger and the focal a little shorter look
  // alike; the priors split such a difference.)
  const Scene corrected = CorrectedScene(rough, r);
  EXPECT_LT(MaxImageError(corrected, CorrectedCamera(rough_camera, r.camera),
                          truth, true_camera),
            2.5);
  EXPECT_LT(MaxVertexError(corrected, truth), 0.1);
}

TEST(RefineModel, LeavesATrueModelWhereTheClipShowsIt) {
  const testing::Mesh truth = testing::BoxAndPole();
  const Scene scene = truth.Build();
  const Camera camera = TrueCamera();
  const ModelRefineResult r = RefineModel(
      scene, camera, {0}, StableEdges(Frames(scene, camera, 9)), Loose());
  EXPECT_LT(r.distance_before_px, 1.5);
  const Camera refined = r.ok() ? CorrectedCamera(camera, r.camera) : camera;
  EXPECT_LT(MaxImageError(r.ok() ? CorrectedScene(scene, r) : truth.Build(),
                          refined, truth, camera),
            1.0);
  EXPECT_LT(r.camera.turn_deg, 0.5);
}

// A model already within min_distance_before_px of the clip's edges is not
// fitted at all (its corrections would not be used): each object in view is
// accounted for, uncorrected, and the status says so.
TEST(RefineModel, DoesNotFitAModelThatAlreadyFits) {
  const testing::Mesh truth = testing::BoxAndPole();
  const Scene scene = truth.Build();
  const Camera camera = TrueCamera();
  const cv::Mat edges = StableEdges(Frames(scene, camera, 9));
  ModelRefineOptions o = Loose();
  o.min_distance_before_px = 4.0;  // this model is within it
  const ModelRefineResult r = RefineModel(scene, camera, {0}, edges, o);
  ASSERT_EQ(r.status, ModelRefineResult::Status::kUnchanged) << r.message;
  EXPECT_NE(r.message.find("already fits"), std::string::npos) << r.message;
  EXPECT_EQ(r.distance_after_px, r.distance_before_px);
  EXPECT_EQ(r.camera.turn_deg, 0.0);
  ASSERT_EQ(r.objects.size(), 2u);
  for (const auto& c : r.objects) {
    EXPECT_FALSE(c.refined);
    EXPECT_GT(c.points, 0);
    EXPECT_EQ(c.move_in_world_m.norm(), 0.0);
  }
  // Asked to fit it anyway, the fit runs and moves something.
  o.min_distance_before_px = 0.0;
  const ModelRefineResult fitted = RefineModel(scene, camera, {0}, edges, o);
  EXPECT_EQ(fitted.message.find("already fits"), std::string::npos)
      << fitted.message;
  EXPECT_NE(fitted.distance_after_px, fitted.distance_before_px);
}

// The corrections of object `id` (none when it was not in view).
const ObjectCorrection* CorrectionOf(const ModelRefineResult& r, int id) {
  for (const auto& c : r.objects)
    if (c.object_id == id) return &c;
  return nullptr;
}

TEST(RefineModel, MovesASmallObjectByAtMostAFractionOfItsSize) {
  // The footage shows a 0.5 m cube 0.2 m from where the model has it.
  const float size = 0.5f;
  testing::Mesh truth = testing::BoxAndPole();
  truth.Box({-1.0f, -4.0f, 0}, {-1.0f + size, -4.0f + size, size}, 3);
  testing::Mesh modelled = testing::BoxAndPole();
  modelled.Box({-0.8f, -4.0f, 0}, {-0.8f + size, -4.0f + size, size}, 3);
  const Camera camera = TrueCamera();
  const cv::Mat edges = StableEdges(Frames(truth.Build(), camera, 9));
  ModelRefineOptions o = Loose();
  o.max_move_m = o.move_sigma_m = 1.0;  // the metres alone would let it go back
  // One small object off among true ones: the model fits on average (the
  // gate); fitted anyway, to see how far the cube may go.
  o.min_distance_before_px = 0.0;
  ModelRefineOptions wide = o;
  wide.max_move_fraction = wide.move_sigma_fraction = 10.0;
  const ObjectCorrection* free =
      CorrectionOf(RefineModel(modelled.Build(), camera, {0}, edges, wide), 3);
  ASSERT_NE(free, nullptr);
  ASSERT_TRUE(free->refined);
  // Free, it goes back most of the way: beyond what the fraction allows.
  EXPECT_LT(free->move_in_world_m.x(), -o.max_move_fraction * size - 0.02);
  const ObjectCorrection* held =
      CorrectionOf(RefineModel(modelled.Build(), camera, {0}, edges, o), 3);
  ASSERT_NE(held, nullptr);
  EXPECT_LE(std::abs(held->move_in_world_m.x()),
            o.max_move_fraction * size + 1e-9);
  EXPECT_LE(std::abs(held->move_in_world_m.y()),
            o.max_move_fraction * size + 1e-9);
}

TEST(RefineModel, SaysWhenThereIsNothingToFit) {
  const Scene scene = testing::BoxAndPole().Build();
  const Camera camera = TrueCamera();
  EXPECT_EQ(RefineModel(scene, camera, {0}, cv::Mat()).status,
            ModelRefineResult::Status::kNoEdges);
  // The camera looking away from the model: none of its edges in view.
  const Camera away = testing::LookAt(kEye, {20, -40, 9}, 640, 480);
  const cv::Mat blank(480, 640, CV_8U, cv::Scalar(0));
  EXPECT_EQ(RefineModel(scene, away, {0}, blank).status,
            ModelRefineResult::Status::kNoEdges);
  ModelRefineOptions bad;
  bad.max_scale_change = 1.5;
  EXPECT_THROW(bad.Check(), std::invalid_argument);
  EXPECT_THROW(RefineModel(scene, camera, {0}, cv::Mat(10, 10, CV_8U), {}),
               std::invalid_argument);
}

}  // namespace
}  // namespace sunlapse
