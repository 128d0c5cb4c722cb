#include "sunlapse/sky/sky_evidence.h"
#include "sunlapse/common/require.h"

#include "sunlapse/common/angles.h"
#include "sunlapse/common/huge_pages.h"
#include "sunlapse/common/order_statistics.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <tuple>
#include <utility>

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

namespace sunlapse {
namespace {

constexpr double kDeg = M_PI / 180.0;
// Samples a table may hold: the bands index them in 16 bits.
constexpr int64_t kMaxSamples = 65536;

double Seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0)
      .count();
}

// A sample faces a direction when the cosine between its normal and the
// direction exceeds this (grazing light shows no shadow edge).
constexpr float kFacingCos = 0.02f;

}  // namespace

// ---------------------------------------------------------------- SkyGrid

SkyGrid::SkyGrid(int num_directions, double max_zenith_deg) {
  Require(num_directions >= 16, "num_directions must be >= 16");
  Require(max_zenith_deg > 0 && max_zenith_deg <= 90,
          "max_zenith_deg must be in (0, 90]");
  directions_ = FibonacciSky(num_directions, max_zenith_deg);
  max_zenith_deg_ = max_zenith_deg;
  const double zmin = std::cos(max_zenith_deg * kDeg);
  // Solid angle per direction -> the side of a square of that area.
  const double solid = 2.0 * M_PI * (1.0 - zmin) / num_directions;
  spacing_deg_ = std::sqrt(solid) / kDeg;
  // Path steps of up to ~20 deg (a generous per-frame bound plus the
  // grid's slack) are looked up, not scanned.
  cached_radius_deg_ = std::max(3.0 * spacing_deg_, 22.0);
}

const std::vector<std::vector<SkyGrid::Neighbour>>& SkyGrid::Lists() const {
  // Isolated: while it waits for its parallel loop, the first caller must not
  // take up other work of the pool that may ask for the lists again.
  std::call_once(cached_->once, [this] {
    tbb::this_task_arena::isolate([this] {
      std::vector<std::vector<Neighbour>>& cached = cached_->lists;
      const int num_directions = size();
      const double zmin = std::cos(max_zenith_deg_ * kDeg);
      cached.resize(directions_.size());
      const double cos_r = std::cos(cached_radius_deg_ * kDeg);
      // About this many in the cap (fewer by the horizon): reserved, as a
      // vector grown by doubling copies itself onto fresh pages.
      const size_t expected = static_cast<size_t>(
          1.2 * num_directions * (1.0 - cos_r) / (1.0 - zmin) + 8.0);
      // The spiral runs from the zenith down (z falls with the index), and a
      // direction within r of another is within r of it in zenith: each one
      // scans only the indices of that zenith band (a margin keeps it a
      // superset; the dot product decides as before).
      const double r = cached_radius_deg_ * kDeg + 1e-6;
      auto first_below = [&](double z) {  // the first index whose z is below
        return static_cast<int>(
            std::partition_point(
                directions_.begin(), directions_.end(),
                [z](const Eigen::Vector3d& v) { return v.z() >= z; }) -
            directions_.begin());
      };
      tbb::parallel_for(0, size(), [&](int i) {
        cached[i].reserve(expected);
        const double zenith =
            std::acos(std::clamp(directions_[i].z(), -1.0, 1.0));
        const int j0 = first_below(std::cos(std::max(0.0, zenith - r)) + 1e-12);
        const int j1 =
            first_below(std::cos(std::min(M_PI, zenith + r)) - 1e-12);
        for (int j = j0; j < j1; ++j) {
          const double c = directions_[i].dot(directions_[j]);
          if (c >= cos_r) {
            cached[i].push_back(
                {j, static_cast<float>(
                        std::atan2(directions_[i].cross(directions_[j]).norm(),
                                   c) /
                        kDeg)});
          }
        }
        // Nearest first: a search within a smaller radius stops at the first
        // neighbour beyond it.
        std::sort(cached[i].begin(), cached[i].end(),
                  [](const Neighbour& a, const Neighbour& b) {
                    return a.angle_deg < b.angle_deg ||
                           (a.angle_deg == b.angle_deg && a.index < b.index);
                  });
      });
    });
  });
  return cached_->lists;
}

std::vector<int> SkyGrid::Within(int i, double radius_deg) const {
  std::vector<int> out;
  const double cos_r = std::cos(std::min(radius_deg, 180.0) * kDeg);
  if (radius_deg <= cached_radius_deg_) {
    for (const Neighbour& nb : Cached(i)) {
      if (nb.angle_deg > radius_deg) break;
      out.push_back(nb.index);
    }
    return out;
  }
  for (int j = 0; j < size(); ++j) {
    if (directions_[i].dot(directions_[j]) >= cos_r) out.push_back(j);
  }
  return out;
}

