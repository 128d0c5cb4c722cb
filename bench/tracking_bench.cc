// Tracking benchmark: cost of ShadowTracker::Track per 1920x1080 frame
// (decoding excluded: frames are rendered beforehand), and the memory the
// tracker keeps. Prints figures; never gates anything.
//   build/bench/bench_tracking
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include "sunlapse/tracking/shadow_tracker.h"
#include "synthetic.h"

using namespace sunlapse;

static long RssKb() {
  std::ifstream f("/proc/self/status");
  std::string k;
  long v = 0;
  while (f >> k) {
    if (k == "VmRSS:") {
      f >> v;
      break;
    }
  }
  return v;
}

int main() {
  const Scene scene = testing::BenchScene().Build();
  const Camera cam = testing::BenchCamera();
  auto sun = [](int f) {
    const double z = (55 - 0.3 * f) * M_PI / 180, a = (120 + 0.5 * f) * M_PI / 180;
    return Eigen::Vector3d(std::sin(z) * std::sin(a), std::sin(z) * std::cos(a), std::cos(z));
  };
  testing::RenderOptions ro;
  ro.albedo = [](int id, const Eigen::Vector3f& p) {
    return id == 0 ? 0.3 + 0.05 * std::sin(3 * p.x()) * std::cos(2 * p.y()) : 0.5;
  };
  const int n = 40;
  std::vector<cv::Mat> frames;
  for (int f = 0; f < n; ++f) {
    ro.seed = f + 1;
    frames.push_back(testing::RenderLambertian(scene, cam, sun(f), ro));
  }
  ShadowTrackerOptions o;
  o.ground_object_ids = {0};
  ShadowTracker tracker(scene, cam, o);
  const TrackedFrame first = tracker.Initialize(frames[0], sun(0));
  const long rss0 = RssKb();
  double total = 0, worst_ms = 0, worst_err = 0, sum_err = 0;
  int band = 0;
  double rays = 0, evals = 0;
  for (int f = 1; f < n; ++f) {
    const TrackedFrame r = tracker.Track(frames[f]);
    total += r.seconds;
    worst_ms = std::max(worst_ms, 1000 * r.seconds);
    const double err = testing::AngleDeg(r.sun_in_world, sun(f));
    worst_err = std::max(worst_err, err);
    sum_err += err;
    band = r.band_pixels;
    rays += r.rays;
    evals += r.evaluations;
  }
  std::printf("tracking_init: %.3f s (ground map and albedo, once per clip)\n", first.seconds);
  std::printf("tracking: 1920x1080, %.2f ms/frame mean, %.2f ms worst, %d band pixels, "
              "error %.3f deg mean, %.3f max\n",
              1000 * total / (n - 1), worst_ms, band, sum_err / (n - 1), worst_err);
  std::printf("tracking_cost: %.0f shadow rays, %.1f candidate Suns scored per frame\n",
              rays / (n - 1), evals / (n - 1));
  std::printf("tracking_memory: %ld kB resident after init, %+ld kB over %d frames\n", rss0,
              RssKb() - rss0, n - 1);
  return 0;
}
