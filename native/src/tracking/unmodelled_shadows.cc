#include "sunlapse/tracking/unmodelled_shadows.h"
#include "sunlapse/common/order_statistics.h"
#include "sunlapse/common/require.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include <opencv2/imgproc.hpp>

namespace sunlapse {
namespace {

cv::Mat1f Luminance(const cv::Mat& m) {
  if (m.channels() == 1) return m;
  cv::Mat1f out;
  cv::transform(m, out, cv::Matx13f(0.0722f, 0.7152f, 0.2126f));  // BGR
  return out;
}

// Median of m's values where mask is set (0 if none).
float MaskedMedian(const cv::Mat1f& m, const cv::Mat1b& mask) {
  std::vector<float> v;
  v.reserve(static_cast<size_t>(cv::countNonZero(mask)));
  for (int y = 0; y < m.rows; ++y) {
    const float* row = m[y];
    const uint8_t* k = mask[y];
    for (int x = 0; x < m.cols; ++x) {
      if (k[x]) v.push_back(row[x]);
    }
  }
  if (v.empty()) return 0.f;
  return MedianInPlace(&v);
}

// The mean of `values` over the `lit` pixels in a win x win window around
// each pixel; `fallback` where the window holds too few of them.
cv::Mat1f LocalLevel(const cv::Mat1f& values, const cv::Mat1b& lit, int win,
                     float fallback) {
  cv::Mat1f w, vw;
  lit.convertTo(w, CV_32F, 1.0 / 255);
  cv::multiply(values, w, vw);
  cv::boxFilter(w, w, -1, {win, win}, {-1, -1}, false, cv::BORDER_REPLICATE);
  cv::boxFilter(vw, vw, -1, {win, win}, {-1, -1}, false, cv::BORDER_REPLICATE);
  cv::Mat1f level(values.size(), fallback);
  const float min_weight = 0.05f * win * win;
  for (int y = 0; y < level.rows; ++y) {
    for (int x = 0; x < level.cols; ++x) {
      if (w(y, x) > min_weight) level(y, x) = vw(y, x) / w(y, x);
    }
  }
  return level;
}

}  // namespace

void UnmodelledShadowOptions::Check() const {
  Require(dark_ratio > 0 && dark_ratio < 1, "dark_ratio must be in (0, 1)");
  Require(max_chroma_ratio >= 1, "max_chroma_ratio must be >= 1");
  Require(level_window > 0 && level_window <= 1,
          "level_window must be in (0, 1]");
  Require(model_margin_px >= 0 && model_margin_px <= 50,
          "model_margin_px must be in [0, 50]");
  Require(min_area_fraction >= 0 && min_area_fraction < 1,
          "min_area_fraction must be in [0, 1)");
  Require(min_edge_contrast >= 0, "min_edge_contrast must be >= 0");
  Require(registration_px >= 0 && registration_px <= 20,
          "registration_px must be in [0, 20]");
}

UnmodelledShadows DetectUnmodelledShadows(const cv::Mat& frame,
                                          const cv::Mat& background,
                                          const cv::Mat& ground,
                                          const cv::Mat& model_shadow,
                                          const UnmodelledShadowOptions& o) {
  o.Check();
  Require(
      !frame.empty() && (frame.type() == CV_32FC1 || frame.type() == CV_32FC3),
      "frame: expected float32 gray or colour");
  Require(background.empty() || (background.size() == frame.size() &&
                                 background.type() == frame.type()),
          "background: expected the frame's size and type (or none)");
  Require(ground.size() == frame.size() && ground.type() == CV_8UC1,
          "ground: expected a uint8 mask of the frame's size");
  Require(model_shadow.size() == frame.size() && model_shadow.type() == CV_8UC1,
          "model_shadow: expected a uint8 mask of the frame's size");
  const int W = frame.cols, H = frame.rows;
  UnmodelledShadows out;
  out.mask = cv::Mat1b(H, W, uint8_t(0));

  const cv::Mat& bg = background;
  // Each channel relative to the background (or as it is without one).
  std::vector<cv::Mat1f> rc(frame.channels());
  {
    std::vector<cv::Mat> fc, bc;
    cv::split(frame, fc);
    if (!bg.empty()) cv::split(bg, bc);
    for (int c = 0; c < frame.channels(); ++c) {
      if (bc.empty()) {
        rc[c] = fc[c];
      } else {
        cv::divide(fc[c], cv::max(bc[c], 1e-6f), rc[c]);
      }
    }
  }
  const cv::Mat1f f = Luminance(frame);
  cv::Mat1f ratio;
  const cv::Mat1b on_ground = ground != 0;
  cv::Mat1b valid = on_ground.clone();
  if (bg.empty()) {
    ratio = f;
  } else {
    const cv::Mat1f b = Luminance(bg);
    const float b_median = MaskedMedian(b, on_ground);
    if (b_median <= 0) return out;
    valid &= b > 0.05f * b_median;
    cv::divide(f, cv::max(b, 1e-6f), ratio);
  }

  // The model's shadow, widened: explained already; and a ring around it.
  cv::Mat1b model = model_shadow != 0, near_model;
  if (o.model_margin_px > 0) {
    const int k = 2 * o.model_margin_px + 1;
    cv::dilate(model, model,
               cv::getStructuringElement(cv::MORPH_ELLIPSE, {k, k}));
  }
  cv::dilate(model, near_model,
             cv::getStructuringElement(cv::MORPH_ELLIPSE, {5, 5}));

  // Lit level around each pixel: the mean over the lit-looking ground in a
  // wide window (pixels darker than dark_ratio x the global median and the
  // model's shadow are left out, so shadows do not pull the level down).
  // Without a background the ground's albedo must be even at that scale.
  const cv::Mat1b free_ground = valid & ~model;
  const float global =
      MaskedMedian(ratio, cv::countNonZero(free_ground) ? free_ground : valid);
  if (global <= 0) return out;
  const cv::Mat1b lit = free_ground & (ratio > o.dark_ratio * global);
  const int win = std::max(3, static_cast<int>(o.level_window * W) | 1);
  const cv::Mat1f level = LocalLevel(ratio, lit, win, global);

  // Dark: below dark_ratio x the level even against the darkest background
  // within registration_px (paint that the camera's shake moved a pixel or
  // two is dark in the background there too).
  cv::Mat1f ratio_test = ratio;
  if (!bg.empty() && o.registration_px > 0) {
    const int k = 2 * o.registration_px + 1;
    cv::Mat1f b_min;
    cv::erode(Luminance(bg), b_min,
              cv::getStructuringElement(cv::MORPH_RECT, {k, k}));
    cv::divide(f, cv::max(b_min, 1e-6f), ratio_test);
  }
  cv::Mat1b dark = valid & ~model & (ratio_test < o.dark_ratio * level);
  // Shade dims every channel alike (relative to the lit ground around); a
  // dark or differently coloured thing on the ground does not.
  if (frame.channels() == 3) {
    cv::Mat1f q[3];
    for (int c = 0; c < 3; ++c) {
      const float g = std::max(1e-6f, MaskedMedian(rc[c], lit));
      cv::divide(rc[c], cv::max(LocalLevel(rc[c], lit, win, g), 1e-6f), q[c]);
    }
    const cv::Mat1f hi = cv::max(cv::max(q[0], q[1]), q[2]);
    const cv::Mat1f lo = cv::max(cv::min(cv::min(q[0], q[1]), q[2]), 1e-6f);
    dark &= hi <= o.max_chroma_ratio * lo;
  }
  cv::morphologyEx(dark, dark, cv::MORPH_OPEN,
                   cv::getStructuringElement(cv::MORPH_CROSS, {3, 3}));

  // Energy e = |dI/dx| + |dI/dy| of the frame, and its typical level on the
  // ground (texture and noise).
  cv::Mat1f dx, dy, energy;
  cv::Sobel(f, dx, CV_32F, 1, 0, 1, 0.5);
  cv::Sobel(f, dy, CV_32F, 0, 1, 1, 0.5);
  energy = cv::abs(dx) + cv::abs(dy);
  cv::Mat1f energy_max;  // an edge straddles the rim: look one pixel around
  cv::dilate(energy, energy_max, cv::Mat());
  const float e_median = std::max(1e-6f, MaskedMedian(energy, valid));

  cv::Mat1i labels;
  cv::Mat stats, centroids;
  const int n = cv::connectedComponentsWithStats(dark, labels, stats, centroids,
                                                 8, CV_32S);
  const int min_area = std::max(
      12, static_cast<int>(o.min_area_fraction * cv::countNonZero(valid)));
  std::vector<std::vector<float>> rim(n);
  std::vector<double> ratio_sum(n, 0.0);
  std::vector<uint8_t> touches(n, 0);
  for (int y = 0; y < H; ++y) {
    for (int x = 0; x < W; ++x) {
      const int l = labels(y, x);
      if (l == 0 || stats.at<int>(l, cv::CC_STAT_AREA) < min_area) continue;
      ratio_sum[l] += ratio(y, x) / std::max(1e-6f, level(y, x));
      touches[l] |= near_model(y, x) != 0;
      const bool inner = x > 0 && y > 0 && x < W - 1 && y < H - 1 &&
                         labels(y, x - 1) == l && labels(y, x + 1) == l &&
                         labels(y - 1, x) == l && labels(y + 1, x) == l;
      if (!inner) rim[l].push_back(energy_max(y, x));
    }
  }
  for (int l = 1; l < n; ++l) {
    const int area = stats.at<int>(l, cv::CC_STAT_AREA);
    if (area < min_area || rim[l].empty()) continue;
    // The upper quartile of the rim: part of a rim may run along the model's
    // shadow or the ground's border, where no edge of its own is seen.
    std::vector<float>& r = rim[l];
    const double contrast = QuantileInPlace(&r, 0.75) / e_median;
    if (contrast < o.min_edge_contrast) continue;
    UnmodelledShadow s;
    s.area_px = area;
    s.box = cv::Rect(stats.at<int>(l, cv::CC_STAT_LEFT),
                     stats.at<int>(l, cv::CC_STAT_TOP),
                     stats.at<int>(l, cv::CC_STAT_WIDTH),
                     stats.at<int>(l, cv::CC_STAT_HEIGHT));
    s.centroid_px = {centroids.at<double>(l, 0), centroids.at<double>(l, 1)};
    s.darkening = ratio_sum[l] / area;
    s.edge_contrast = contrast;
    s.touches_model = touches[l] != 0;
    out.regions.push_back(s);
    out.mask.setTo(255, labels == l);
  }
  std::sort(out.regions.begin(), out.regions.end(),
            [](const UnmodelledShadow& a, const UnmodelledShadow& b) {
              return a.area_px > b.area_px;
            });
  return out;
}

}  // namespace sunlapse
