#include "sunlapse/scene/scene.h"

#include "synthetic.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

namespace sunlapse {
namespace {

// Adds an axis-aligned box [lo, hi] as object `id`.
void AddBox(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi, int32_t id,
            std::vector<Eigen::Vector3f>* v, std::vector<Eigen::Vector3i>* t,
            std::vector<int32_t>* ids) {
  const int b = static_cast<int>(v->size());
  for (int i = 0; i < 8; ++i) {
    v->emplace_back((i & 1) ? hi.x() : lo.x(), (i & 2) ? hi.y() : lo.y(),
                    (i & 4) ? hi.z() : lo.z());
  }
  const int quads[6][4] = {{0, 1, 3, 2}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    t->emplace_back(b + q[0], b + q[1], b + q[2]);
    t->emplace_back(b + q[0], b + q[2], b + q[3]);
    ids->insert(ids->end(), 2, id);
  }
}

// Ground plane z = 0 over [-10, 10]^2 (object 0) and a 2 x 2 x 2 box standing
// on it at the origin (object 1).
Scene BoxOnPlane() {
  std::vector<Eigen::Vector3f> v = {
      {-10, -10, 0}, {10, -10, 0}, {10, 10, 0}, {-10, 10, 0}};
  std::vector<Eigen::Vector3i> t = {{0, 1, 2}, {0, 2, 3}};
  std::vector<int32_t> ids = {0, 0};
  AddBox({-1, -1, 0}, {1, 1, 2}, 1, &v, &t, &ids);
  return Scene(v, t, ids);
}

TEST(Scene, ReportsCountsAndBounds) {
  const Scene scene = BoxOnPlane();
  EXPECT_EQ(scene.num_triangles(), 14);
  EXPECT_EQ(scene.num_vertices(), 12);
  EXPECT_FLOAT_EQ(scene.bounds().min().x(), -10);
  EXPECT_FLOAT_EQ(scene.bounds().max().z(), 2);
}

TEST(Scene, FirstHitsGivePointNormalAndObject) {
  const Scene scene = BoxOnPlane();
  // Down onto the box top, down onto the ground, up from below the ground,
  // and one ray that misses everything.
  const float origins[] = {0.5f, 0.2f, 10, 5, 5, 10, 5, 5, -3, 0, 0, 10};
  const float dirs[] = {0, 0, -2, 0, 0, -1, 0, 0, 1, 0, 0, 1};
  Hits hits(4);
  scene.Intersect(4, origins, dirs, 0.f, INFINITY, hits.buffers());
  ASSERT_TRUE(hits.hit(0));
  EXPECT_EQ(hits.object_id[0], 1);
  EXPECT_NEAR((hits.point(0) - Eigen::Vector3f(0.5f, 0.2f, 2)).norm(), 0, 1e-5);
  EXPECT_NEAR((hits.normal(0) - Eigen::Vector3f::UnitZ()).norm(), 0, 1e-6);
  EXPECT_NEAR(hits.distance[0], 8.0, 1e-5);  // along the unit direction
  EXPECT_EQ(hits.object_id[1], 0);
  EXPECT_NEAR(hits.point(1).z(), 0, 1e-6);
  EXPECT_NEAR((hits.normal(2) + Eigen::Vector3f::UnitZ()).norm(), 0, 1e-6)
      << "normal must face the ray origin";
  EXPECT_FALSE(hits.hit(3));
  EXPECT_EQ(hits.triangle_id[3], -1);
  EXPECT_TRUE(std::isinf(hits.distance[3]));
}

TEST(Scene, CameraPixelsHitWhatTheyProjectFrom) {
  const Scene scene = BoxOnPlane();
  BlenderCameraParams p;
  p.width = 320;
  p.height = 240;
  // Camera 12 m south, 8 m up, looking at the origin.
  const Eigen::Vector3d eye(0, -12, 8);
  const Eigen::Vector3d back = eye.normalized();
  const Eigen::Vector3d right =
      Eigen::Vector3d::UnitZ().cross(back).normalized();
  p.world_from_camera_local.block<3, 1>(0, 0) = right;
  p.world_from_camera_local.block<3, 1>(0, 1) = back.cross(right);
  p.world_from_camera_local.block<3, 1>(0, 2) = back;
  p.world_from_camera_local.block<3, 1>(0, 3) = eye;
  const Camera cam = Camera::FromBlender(p);
  const Eigen::Vector3d top(0.3, -0.4, 2.0), ground(4, 3, 0);
  Eigen::Vector2d px_top, px_ground;
  ASSERT_TRUE(cam.WorldToPixel(top, &px_top));
  ASSERT_TRUE(cam.WorldToPixel(ground, &px_ground));
  const Hits hits = scene.IntersectPixels(cam, {px_top, px_ground});
  EXPECT_EQ(hits.object_id[0], 1);
  EXPECT_NEAR((hits.point(0).cast<double>() - top).norm(), 0, 1e-4);
  EXPECT_EQ(hits.object_id[1], 0);
  EXPECT_NEAR((hits.point(1).cast<double>() - ground).norm(), 0, 1e-4);
}

// Pixels go through the BVH 16 at a time: every pixel of a batch whose
// size is no multiple of 16 (the box, the ground, the sky beyond it and a
// NaN pixel among them) hits what its own ray from the camera hits.
TEST(Scene, CameraPixelsInPacketsHitWhatSingleRaysHit) {
  const Scene scene = BoxOnPlane();
  const Camera cam = testing::LookAt({0, -12, 8}, {0, 0, 0}, 320, 240, 50.0);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<Eigen::Vector2d> px;
  for (int i = 0; i < 37; ++i) px.emplace_back(320 * u(rng), 240 * u(rng));
  px[5] = Eigen::Vector2d(NAN, 3);
  const Hits packed = scene.IntersectPixels(cam, px);
  const Eigen::Vector3f o = cam.center_in_world().cast<float>();
  int boxes = 0, grounds = 0, misses = 0;
  for (size_t i = 0; i < px.size(); ++i) {
    if (i == 5) {
      EXPECT_FALSE(packed.hit(i));
      continue;
    }
    const Eigen::Vector3f d = cam.PixelToRayInWorld(px[i]).cast<float>();
    Hits one(1);
    scene.Intersect(1, o.data(), d.data(), 0.f, INFINITY, one.buffers());
    ASSERT_EQ(packed.object_id[i], one.object_id[0]) << "pixel " << i;
    if (!one.hit(0)) {
      ++misses;
      EXPECT_TRUE(std::isinf(packed.distance[i]));
      continue;
    }
    ++(one.object_id[0] == 1 ? boxes : grounds);
    EXPECT_EQ(packed.triangle_id[i], one.triangle_id[0]);
    EXPECT_NEAR((packed.point(i) - one.point(0)).norm(), 0, 1e-4);
    EXPECT_NEAR((packed.normal(i) - one.normal(0)).norm(), 0, 1e-5);
    EXPECT_NEAR(packed.distance[i], one.distance[0], 1e-4);
  }
  EXPECT_GT(boxes, 0);
  EXPECT_GT(grounds, 0);
  EXPECT_GT(misses, 0);
}

// A pole's shadow on a wide ground ends where geometry puts it: rays
// leaving the ground start surface_offset() above it, and that must not
// shorten the shadow (2e-4 of this model's diagonal, 4.5 cm, lit the last
// 4.5 cm of it and biased every Sun found from shadows 0.45 deg low).
TEST(Scene, APolesShadowOnAWideGroundEndsWhereGeometryPutsIt) {
  const Scene scene = testing::PoleOnGround(80.f, 2.5f).Build();
  EXPECT_GT(scene.surface_offset(), 1e-4f);  // above float32's error here
  // The Sun 45 deg up in the west: the tip falls at x = 0.1 + 2.5.
  const Eigen::Vector3f to_sun = Eigen::Vector3f(-1, 0, 1).normalized();
  const float lift = scene.surface_offset();
  const float origins[] = {2.57f, 0, lift, 2.63f, 0, lift};
  uint8_t occluded[2];
  scene.OccludedToward(2, origins, to_sun, 0.f, INFINITY, occluded);
  EXPECT_EQ(occluded[0], 1) << "3 cm inside the tip";
  EXPECT_EQ(occluded[1], 0) << "3 cm beyond it";
}

TEST(Scene, OcclusionTowardTheSunSeesTheBoxShadow) {
  const Scene scene = BoxOnPlane();
  // Ground points east and west of the box, Sun low in the west (from -X).
  const Eigen::Vector3f to_sun = Eigen::Vector3f(-1, 0, 0.5).normalized();
  const float origins[] = {3, 0, 0, -3, 0, 0, 3, 5, 0};
  float dirs[9];
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < 3; ++k) dirs[3 * i + k] = to_sun[k];
  }
  uint8_t occluded[3];
  scene.Occluded(3, origins, dirs, 1e-3f, INFINITY, occluded);
  EXPECT_EQ(occluded[0], 1);  // east of the box: in its shadow
  EXPECT_EQ(occluded[1], 0);  // west of the box: lit
  EXPECT_EQ(occluded[2], 0);  // beside the shadow: lit
  uint8_t toward[3];
  scene.OccludedToward(3, origins, to_sun * 3.f, 1e-3f, INFINITY, toward);
  EXPECT_EQ(std::vector<uint8_t>(toward, toward + 3),
            std::vector<uint8_t>(occluded, occluded + 3));
  // A short ray stops before the box.
  scene.Occluded(1, origins, dirs, 1e-3f, 0.5f, occluded);
  EXPECT_EQ(occluded[0], 0);
}