int SkyGrid::Nearest(const Eigen::Vector3d& d) const {
  const Eigen::Vector3d u = d.normalized();
  int best = 0;
  double best_dot = -2.0;
  for (int j = 0; j < size(); ++j) {
    const double c = directions_[j].dot(u);
    if (c > best_dot) best_dot = c, best = j;
  }
  return best;
}

// ---------------------------------------------------------- options check

void SkyEvidenceOptions::Check() const {
  Require(num_directions >= 16 && num_directions <= 20000,
          "num_directions must be in [16, 20000]");
  Require(max_zenith_deg > 10 && max_zenith_deg <= 90,
          "max_zenith_deg must be in (10, 90]");
  Require(max_samples >= 50 && max_samples <= 65535,
          "max_samples must be in [50, 65535]");
  Require(ignore_top_rows >= 0 && ignore_bottom_rows >= 0,
          "ignore_top_rows/ignore_bottom_rows must be >= 0");
  Require(normal_bin_deg > 0 && normal_bin_deg < 90,
          "normal_bin_deg must be in (0, 90)");
  Require(min_side_samples >= 1, "min_side_samples must be >= 1");
  Require(band_steps >= 0 && band_steps <= 20, "band_steps must be in [0, 20]");
  Require(max_ratio > 1, "max_ratio must be > 1");
  Require(reference_quantile > 0 && reference_quantile < 1,
          "reference_quantile must be in (0, 1)");
  Require(rival_exclusion_deg >= 0, "rival_exclusion_deg must be >= 0");
  Require(min_significance >= 0, "min_significance must be >= 0");
  Require(samples_per_observation >= 1, "samples_per_observation must be >= 1");
}

// ------------------------------------------------------------ SkyEvidence

struct SkyEvidence::Impl {
  const Scene& scene;
  const Camera& camera;
  SkyEvidenceOptions o;
  SkyGrid grid;
  // Samples: pixel and planar group.
  std::vector<Eigen::Vector2f> pixels;
  std::vector<int> group;
  int num_groups = 0;
  // Per direction the band around its predicted shadow boundaries: samples
  // within band_steps grid steps of a neighbour (same group) of the other
  // state; s when lit, ~s when in shade. Only the band is scored: a shadow
  // is an edge, and a smooth gradient has no contrast across one.
  // Stored per direction as segments, one per planar group with enough
  // samples on both sides to be scored (the others never score): the lit
  // samples band[lit, shade), then the shaded ones band[shade, end). The
  // counts never change, so a frame only sums its ratios over each side.
  // Sample numbers are 16-bit: the band is read whole on every frame (6 MB
  // at 32 bits for 1.5M entries, more than the caches hold).
  struct Segment {
    int32_t group;
    int64_t lit, shade, end;
  };
  std::vector<uint16_t> band;
  // Samples in some direction's band (where shadows can show), and how many.
  std::vector<uint8_t> in_band;
  int band_samples = 0;
  std::vector<Segment> segments;
  std::vector<int64_t> segments_begin;  // size D + 1
  // Right-hand grid neighbour of each sample in the same group (-1: none),
  // for the noise of neighbouring differences.
  std::vector<int32_t> right;
  std::vector<float> reference;     // empty until SetReference
  std::vector<uint8_t> scores;      // frames x directions, cost x 10, clipped
  std::vector<float> best;          // per frame, the best explained share
  std::vector<float> significance;  // per frame, FrameEvidence::significance
  int frames = 0;
  double build_seconds = 0.0;

  Impl(const Scene& s, const Camera& c, const SkyEvidenceOptions& opt)
      : scene(s),
        camera(c),
        o(opt),
        grid(opt.num_directions, opt.max_zenith_deg) {}

  int S() const { return static_cast<int>(pixels.size()); }

