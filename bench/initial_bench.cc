// Initial-Sun benchmark: time of EstimateInitialSun on a 1920x1080 frame
// (ray casting + fit), both methods. Prints figures; never gates anything.
//   build/bench/bench_initial
#include <chrono>
#include <cmath>
#include <cstdio>

#include "sunlapse/initial/initial_sun.h"
#include "synthetic.h"

using namespace sunlapse;

int main() {
  // Ground, a box, three poles and a wall, seen at 1920x1080.
  const Scene scene = testing::BenchScene().Build();
  const Camera cam = testing::BenchCamera();
  const Eigen::Vector3d sun = SunInWorldFromAngles(45, 210);
  testing::RenderOptions ro;
  const double albedo[] = {0.35, 0.8, 0.15, 0.15, 0.6};
  ro.albedo = [&](int id, const Eigen::Vector3f&) { return albedo[id]; };
  const cv::Mat img = testing::RenderLambertian(scene, cam, sun, ro);

  for (auto method : {InitialSunMethod::kDefault, InitialSunMethod::kThesis}) {
    InitialSunOptions o;
    o.method = method;
    double best = 1e9;
    InitialSunResult r;
    for (int rep = 0; rep < 3; ++rep) {
      r = EstimateInitialSun(scene, cam, img, o);
      best = std::min(best, r.seconds);
    }
    const double err = AngleBetweenDeg(r.sun_in_world, sun);
    std::printf(
        "initial_sun[%s]: 1920x1080 in %.3f s (%d pixels used), error %.2f "
        "deg\n",
        method == InitialSunMethod::kDefault ? "default" : "thesis", best,
        r.num_pixels, err);
  }
  return 0;
}