TEST(Scene, OccludedTowardAgreesWithSingleRaysOnManyRays) {
  const Scene scene = BoxOnPlane();
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-4, 4);
  const int n = 5003;  // not a multiple of the packet size
  std::vector<float> origins(3 * n), dirs(3 * n);
  const Eigen::Vector3f d = Eigen::Vector3f(0.4f, -0.3f, 0.6f).normalized();
  for (int i = 0; i < n; ++i) {
    origins[3 * i] = u(rng);
    origins[3 * i + 1] = u(rng);
    origins[3 * i + 2] = 0.01f;
    for (int k = 0; k < 3; ++k) dirs[3 * i + k] = d[k];
  }
  std::vector<uint8_t> a(n), b(n);
  scene.Occluded(n, origins.data(), dirs.data(), 0.f, INFINITY, a.data());
  scene.OccludedToward(n, origins.data(), d, 0.f, INFINITY, b.data());
  int shadowed = 0;
  for (int i = 0; i < n; ++i) {
    ASSERT_EQ(a[i], b[i]) << "ray " << i;
    shadowed += a[i];
  }
  EXPECT_GT(shadowed, 100);
}

TEST(Scene, OccludedTowardASubsetIsTheSameRaysFromItsOrigins) {
  const Scene scene = BoxOnPlane();
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-4, 4);
  const int n = 3001;
  std::vector<float> origins(3 * n);
  for (int i = 0; i < n; ++i) {
    origins[3 * i] = u(rng);
    origins[3 * i + 1] = u(rng);
    origins[3 * i + 2] = 0.01f;
  }
  // Every third origin, backwards, and one twice: not a multiple of the
  // packet size, and not in order.
  std::vector<int32_t> which;
  for (int i = n - 1; i >= 0; i -= 3) which.push_back(i);
  which.push_back(which.front());
  std::vector<float> copied;
  for (int32_t i : which) {
    copied.insert(copied.end(), origins.begin() + 3 * i,
                  origins.begin() + 3 * i + 3);
  }
  const Eigen::Vector3f d = Eigen::Vector3f(-0.5f, 0.2f, 0.7f).normalized();
  const int64_t m = static_cast<int64_t>(which.size());
  std::vector<uint8_t> a(m), b(m);
  scene.OccludedToward(m, copied.data(), d, 0.f, INFINITY, a.data());
  scene.OccludedTowardSubset(m, which.data(), origins.data(), d, 0.f, INFINITY,
                             b.data());
  EXPECT_EQ(a, b);
  EXPECT_GT(std::count(a.begin(), a.end(), 1), 30);
  EXPECT_GT(std::count(a.begin(), a.end(), 0), 30);
}