  void Build() {
    const auto t0 = std::chrono::steady_clock::now();
    const int W = camera.width(), H = camera.height();
    const int y0 = o.ignore_top_rows, y1 = H - o.ignore_bottom_rows;
    Require(y1 > y0, "ignore_top_rows + ignore_bottom_rows leave no rows");
    // A first pass on a fine grid finds how much of the image the model
    // covers; the stride then gives about max_samples samples on it.
    auto cast = [&](int stride, std::vector<double>* px, Hits* hits) {
      px->clear();
      for (int y = y0 + stride / 2; y < y1; y += stride) {
        for (int x = stride / 2; x < W; x += stride)
          px->insert(px->end(), {double(x), double(y)});
      }
      *hits = Hits(static_cast<int64_t>(px->size() / 2));
      scene.IntersectPixels(camera, hits->object_id.size(), px->data(),
                            hits->buffers());
    };
    std::vector<double> px;
    Hits hits;
    const int probe = std::max(1, std::min(W, y1 - y0) / 64);
    cast(probe, &px, &hits);
    auto count = [&] {  // samples that hit the model
      int64_t c = 0;
      for (size_t i = 0; i < hits.object_id.size(); ++i) c += hits.hit(i);
      return c;
    };
    const int64_t covered = count();
    Require(covered > 0,
            "the camera sees no model surface: check the camera and the model");
    const double area = double(covered) * probe * probe;
    int stride = std::max(
        1, static_cast<int>(std::floor(std::sqrt(area / o.max_samples))));
    cast(stride, &px, &hits);
    // The bands hold sample indices in 16 bits; the stride's rounding may
    // give up to four times max_samples.
    while (count() > kMaxSamples) cast(++stride, &px, &hits);

    const float lift = scene.surface_offset();
    std::vector<Eigen::Vector3f> origin, normal;
    std::map<std::tuple<int, int, int, int>, int> groups;
    const int gw = (W - stride / 2 + stride - 1) / stride;
    const int gh = (y1 - (y0 + stride / 2) + stride - 1) / stride;
    std::vector<int32_t> cell(static_cast<size_t>(gw) * gh, -1);
    std::vector<std::pair<int, int>> cells;
    for (size_t i = 0; i < hits.object_id.size(); ++i) {
      if (!hits.hit(i)) continue;
      const Eigen::Vector3f n = hits.normal(i);
      const Eigen::Vector3f p = hits.point(i);
      if (!n.allFinite() || !p.allFinite()) continue;
      // Group key: object and the normal's direction binned in zenith/azimuth.
      const auto [zbin, abin] = NormalBin(n, o.normal_bin_deg);
      const auto key = std::make_tuple(int(hits.object_id[i]), zbin, abin, 0);
      auto it = groups.find(key);
      if (it == groups.end())
        it = groups.emplace(key, static_cast<int>(groups.size())).first;
      const int cx = (static_cast<int>(px[2 * i]) - stride / 2) / stride;
      const int cy =
          (static_cast<int>(px[2 * i + 1]) - y0 - stride / 2) / stride;
      if (cx >= 0 && cx < gw && cy >= 0 && cy < gh) {
        cell[static_cast<size_t>(cy) * gw + cx] =
            static_cast<int32_t>(pixels.size());
      }
      cells.emplace_back(cx, cy);
      pixels.emplace_back(float(px[2 * i]), float(px[2 * i + 1]));
      group.push_back(it->second);
      origin.push_back(p + lift * n);
      normal.push_back(n);
    }
    num_groups = static_cast<int>(groups.size());
    const int s_count = S();
    Require(s_count > 0,
            "the camera sees no model surface: check the camera and the model");
    std::vector<float> flat(3 * s_count), nx(s_count), ny(s_count), nz(s_count);
    for (int s = 0; s < s_count; ++s) {
      for (int k = 0; k < 3; ++k) flat[3 * s + k] = origin[s][k];
      nx[s] = normal[s].x(), ny[s] = normal[s].y(), nz[s] = normal[s].z();
    }
    auto at = [&](int cx, int cy) -> int32_t {
      if (cx < 0 || cy < 0 || cx >= gw || cy >= gh) return -1;
      return cell[static_cast<size_t>(cy) * gw + cx];
    };
    right.resize(s_count);
    for (int i = 0; i < s_count; ++i) {
      const int32_t j = at(cells[i].first + 1, cells[i].second);
      right[i] = j >= 0 && group[j] == group[i] ? j : -1;
    }
    // The band pass below runs for every direction (3000 times) over every
    // sample. It works on the samples' grid of cells, one byte each, eight
    // cells at a time as one word, with no bounds or group checks: a column
    // of margin on either side, two rows above and below (a neighbour of a
    // sample's cell is inside; the last word runs into the margin), and
    // same[k][c] = 1 where cell c and its k-th neighbour (right, lower,
    // left, upper, then the diagonals) are samples of one group. Done per
    // sample with neighbour lists, this was 40% of the table's CPU.
    const int pw = gw + 2;
    const size_t c0 = 2 * static_cast<size_t>(pw),
                 c1 = c0 + static_cast<size_t>(pw) * gh,
                 padded = c1 + 2 * static_cast<size_t>(pw) + 8;
    const std::array<int, 8> dx = {1, 0, -1, 0, 1, -1, 1, -1},
                             dy = {0, 1, 0, -1, 1, 1, -1, -1};
    std::array<std::ptrdiff_t, 8> offset;
    for (int k = 0; k < 8; ++k) offset[k] = dy[k] * pw + dx[k];
    std::vector<int32_t> sample_cell(s_count), cell_sample(padded, -1);
    std::array<std::vector<uint8_t>, 8> same;
    for (auto& m : same) m.assign(padded, 0);
    // The words that hold a sample, the only ones worked (a model seen in a
    // corner of the image leaves most of the grid empty).
    std::vector<size_t> words;
    for (int i = 0; i < s_count; ++i) {
      const auto [cx, cy] = cells[i];
      Require(at(cx, cy) == i, "internal: a surface sample off its grid cell");
      const size_t c = c0 + static_cast<size_t>(cy) * pw + cx + 1;
      sample_cell[i] = static_cast<int32_t>(c);
      cell_sample[c] = i;
      const size_t word_start = c0 + (c - c0) / 8 * 8;
      if (words.empty() || words.back() != word_start)
        words.push_back(word_start);  // the cells' order is the samples'
      for (int k = 0; k < 8; ++k) {
        const int32_t j = at(cx + dx[k], cy + dy[k]);
        same[k][c] = j >= 0 && group[j] == group[i];
      }
    }
    // A sample faces a direction when their cosine exceeds kFacingCos. A
    // flat one (its normal this close to the zenith) faces every direction
    // of the grid, with a margin for the float sum's rounding: not tested.
    std::vector<int32_t> always, maybe, always_cell, maybe_cell;
    const double cos_lowest = std::cos(o.max_zenith_deg * kDeg);
    for (int i = 0; i < s_count; ++i) {
      const double tilt = std::acos(std::clamp(double(nz[i]), -1.0, 1.0));
      const bool every =
          cos_lowest > 0 &&
          std::cos(tilt + o.max_zenith_deg * kDeg) > kFacingCos + 0.01;
      (every ? always : maybe).push_back(i);
      (every ? always_cell : maybe_cell).push_back(sample_cell[i]);
    }
    // From a flat sample, the sky is open above the highest elevation of
    // any object's bounding box: a ray above it (with a margin for the
    // rays' float arithmetic) is lit without being cast. Nearly half the
    // rays of the 1080p benchmark's scene.
    std::vector<float> open_above(always.size());
    for (size_t k = 0; k < always.size(); ++k)
      open_above[k] = scene.OpenSkyAbove(origin[always[k]]);
    // Per direction, its band as it goes into the one array below: per
    // group with enough samples on both sides, its lit samples then its
    // shaded ones, each in sample order. Made where the rays are cast (on
    // every core), each of its exact size: growing vectors' fresh pages cost
    // more than the bands' own work.
    struct DirectionBand {
      std::vector<uint16_t> samples;
      std::vector<Segment> segments;  // offsets into samples
    };
    std::vector<DirectionBand> bands(grid.size());
    const float far = 10.f * scene.bounds().diagonal().norm() + 1.f;
    const int steps = o.band_steps;
    // Each thread's buffers, reused from one direction to the next.
    struct Scratch {
      std::vector<int32_t> facing;
      std::vector<int> queue;
      std::vector<uint8_t> occluded, lit, reach, grown;
      std::vector<int64_t> place;
    };
    tbb::enumerable_thread_specific<Scratch> scratch;
    tbb::parallel_for(0, grid.size(), [&](int d) {
      Scratch& w = scratch.local();
      const Eigen::Vector3f dir = grid.direction(d).cast<float>();
      // Rays are cast from the flat samples below their open sky, and from
      // the other samples that face the direction (a wall faces away from
      // half the sky); both listed branch-free.
      const float elevation = std::asin(dir.z());
      w.facing.resize(s_count);
      int32_t* cast_list = w.facing.data();
      size_t cast = 0;
      for (size_t k = 0; k < always.size(); ++k) {
        cast_list[cast] = always[k];
        cast += open_above[k] >= elevation;
      }
      for (const int32_t i : maybe) {
        cast_list[cast] = i;
        cast +=
            nx[i] * dir.x() + ny[i] * dir.y() + nz[i] * dir.z() > kFacingCos;
      }
      w.occluded.resize(cast);
      uint8_t* occluded = w.occluded.data();
      scene.OccludedTowardSubset(static_cast<int64_t>(cast), cast_list,
                                 flat.data(), dir, 0.f, far, occluded);
      // Lit or not per cell (cells of no sample are never read: no mask
      // links them). A sample is on a boundary when a neighbour of its group
      // differs; the band is what lies within `steps` grid steps of one,
      // through neighbours of its group (8-connected).
      std::vector<uint8_t>&lit = w.lit, &reach = w.reach, &grown = w.grown;
      lit.resize(padded);
      reach.resize(padded, 0);  // only words of samples are written
      grown.resize(padded, 0);
      uint8_t* lit_cell = lit.data();
      const int32_t* cell_of = sample_cell.data();
      for (const int32_t c : always_cell) lit_cell[c] = 1;  // open sky
      for (const int32_t c : maybe_cell) lit_cell[c] = 0;
      for (size_t k = 0; k < cast; ++k)
        lit_cell[cell_of[cast_list[k]]] = !occluded[k];
      // Cells 8 at a time as one word: the bytes are 0 or 1, and xor, and
      // and or act on each byte alone.
      auto word = [](const uint8_t* p) {
        uint64_t v;
        std::memcpy(&v, p, sizeof v);
        return v;
      };
      {
        const uint8_t* l = lit.data();
        const uint8_t *m0 = same[0].data(), *m1 = same[1].data(),
                      *m2 = same[2].data(), *m3 = same[3].data();
        uint8_t* out = reach.data();
        for (const size_t c : words) {
          const uint64_t v = word(l + c);
          const uint64_t b = ((v ^ word(l + c + 1)) & word(m0 + c)) |
                             ((v ^ word(l + c + pw)) & word(m1 + c)) |
                             ((v ^ word(l + c - 1)) & word(m2 + c)) |
                             ((v ^ word(l + c - pw)) & word(m3 + c));
          std::memcpy(out + c, &b, sizeof b);
        }
      }
      for (int step = 0; step < steps; ++step) {
        const uint8_t* in = reach.data();
        uint8_t* out = grown.data();
        for (const size_t c : words) {
          uint64_t v = word(in + c);
          for (int k = 0; k < 8; ++k)
            v |= word(in + c + offset[k]) & word(same[k].data() + c);
          std::memcpy(out + c, &v, sizeof v);
        }
        std::swap(reach, grown);
      }
      // The band's samples, in sample order (the cells' order): whole words
      // of cells outside the band are passed over.
      std::vector<int>& queue = w.queue;
      queue.resize(s_count);
      size_t in_the_band = 0;
      for (const size_t c : words) {
        if (word(reach.data() + c) == 0) continue;
        for (size_t j = c; j < c + 8; ++j) {
          if (reach[j]) queue[in_the_band++] = cell_sample[j];
        }
      }
      queue.resize(in_the_band);
      // Counted per group and side, then placed (a counting sort keeps the
      // queue's order within each side).
      std::vector<int64_t>& place = w.place;
      place.assign(2 * static_cast<size_t>(num_groups), 0);
      for (int i : queue) ++place[2 * group[i] + (lit[sample_cell[i]] ? 0 : 1)];
      DirectionBand& out = bands[d];
      int64_t total = 0;
      for (int g = 0; g < num_groups; ++g) {
        const int64_t nl = place[2 * g], ns = place[2 * g + 1];
        if (nl < o.min_side_samples || ns < o.min_side_samples) {
          place[2 * g] = place[2 * g + 1] = -1;
          continue;
        }
        out.segments.push_back(Segment{g, total, total + nl, total + nl + ns});
        place[2 * g] = total;
        place[2 * g + 1] = total + nl;
        total += nl + ns;
      }
      out.samples.resize(static_cast<size_t>(total));
      for (int i : queue) {
        int64_t& k = place[2 * group[i] + (lit[sample_cell[i]] ? 0 : 1)];
        if (k >= 0) out.samples[k++] = static_cast<uint16_t>(i);
      }
    });
    // One array for all directions' bands.
    size_t band_total = 0, segment_total = 0;
    for (const DirectionBand& b : bands) {
      band_total += b.samples.size();
      segment_total += b.segments.size();
    }
    ReserveHuge(&band, band_total);
    segments.reserve(segment_total);
    segments_begin.assign(grid.size() + 1, 0);
    for (int d = 0; d < grid.size(); ++d) {
      const int64_t offset = static_cast<int64_t>(band.size());
      band.insert(band.end(), bands[d].samples.begin(), bands[d].samples.end());
      for (Segment seg : bands[d].segments) {
        seg.lit += offset, seg.shade += offset, seg.end += offset;
        segments.push_back(seg);
      }
      segments_begin[d + 1] = static_cast<int64_t>(segments.size());
      std::vector<uint16_t>().swap(bands[d].samples);
    }
    in_band.assign(S(), 0);
    for (uint16_t i : band) in_band[i] = 1;
    band_samples = static_cast<int>(
        std::count(in_band.begin(), in_band.end(), uint8_t{1}));
    build_seconds = Seconds(t0);
  }

  // The frame's pixel at each sample.
  void Sample(const cv::Mat& f, std::vector<float>* out) const {
    out->resize(S());
    for (int s = 0; s < S(); ++s) {
      const int x = std::clamp(static_cast<int>(std::lround(pixels[s].x())), 0,
                               f.cols - 1);
      const int y = std::clamp(static_cast<int>(std::lround(pixels[s].y())), 0,
                               f.rows - 1);
      (*out)[s] = f.at<float>(y, x);
    }
  }
};

SkyEvidence::SkyEvidence(const Scene& scene, const Camera& camera,
                         const SkyEvidenceOptions& options)
    : impl_(std::make_unique<Impl>(scene, camera, (options.Check(), options))) {
  impl_->Build();
}

SkyEvidence::~SkyEvidence() = default;

const SkyGrid& SkyEvidence::grid() const { return impl_->grid; }
int SkyEvidence::num_samples() const { return impl_->S(); }
std::vector<Eigen::Vector2f> SkyEvidence::sample_pixels() const {
  return impl_->pixels;
}
double SkyEvidence::build_seconds() const { return impl_->build_seconds; }
int64_t SkyEvidence::band_entries() const {
  return static_cast<int64_t>(impl_->band.size());
}
bool SkyEvidence::has_reference() const { return !impl_->reference.empty(); }
int SkyEvidence::num_frames() const { return impl_->frames; }
void SkyEvidence::ReserveFrames(int more) {
  Impl& m = *impl_;
  const size_t frames = static_cast<size_t>(m.frames) + std::max(0, more);
  m.scores.reserve(frames * m.grid.size());
  m.best.reserve(frames);
  m.significance.reserve(frames);
}
const std::vector<uint8_t>& SkyEvidence::scores() const {
  return impl_->scores;
}