// From points on the ground, every ray steeper than OpenSkyAbove is free,
// even just above it and toward the nearest caster; under an overhang
// nothing is. With few objects (their own boxes) and with many (the model's
// box: no bound below its top, but none wrong).
TEST(Scene, NoRaySteeperThanTheOpenSkyIsOccluded) {
  for (const int poles : {0, 30, 300}) {
    std::vector<Eigen::Vector3f> v = {
        {-20, -20, 0}, {20, -20, 0}, {20, 20, 0}, {-20, 20, 0}};
    std::vector<Eigen::Vector3i> t = {{0, 1, 2}, {0, 2, 3}};
    std::vector<int32_t> ids = {0, 0};
    AddBox({-1, -1, 0}, {1, 1, 6}, 1, &v, &t, &ids);    // a tower
    AddBox({4, -2, 3}, {8, 2, 3.2f}, 2, &v, &t, &ids);  // a floating roof
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(-18, 18), h(0.5f, 4);
    for (int k = 0; k < poles; ++k) {
      const float x = u(rng), y = u(rng);
      AddBox({x, y, 0}, {x + 0.1f, y + 0.1f, h(rng)}, 3 + k, &v, &t, &ids);
    }
    const Scene scene(v, t, ids);
    const float kZenith = static_cast<float>(M_PI / 2);
    std::uniform_real_distribution<float> azimuth(0, 2 * M_PI), unit(0, 1);
    int bounded = 0, rays = 0, hits_below = 0;
    for (int i = 0; i < 400; ++i) {
      const Eigen::Vector3f p(u(rng), u(rng), 0.01f);
      const float open = scene.OpenSkyAbove(p);
      ASSERT_TRUE(open >= -kZenith && open <= kZenith) << open;
      bounded += open < kZenith;
      std::vector<float> origins, dirs;
      for (int k = 0; k < 64; ++k) {
        // Half just above the bound, half anywhere above it; and as many
        // below it, where something may stand.
        const float above = k % 2 ? 1e-3f : unit(rng) * (kZenith - open);
        for (const float e : {open + above, open - 0.02f - above}) {
          if (e > kZenith || e < 0) continue;
          const float a = azimuth(rng);
          dirs.insert(dirs.end(), {std::cos(e) * std::cos(a),
                                   std::cos(e) * std::sin(a), std::sin(e)});
          origins.insert(origins.end(), {p.x(), p.y(), p.z()});
        }
      }
      const int64_t n = static_cast<int64_t>(dirs.size() / 3);
      std::vector<uint8_t> occluded(n);
      scene.Occluded(n, origins.data(), dirs.data(), 0.f, INFINITY,
                     occluded.data());
      for (int64_t k = 0; k < n; ++k) {
        const bool steeper = std::asin(dirs[3 * k + 2]) > open;
        if (steeper) {
          ++rays;
          EXPECT_EQ(occluded[k], 0) << "from " << p.transpose();
        } else {
          hits_below += occluded[k];
        }
      }
    }
    if (poles > 256) {
      EXPECT_EQ(bounded, 0);
      continue;
    }
    // The bound is not vacuous: most points see open sky above some
    // elevation, and below it rays do meet the model.
    EXPECT_GT(bounded, 300) << poles;
    EXPECT_GT(rays, 10000) << poles;
    EXPECT_GT(hits_below, 100) << poles;
  }
  // Under the roof, the bound is the zenith.
  std::vector<Eigen::Vector3f> v;
  std::vector<Eigen::Vector3i> t;
  std::vector<int32_t> ids;
  AddBox({4, -2, 3}, {8, 2, 3.2f}, 0, &v, &t, &ids);
  const Scene roof(v, t, ids);
  EXPECT_FLOAT_EQ(roof.OpenSkyAbove({6, 0, 0}), static_cast<float>(M_PI / 2));
  EXPECT_LT(roof.OpenSkyAbove({6, 0, 4}), -1.f);  // above it: all of the sky
}

TEST(Scene, NonFiniteRaysAreMissesNotCrashes) {
  const Scene scene = BoxOnPlane();
  const float nan = NAN;
  const float origins[] = {nan, 0, 10, 0, 0, 10, 0, 0, 10};
  const float dirs[] = {0, 0, -1, 0, 0, 0, 0, nan, -1};
  Hits hits(3);
  scene.Intersect(3, origins, dirs, 0.f, INFINITY, hits.buffers());
  for (int i = 0; i < 3; ++i) EXPECT_FALSE(hits.hit(i));
  uint8_t occluded[3] = {9, 9, 9};
  scene.Occluded(3, origins, dirs, 0.f, INFINITY, occluded);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(occluded[i], 0);
}

TEST(Scene, RejectsBadMeshes) {
  const std::vector<Eigen::Vector3f> v = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  EXPECT_THROW(Scene(v, {}, {}), std::invalid_argument);
  EXPECT_THROW(Scene(v, {{0, 1, 3}}, {0}), std::invalid_argument);
  EXPECT_THROW(Scene(v, {{0, 1, -1}}, {0}), std::invalid_argument);
  EXPECT_THROW(Scene(v, {{0, 1, 2}}, {-2}), std::invalid_argument);
  EXPECT_THROW(Scene(v, {{0, 1, 2}}, {0, 0}), std::invalid_argument);
  EXPECT_THROW(Scene({{0, 0, NAN}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}}, {0}),
               std::invalid_argument);
  try {
    Scene(v, {{0, 1, 7}}, {0});
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("triangles"), std::string::npos);
  }
}

}  // namespace
}  // namespace sunlapse