std::vector<float> SkyEvidence::Cost(int k) const {
  Require(k >= 0 && k < impl_->frames, "frame index out of range");
  const int D = impl_->grid.size();
  std::vector<float> out(D);
  for (int d = 0; d < D; ++d)
    out[d] = impl_->scores[static_cast<size_t>(k) * D + d] / 10.f;
  return out;
}

double SkyEvidence::Significance(int k) const {
  Require(k >= 0 && k < impl_->frames, "frame index out of range");
  return impl_->significance[k];
}

double SkyEvidence::BestExplained(int k) const {
  Require(k >= 0 && k < impl_->frames, "frame index out of range");
  return impl_->best[k];
}

namespace {

void CheckFrame(const cv::Mat& f, const Camera& camera) {
  Require(f.type() == CV_32FC1 && f.cols == camera.width() &&
              f.rows == camera.height(),
          "frame: expected float32 gray of the camera's size (" +
              std::to_string(camera.width()) + "x" +
              std::to_string(camera.height()) + ")");
}

// The samples a frame sees (not NaN).
std::vector<float> Seen(const std::vector<float>& v) {
  std::vector<float> out;
  out.reserve(v.size());
  for (float x : v)
    if (!std::isnan(x)) out.push_back(x);
  return out;
}

// A frame that sees less than this share of the samples (a moving camera's,
// motion/view_warp.h) has the model out of view.
constexpr double kMinSeenShare = 0.1;
// A sample's reference level needs this many reference frames seeing it.
constexpr size_t kMinReferenceFrames = 6;

}  // namespace

int SkyEvidence::SetReference(const std::vector<cv::Mat>& frames) {
  Impl& m = *impl_;
  const int S = m.S();
  std::vector<std::vector<float>> per_sample(S);
  int used = 0;
  std::vector<float> v;
  for (const cv::Mat& f : frames) {
    if (f.empty()) continue;
    CheckFrame(f, m.camera);
    m.Sample(f, &v);
    // A frame's exposure is taken out before the quantile: the reference is
    // a level relative to the frame's median. NaN: a sample a moving
    // camera's frame does not see (motion/view_warp.h).
    std::vector<float> sorted = Seen(v);
    if (sorted.empty()) continue;
    const float med = MedianInPlace(&sorted);
    if (!(med > 1e-4f)) continue;  // black frame
    for (int s = 0; s < S; ++s)
      if (!std::isnan(v[s])) per_sample[s].push_back(v[s] / med);
    ++used;
  }
  if (used == 0) return 0;
  m.reference.assign(S, 0.f);
  // A moving camera's sample seen by only a few of the reference frames
  // (near the edge of the view at one end of the move) would take its level
  // from them, shadowed or not: it is left out. Not more is asked: a camera
  // that pans away from the casters and back sees them on under half of
  // the clip. A fixed camera's samples are all seen by every frame.
  const size_t enough =
      std::min(static_cast<size_t>(used), kMinReferenceFrames);
  for (int s = 0; s < S; ++s) {
    auto& x = per_sample[s];
    if (x.empty() || x.size() < enough) {
      m.reference[s] = std::numeric_limits<float>::quiet_NaN();
      continue;
    }
    m.reference[s] =
        std::max(1e-4f, QuantileInPlace(&x, m.o.reference_quantile));
  }
  return used;
}

namespace {

// values[i] summed over the indices [first, last), in four running sums: one
// sum is a chain of dependent additions, four keep the adder busy (a third
// less time for the whole frame's evidence).
float SumAt(const float* values, const uint16_t* first, const uint16_t* last) {
  float s0 = 0.f, s1 = 0.f, s2 = 0.f, s3 = 0.f;
  for (; last - first >= 4; first += 4) {
    s0 += values[first[0]];
    s1 += values[first[1]];
    s2 += values[first[2]];
    s3 += values[first[3]];
  }
  for (; first < last; ++first) s0 += values[*first];
  return (s0 + s1) + (s2 + s3);
}

// A sample's ratio and whether it is seen, side by side: one gather reads
// both (a second SumAt over the weights cost a moving frame's band pass
// half again).
struct SeenRatio {
  float ratio, seen;
};

// (sum of ratios, samples seen) over the indices [first, last).
std::pair<float, float> SumSeenAt(const SeenRatio* values,
                                  const uint16_t* first, const uint16_t* last) {
  float r0 = 0.f, r1 = 0.f, n0 = 0.f, n1 = 0.f;
  for (; last - first >= 2; first += 2) {
    const SeenRatio& a = values[first[0]];
    const SeenRatio& b = values[first[1]];
    r0 += a.ratio, n0 += a.seen;
    r1 += b.ratio, n1 += b.seen;
  }
  for (; first < last; ++first)
    r0 += values[*first].ratio, n0 += values[*first].seen;
  return {r0 + r1, n0 + n1};
}

}  // namespace

FrameEvidence SkyEvidence::AddFrame(const cv::Mat& frame,
                                    std::vector<float>* explained_out) {
  Impl& m = *impl_;
  const auto t0 = std::chrono::steady_clock::now();
  const int S = m.S(), D = m.grid.size(), G = m.num_groups;
  FrameEvidence out;
  std::vector<float> explained(D, 0.f);
  std::vector<float> cost(D, 0.f);  // stays 0 (no preference) without evidence
  auto keep = [&]() {
    m.scores.resize(m.scores.size() + D);
    uint8_t* row = &m.scores[static_cast<size_t>(m.frames) * D];
    for (int d = 0; d < D; ++d) {
      row[d] = static_cast<uint8_t>(
          std::lround(std::clamp(cost[d], 0.f, 25.5f) * 10.f));
    }
    m.best.push_back(out.best_explained);
    m.significance.push_back(out.significance);
    ++m.frames;
    if (explained_out) *explained_out = explained;
    out.seconds = Seconds(t0);
    return out;
  };
  if (frame.empty()) {
    out.status = FrameEvidence::Status::kNoFrame;
    out.message = "frame not decodable";
    return keep();
  }
  CheckFrame(frame, m.camera);
  Require(!m.reference.empty(), "AddFrame() before SetReference()");
  std::vector<float> v;
  m.Sample(frame, &v);
  // A sample is unseen where a moving camera's frame does not see it, or no
  // reference frame did (NaN, motion/view_warp.h).
  int unseen = 0;
  for (int s = 0; s < S; ++s) {
    if (std::isnan(m.reference[s]))
      v[s] = std::numeric_limits<float>::quiet_NaN();
    unseen += std::isnan(v[s]);
  }
  if (unseen > 0 && m.band_samples > 0) {
    int seen_band = 0;
    for (int s = 0; s < S; ++s) seen_band += m.in_band[s] && !std::isnan(v[s]);
    out.shadow_view = static_cast<double>(seen_band) / m.band_samples;
  }
  if (S - unseen < std::max(1.0, kMinSeenShare * S)) {
    out.status = FrameEvidence::Status::kUnusable;
    out.message = "the model is out of view";
    return keep();
  }
  std::vector<float> sorted = Seen(v);
  const int seen = static_cast<int>(sorted.size());
  const float med = MedianInPlace(&sorted);
  int saturated = 0;
  for (float x : v) saturated += x >= 0.98f;
  if (!(med > 2e-3f) || saturated > 0.9 * seen) {
    out.status = FrameEvidence::Status::kUnusable;
    out.message = med > 2e-3f ? "overexposed" : "black (nothing visible)";
    return keep();
  }
  // Ratio to the sample's reference level, exposure taken out.
  std::vector<double> r(S);
  for (int s = 0; s < S; ++s) {
    r[s] = std::clamp(double(v[s]) / med / m.reference[s], 0.0, m.o.max_ratio);
  }
  if (unseen > 0) {
    // An unseen sample takes its group's mean: it adds no contrast across a
    // boundary and no variance to explain, so only the seen ones count.
    std::vector<double> n(G, 0), sum(G, 0);
    double n_all = 0, sum_all = 0;
    for (int s = 0; s < S; ++s) {
      if (std::isnan(v[s])) continue;
      n[m.group[s]] += 1, sum[m.group[s]] += r[s];
      n_all += 1, sum_all += r[s];
    }
    for (int s = 0; s < S; ++s) {
      if (!std::isnan(v[s])) continue;
      const int g = m.group[s];
      r[s] = n[g] > 0 ? sum[g] / n[g] : sum_all / n_all;
    }
  }
  out.exposure = med;
  // Per group: totals, for the variance every direction tries to explain.
  std::vector<double> n_g(G, 0), sum_g(G, 0), sq_g(G, 0);
  for (int s = 0; s < S; ++s) {
    const int g = m.group[s];
    n_g[g] += 1, sum_g[g] += r[s], sq_g[g] += r[s] * r[s];
  }
  double total = 0;
  std::vector<double> sst(G);
  for (int g = 0; g < G; ++g) {
    sst[g] = n_g[g] > 0 ? std::max(0.0, sq_g[g] - sum_g[g] * sum_g[g] / n_g[g])
                        : 0.0;
    total += sst[g];
  }
  if (!(total > 1e-9)) {
    out.status = FrameEvidence::Status::kUnusable;
    out.message = "uniform where the model is seen";
    return keep();
  }
  // Noise: the robust spread of differences between grid neighbours (a
  // smooth gradient cancels in them; edges are few, the median ignores them).
  std::vector<double> diffs;
  diffs.reserve(S);
  for (int i = 0; i < S; ++i) {
    const int j = m.right[i];
    if (j >= 0 && !std::isnan(v[i]) && !std::isnan(v[j]))
      diffs.push_back(std::abs(r[i] - r[j]));
  }
  double noise = 1e-6;
  if (!diffs.empty()) {
    const double sigma = 1.4826 * MedianInPlace(&diffs) / std::sqrt(2.0);
    noise = std::max(1e-6, sigma * sigma);
  }
  std::vector<float> rf(r.begin(), r.end());
  // With unseen samples, each side's mean is over the seen ones alone: a
  // group mean put in their place is not neutral (a side of unseen lit
  // ground against seen shade still showed a contrast, and moving members'
  // frames chose long shadows 8-21 deg off). Only frames that miss some
  // of the band take this way.
  std::vector<SeenRatio> seen_ratio;
  if (out.shadow_view < 1.0) {
    seen_ratio.resize(S);
    for (int s = 0; s < S; ++s) {
      const bool seen = !std::isnan(v[s]);
      seen_ratio[s] = {seen ? rf[s] : 0.f, seen ? 1.f : 0.f};
    }
  }
  const int min_side = m.o.min_side_samples;
  std::vector<double> gain(D, 0.0);
  tbb::parallel_for(
      tbb::blocked_range<int>(0, D, 64),
      [&](const tbb::blocked_range<int>& range) {
        const uint16_t* idx = m.band.data();
        const float* ratio = rf.data();
        const SeenRatio* weighted =
            seen_ratio.empty() ? nullptr : seen_ratio.data();
        for (int d = range.begin(); d < range.end(); ++d) {
          // Between-sides sum of squares of the band, per group, only where the
          // predicted shade is darker than the predicted light.
          double g_sum = 0;
          for (int64_t k = m.segments_begin[d]; k < m.segments_begin[d + 1];
               ++k) {
            const Impl::Segment& seg = m.segments[k];
            double lit_sum, shade_sum, n_lit, n_shade;
            if (weighted == nullptr) {
              lit_sum = SumAt(ratio, idx + seg.lit, idx + seg.shade);
              shade_sum = SumAt(ratio, idx + seg.shade, idx + seg.end);
              n_lit = static_cast<double>(seg.shade - seg.lit);
              n_shade = static_cast<double>(seg.end - seg.shade);
            } else {
              std::tie(lit_sum, n_lit) =
                  SumSeenAt(weighted, idx + seg.lit, idx + seg.shade);
              std::tie(shade_sum, n_shade) =
                  SumSeenAt(weighted, idx + seg.shade, idx + seg.end);
              if (n_lit < min_side || n_shade < min_side) continue;
            }
            const double mean_lit = lit_sum / n_lit,
                         mean_shade = shade_sum / n_shade;
            if (mean_shade >= mean_lit) continue;
            const double diff = mean_lit - mean_shade;
            g_sum += n_lit * n_shade / (n_lit + n_shade) * diff * diff;
          }
          gain[d] = g_sum;
          explained[d] = static_cast<float>(g_sum / total);
        }
      });
  const int best = static_cast<int>(std::max_element(gain.begin(), gain.end()) -
                                    gain.begin());
  out.best_direction = best;
  out.best_explained = explained[best];
  // Costs in units of log-likelihood: the band contrast a direction lacks
  // against the best one, over the noise, divided by the samples per
  // independent observation (neighbours share texture, blur, the model's
  // misfit).
  const double scale = 1.0 / noise / (2.0 * m.o.samples_per_observation);
  for (int d = 0; d < D; ++d)
    cost[d] = static_cast<float>((gain[best] - gain[d]) * scale);
  const double cos_x = std::cos(m.o.rival_exclusion_deg * kDeg);
  double rival = 0.0;
  for (int d = 0; d < D; ++d) {
    if (m.grid.direction(d).dot(m.grid.direction(best)) < cos_x)
      rival = std::max(rival, gain[d]);
  }
  out.margin = (gain[best] - rival) * scale;
  out.significance = gain[best] * scale;
  out.status = out.significance >= m.o.min_significance
                   ? FrameEvidence::Status::kOk
                   : FrameEvidence::Status::kNoShadows;
  if (out.status == FrameEvidence::Status::kNoShadows) {
    out.message = "no direction's shadows match the frame (overcast?)";
    std::fill(cost.begin(), cost.end(), 0.f);
  }
  return keep();
}

}  // namespace sunlapse
