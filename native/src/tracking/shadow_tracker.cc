#include "sunlapse/tracking/shadow_tracker.h"
#include "sunlapse/common/require.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <stdexcept>
#include <tuple>

#include <opencv2/imgproc.hpp>

#include "casters.h"
#include "sunlapse/common/angles.h"
#include "sunlapse/common/huge_pages.h"
#include "sunlapse/common/order_statistics.h"
#include "sunlapse/common/robust_fit.h"

namespace sunlapse {
namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr float kInf = std::numeric_limits<float>::infinity();
// Frames tracked from the recorded edge casters before the boundaries are
// searched afresh around the last ones.
constexpr int kRefreshFrames = 16;
// Step factor between the search's levels: the parabolas place the minimum
// well inside a step, so the steps may shrink faster than halving.
constexpr double kShrink = 0.4;
// How far (in first search steps) a frame's search may walk from the
// predicted Sun before the frame counts as lost.
constexpr double kMaxWalkSteps = 10;
// A moving camera's frame that sees less than this share of the ground (or
// of the band) it is asked about is out of view for the tracker.
constexpr double kMinSeenShare = 0.25;
// A step of the Sun's elevation the band's pixels notice: this many noise
// variances more of squared residual (TrackedFrame::elevation_pinned_deg).
constexpr double kPinChi2 = 25.0;
// Neighbouring pixels whose normals differ by more than about 10 deg lie on
// different faces.
constexpr float kSamePlaneCos = 0.985f;
// The walls' Sun is taken only when at least this share of their band lies
// off the ground (ShadowTrackerOptions::surfaces_pin_deg).
constexpr double kMinOffGroundShare = 0.2;

}  // namespace

void ShadowTrackerOptions::Check() const {
  Require(!ground_object_ids.empty(),
          "ground_object_ids: name at least one ground object");
  Require(surfaces_pin_deg >= 0, "surfaces_pin_deg must be >= 0");
  Require(band_radius_px >= 1 && band_radius_px <= 50,
          "band_radius_px must be in [1, 50]");
  Require(max_band_pixels >= 100, "max_band_pixels must be >= 100");
  Require(search_step_deg > 0 && tolerance_deg > 0 &&
              tolerance_deg <= search_step_deg,
          "need 0 < tolerance_deg <= search_step_deg");
  Require(loss_scale > 0, "loss_scale must be > 0");
  Require(min_contrast >= 0, "min_contrast must be >= 0");
  Require(subsamples >= 0 && subsamples <= 4,
          "subsamples must be in [0, 4] (0: by the frame's width)");
  Require(ignore_top_rows >= 0 && ignore_bottom_rows >= 0,
          "ignore_top_rows/ignore_bottom_rows must be >= 0");
}

struct ShadowTracker::Impl {
  const Scene& scene;
  const Camera& camera;
  ShadowTrackerOptions o;
  int W = 0, H = 0;

  // The ground as the camera sees it, one entry per ground pixel.
  cv::Mat1i ground_index;  // H x W, -1 elsewhere
  // Everything a ground pixel needs in one cache line: the band's pixels
  // are scattered over the frame, and separate arrays cost a miss each.
  // Kept small: the map is made on the tracker's first frame, and at 1080p
  // its half a million pixels' first writes cost more than their rays.
  struct GroundPixel {
    Eigen::Vector3f origin =
        Eigen::Vector3f::Zero();  // lifted along the normal
    Eigen::Vector3f normal = Eigen::Vector3f::UnitZ();
    float albedo = 1.f;  // relative, median 1
    cv::Point px;
  };
  std::vector<GroundPixel> ground;
  // With all_surfaces: each pixel's face (object and normal, binned), whose
  // light is fitted on its own (a wall sees less sky than the ground, and
  // the Sun at another angle).
  std::vector<int> face;
  std::vector<uint8_t> face_on_ground;
  int num_faces = 1;
  // Without all_surfaces and with surfaces_pin_deg > 0: the same tracker on
  // every surface, for the frames whose height the ground leaves open.
  std::unique_ptr<ShadowTracker> surfaces;
  bool surfaces_started = false;
  std::vector<internal::Caster> casters;

  bool mapped = false;  // ground and casters made (once)

  // Tracking state.
  bool initialized = false;
  Eigen::Vector3d sun, sun_before;  // last two accepted Suns
  bool have_velocity = false;
  int lost = 0;
  double last_correction_deg = 0.5;  // |found - predicted| on the last frame
  std::vector<int> band;             // ground indices near shadow boundaries
  std::vector<int> boundary;         // ground indices on a lit/shadow boundary
  // Where the shadow edge comes from: for (a sample of) the shadowed side of
  // the boundary, the point of the caster its ray to the Sun hits. Moving
  // the Sun moves the edge to where those points' shadows land.
  std::vector<Eigen::Vector3f> edge_caster;
  std::vector<int> edge_ground;  // the ground pixel each was found from
  int frames_since_refresh = 0;
  int band_core = 0;  // band[0, band_core) lie by a boundary
  // Scratch per ground pixel, valid where its tag equals the current epoch.
  std::vector<int> tag, slot;
  int epoch = 0;

  // Work buffers: band_origin per sub-pixel ray (subsamples^2 per pixel),
  // band_normal/band_x/band_y per band pixel.
  std::vector<float> band_origin, band_x, band_y;
  size_t band_picked = 0;  // band pixels LoadBand looked at (seen or not)
  std::vector<Eigen::Vector3f> band_normal;
  std::vector<int> band_ground;  // per loaded band pixel: its ground index
  std::vector<int> band_face;    // and its face (all_surfaces)
  std::vector<uint8_t> occluded;
  // Every ground pixel's origin, x y z: LitOf casts from it through the
  // pixels' indices (Scene::OccludedTowardSubset), copying none.
  std::vector<float> ground_origin;
  // Initialize's scratch over the whole ground, kept: a run initialises
  // again on every re-acquisition, and at 1080p each fresh buffer's first
  // writes (page faults) cost more than filling it.
  std::vector<float> init_x, init_y, init_sorted;
  std::vector<uint8_t> init_near_edge;
  AffineFit init_fit;
  std::vector<int> every;  // every ground pixel's index, 0 to n - 1
  AffineFit fit;
  int64_t rays_cast = 0, evaluations = 0;  // counters of the current frame

  Impl(const Scene& s, const Camera& c, const ShadowTrackerOptions& opt)
      : scene(s), camera(c), o(opt), W(c.width()), H(c.height()) {
    if (o.subsamples == 0) o.subsamples = W < 1280 ? 2 : 1;
    if (!o.all_surfaces && o.surfaces_pin_deg > 0) {
      ShadowTrackerOptions every = opt;
      every.all_surfaces = true;
      surfaces = std::make_unique<ShadowTracker>(s, c, every);
    }
  }

  bool IsGround(int32_t id) const {
    return internal::IsGround(o.ground_object_ids, id);
  }
  bool IsReceiver(int32_t id) const { return o.all_surfaces || IsGround(id); }
  // Ground pixels a and b lie on one plane: where two faces meet (a lit wall
  // over shaded ground) the lit/shaded step is the faces', whatever the Sun.
  bool OnePlane(int a, int b) const {
    return ground[a].normal.dot(ground[b].normal) >= kSamePlaneCos;
  }

  std::map<std::tuple<int, int, int>, int> faces;
  int FaceOf(int32_t object, const Eigen::Vector3f& n) {
    const auto [zbin, abin] = NormalBin(n, kFaceNormalBinDeg);
    const auto it = faces.emplace(std::make_tuple(int(object), zbin, abin),
                                  static_cast<int>(faces.size()));
    if (it.second) face_on_ground.push_back(IsGround(object));
    num_faces = static_cast<int>(faces.size());
    return it.first->second;
  }

  const int* FacesOf(const std::vector<int>& v) const {
    return o.all_surfaces ? v.data() : nullptr;
  }
  int Faces() const { return o.all_surfaces ? num_faces : 1; }
  // Share of the loaded band (all_surfaces) off the ground's faces.
  double OffGroundShare() const {
    size_t off = 0;
    for (int f : band_face) off += !face_on_ground[f];
    return band_face.empty() ? 0.0 : double(off) / band_face.size();
  }
  // The fit's sun/ambient contrast: on the face with most band pixels.
  double Contrast(const AffineFit& f, const std::vector<int>& faces_of) const {
    int g = 0;
    if (o.all_surfaces && !faces_of.empty()) {
      std::vector<int> count(num_faces, 0);
      for (int k : faces_of) ++count[k];
      g = static_cast<int>(std::max_element(count.begin(), count.end()) -
                           count.begin());
    }
    const double a = f.a[g], b = f.b[g];
    return a > 0 ? b / a : (b > 0 ? 100.0 : 0.0);
  }

  void MapGround() {
    ground_index.create(H, W);
    AdviseHugePages(ground_index.data, ground_index.total() * sizeof(int));
    ground_index.setTo(-1);
    const int y0 = o.ignore_top_rows, y1 = H - o.ignore_bottom_rows;
    const float lift = scene.surface_offset();
    ReserveHuge(&ground, static_cast<size_t>(std::max(0, y1 - y0)) * W);
    // A few rows at a time: the rays' buffers stay small and warm.
    constexpr int kRows = 16;
    std::vector<double> px;
    Hits hits;
    for (int ya = y0; ya < y1; ya += kRows) {
      const int yb = std::min(y1, ya + kRows);
      px.clear();
      for (int y = ya; y < yb; ++y) {
        for (int x = 0; x < W; ++x) px.insert(px.end(), {double(x), double(y)});
      }
      const int64_t n = static_cast<int64_t>(px.size() / 2);
      if (static_cast<int64_t>(hits.object_id.size()) != n) hits = Hits(n);
      scene.IntersectPixels(camera, n, px.data(), hits.buffers());
      for (int64_t i = 0; i < n; ++i) {
        if (!hits.hit(i) || !IsReceiver(hits.object_id[i])) continue;
        const int x = static_cast<int>(px[2 * i]),
                  y = static_cast<int>(px[2 * i + 1]);
        ground_index(y, x) = static_cast<int>(ground.size());
        GroundPixel gp;
        gp.px = cv::Point(x, y);
        gp.normal = hits.normal(i);
        gp.origin = hits.point(i) + lift * gp.normal;
        ground.push_back(gp);
        if (o.all_surfaces)
          face.push_back(FaceOf(hits.object_id[i], gp.normal));
      }
    }
    ReserveHuge(&tag, ground.size());
    ReserveHuge(&slot, ground.size());
    tag.assign(ground.size(), 0);
    slot.assign(ground.size(), 0);
    ReserveHuge(&every, ground.size());
    every.resize(ground.size());
    std::iota(every.begin(), every.end(), 0);
    // Initialize's scratch over the whole ground, written once here: this
    // runs beside the reference frames' decoding, and the first frame's
    // start paid these pages' faults (at 1080p, half of its time).
    const size_t n = ground.size();
    for (std::vector<float>* v : {&init_x, &init_y, &init_sorted}) {
      ReserveHuge(v, n);
      v->assign(n, 0.f);
    }
    ReserveHuge(&init_fit.residual, n);
    init_fit.residual.assign(n, 0.0);
    ReserveHuge(&ground_origin, 3 * n);
    ground_origin.resize(3 * n);
    for (size_t g = 0; g < n; ++g) {
      for (int k = 0; k < 3; ++k)
        ground_origin[3 * g + k] = ground[g].origin[k];
    }
    init_near_edge.assign(n, 0);
  }

  // How ground pixel g's point moves per pixel step (dx, dy), from its
  // neighbouring ground pixels; only sub-pixel rays need it.
  Eigen::Vector3f Step(int g, int dx, int dy) const {
    const cv::Point p = ground[g].px;
    const cv::Point a(p.x - dx, p.y - dy), b(p.x + dx, p.y + dy);
    const cv::Rect frame(0, 0, W, H);
    const int ga = frame.contains(a) ? ground_index(a) : -1;
    const int gb = frame.contains(b) ? ground_index(b) : -1;
    if (ga >= 0 && gb >= 0)
      return 0.5f * (ground[gb].origin - ground[ga].origin);
    if (gb >= 0) return ground[gb].origin - ground[g].origin;
    if (ga >= 0) return ground[g].origin - ground[ga].origin;
    return Eigen::Vector3f::Zero();
  }

  // Shading of ground pixel g toward `toward_sun` given its occlusion flag.
  float Shading(int g, const Eigen::Vector3f& d, bool occ) const {
    return occ ? 0.f : std::max(0.f, ground[g].normal.dot(d));
  }

  // Lit flags of ground indices `ids` toward d (1 lit, 0 shadow).
  std::vector<uint8_t> LitOf(const std::vector<int>& ids,
                             const Eigen::Vector3f& d) {
    std::vector<uint8_t> occ(ids.size());
    scene.OccludedTowardSubset(static_cast<int64_t>(ids.size()), ids.data(),
                               ground_origin.data(), d, 0.f, kInf, occ.data());
    rays_cast += static_cast<int64_t>(ids.size());
    for (auto& v : occ) v = !v;
    return occ;
  }

  // Ground pixels within a (2r+1)^2 window of any of `centers`, each once.
  // Cost grows with the number of centres, not with the frame's size.
  std::vector<int> Window(const std::vector<int>& centers, int r) {
    ++epoch;
    std::vector<int> out;
    for (int c : centers) {
      const cv::Point p = ground[c].px;
      for (int y = std::max(0, p.y - r); y <= std::min(H - 1, p.y + r); ++y) {
        const int* row = ground_index[y];
        for (int x = std::max(0, p.x - r); x <= std::min(W - 1, p.x + r); ++x) {
          const int g = row[x];
          if (g >= 0 && tag[g] != epoch) {
            tag[g] = epoch;
            out.push_back(g);
          }
        }
      }
    }
    return out;
  }

  // Appends the ground pixel at (x, y), if any, unless this epoch has it.
  void AddOnce(int x, int y, std::vector<int>* out) {
    if (x < 0 || y < 0 || x >= W || y >= H) return;
    const int g = ground_index(y, x);
    if (g >= 0 && tag[g] != epoch) {
      tag[g] = epoch;
      out->push_back(g);
    }
  }

  // The pixels within `stride` of a lit/shadow boundary toward d (on one
  // plane), the boundaries found on a grid `stride` pixels apart: every
  // surface looked at for a 1/stride^2 of its rays.
  std::vector<int> NearBoundaries(const Eigen::Vector3f& d, int stride) {
    const std::vector<int> coarse = AllGround(stride);
    const std::vector<uint8_t> lit = LitOf(coarse, d);
    const int on_grid = ++epoch;
    for (size_t i = 0; i < coarse.size(); ++i) {
      tag[coarse[i]] = on_grid;
      slot[coarse[i]] = static_cast<int>(i);
    }
    std::vector<int> seeds;
    for (size_t i = 0; i < coarse.size(); ++i) {
      const int gi = coarse[i];
      const cv::Point p = ground[gi].px;
      const cv::Point next[2] = {{p.x + stride, p.y}, {p.x, p.y + stride}};
      for (const cv::Point& q : next) {
        if (q.x >= W || q.y >= H) continue;
        const int g = ground_index(q);
        if (g < 0 || tag[g] != on_grid || lit[slot[g]] == lit[i]) continue;
        if (!OnePlane(g, gi)) continue;
        seeds.push_back(gi);
        seeds.push_back(g);
      }
    }
    return Window(seeds, stride);
  }

  // A sample of the ring r pixels away from `centers` (8 per centre), each
  // pixel once: the outer band's share of the fit without visiting all of it.
  std::vector<int> Ring(const std::vector<int>& centers, int r) {
    ++epoch;
    std::vector<int> out;
    const int offsets[8][2] = {{r, 0}, {-r, 0},  {0, r},  {0, -r},
                               {r, r}, {-r, -r}, {r, -r}, {-r, r}};
    for (int c : centers) {
      const cv::Point p = ground[c].px;
      for (const auto& dxy : offsets) AddOnce(p.x + dxy[0], p.y + dxy[1], &out);
    }
    return out;
  }

  // Lit/shadow boundaries toward d among `candidates`; sets `boundary` (each
  // pixel once) and returns the band: ground pixels within band_radius of a
  // boundary, those next to it first. With `thin`, only as many boundary
  // pixels seed the band as the fit will sample (LoadBand keeps at most
  // max_band_pixels of it), every so many along the boundary.
  // `shadowed` (optional) receives the boundary pixels on the shadow side.
  // `lit_given` (optional): the candidates' LitOf toward d, already cast.
  std::vector<int> BandAround(const std::vector<int>& candidates,
                              const Eigen::Vector3f& d, bool thin = false,
                              std::vector<int>* shadowed = nullptr,
                              const std::vector<uint8_t>* lit_given = nullptr) {
    boundary.clear();
    if (shadowed) shadowed->clear();
    if (candidates.empty()) return {};
    std::vector<uint8_t> cast;
    if (!lit_given) cast = LitOf(candidates, d);
    const std::vector<uint8_t>& lit = lit_given ? *lit_given : cast;
    ++epoch;
    for (size_t i = 0; i < candidates.size(); ++i) {
      tag[candidates[i]] = epoch;
      slot[candidates[i]] = static_cast<int>(i);
    }
    // A second epoch marks pixels already on the boundary.
    const int seen = ++epoch;
    auto add = [&](int g, bool is_lit) {
      if (tag[g] == seen) return;
      tag[g] = seen;
      boundary.push_back(g);
      if (shadowed && !is_lit) shadowed->push_back(g);
    };
    for (size_t i = 0; i < candidates.size(); ++i) {
      const int gi = candidates[i];
      const cv::Point p = ground[gi].px;
      const cv::Point next[2] = {{p.x + 1, p.y}, {p.x, p.y + 1}};
      for (const cv::Point& q : next) {
        if (q.x >= W || q.y >= H) continue;
        const int g = ground_index(q);
        if (g < 0 || (tag[g] != seen && tag[g] != seen - 1)) continue;
        const int gs = slot[g];
        if (lit[gs] == lit[i]) continue;
        if (o.all_surfaces && !OnePlane(g, gi)) continue;
        add(gi, lit[i]);
        add(g, lit[gs]);
      }
    }
    // The pixels next to a boundary carry the direction: they come first in
    // the band, so that subsampling (LoadBand) thins only the outer ring,
    // which serves the photometric fit.
    // Along a boundary a 3x3 window adds about 3 new pixels; the outer ring is
    // kept at least twice what LoadBand samples of it.
    const int budget = o.max_band_pixels;
    const size_t core_stride =
        thin ? std::max<size_t>(1, 3 * boundary.size() / (2 * budget)) : 1;
    const size_t outer_stride =
        thin ? std::max<size_t>(1, 2 * boundary.size() / budget) : 1;
    std::vector<int> seeds;
    for (size_t i = 0; i < boundary.size(); i += core_stride)
      seeds.push_back(boundary[i]);
    std::vector<int> core = Window(seeds, 1);
    const int core_epoch = epoch;
    seeds.clear();
    for (size_t i = 0; i < boundary.size(); i += outer_stride)
      seeds.push_back(boundary[i]);
    std::vector<int> band =
        thin ? Ring(seeds, o.band_radius_px) : Window(seeds, o.band_radius_px);
    band_core = static_cast<int>(core.size());
    for (int g : core) tag[g] = core_epoch;  // mark the core again
    std::vector<int> ordered = core;
    for (int g : band) {
      if (tag[g] != core_epoch) ordered.push_back(g);
    }
    return ordered;
  }

  // Records which caster point casts each of (a sample of) the shadowed
  // boundary pixels toward d.
  void FindEdgeCasters(const std::vector<int>& shadowed,
                       const Eigen::Vector3d& d) {
    edge_caster.clear();
    edge_ground.clear();
    const int stride = (static_cast<int>(shadowed.size()) + 599) / 600;
    std::vector<float> org, dir;
    std::vector<int> from;
    for (size_t i = 0; i < shadowed.size(); i += stride) {
      const int g = shadowed[i];
      const Eigen::Vector3f& p = ground[g].origin;
      org.insert(org.end(), {p.x(), p.y(), p.z()});
      dir.insert(dir.end(), {float(d.x()), float(d.y()), float(d.z())});
      from.push_back(g);
    }
    const int64_t n = static_cast<int64_t>(from.size());
    Hits hits(n);
    scene.Intersect(n, org.data(), dir.data(), 0.f, kInf, hits.buffers());
    rays_cast += n;
    for (int64_t i = 0; i < n; ++i) {
      if (!hits.hit(i) || IsGround(hits.object_id[i])) continue;
      edge_caster.push_back(hits.point(i));
      edge_ground.push_back(from[i]);
    }
  }

  // Ground pixels where the recorded caster points' shadows land toward d,
  // each shadow put on the tangent plane of the ground pixel it came from.
  std::vector<int> MovedEdge(const Eigen::Vector3d& d) {
    ++epoch;
    std::vector<int> out;
    const Eigen::Vector3f df = d.cast<float>();
    for (size_t i = 0; i < edge_caster.size(); ++i) {
      const int g = edge_ground[i];
      const Eigen::Vector3f n = ground[g].normal;
      const float dn = df.dot(n);
      if (dn < 0.02f) continue;
      const Eigen::Vector3f q = edge_caster[i];
      const Eigen::Vector3f p = q - ((q - ground[g].origin).dot(n) / dn) * df;
      Eigen::Vector2d px;
      if (!camera.WorldToPixel(p.cast<double>(), &px)) continue;
      AddOnce(static_cast<int>(std::lround(px.x())),
              static_cast<int>(std::lround(px.y())), &out);
    }
    return out;
  }

  std::vector<int> AllGround(int stride) const {
    std::vector<int> out;
    for (int g = 0; g < static_cast<int>(ground.size()); ++g) {
      if (ground[g].px.x % stride == 0 && ground[g].px.y % stride == 0)
        out.push_back(g);
    }
    return out;
  }

  // Loads the band's pixels (subsampled) and the frame's values into buffers,
  // with subsamples^2 rays per pixel spread over the pixel's footprint.
  void LoadBand(const cv::Mat& frame) {
    // All of the core (up to the budget), then every stride-th outer pixel.
    const int n = static_cast<int>(band.size());
    const int core = std::min(band_core, o.max_band_pixels);
    const int room = std::max(o.max_band_pixels - core, o.max_band_pixels / 4);
    const int core_stride = std::max(1, band_core / std::max(1, core));
    const int outer_stride = std::max(1, (n - band_core) / room + 1);
    std::vector<int> picked;
    for (int i = 0; i < band_core; i += core_stride) picked.push_back(band[i]);
    for (int i = band_core; i < n; i += outer_stride) picked.push_back(band[i]);
    // In memory order: the band's pixels are scattered over the frame.
    std::sort(picked.begin(), picked.end());
    band_picked = picked.size();
    // subsamples^2 rays over each pixel's footprint: the lit fraction places
    // an edge within the pixel.
    const int k = o.subsamples;
    band_origin.clear();
    band_normal.clear();
    band_ground.clear();
    band_face.clear();
    band_y.clear();
    // The pixels' records and frame values are scattered cache misses:
    // fetched a few pixels ahead, the misses overlap.
    const size_t m = picked.size();
    for (size_t i = 0; i < m; ++i) {
      if (i + 16 < m) __builtin_prefetch(&ground[picked[i + 16]]);
      if (i + 8 < m)
        __builtin_prefetch(&frame.at<float>(ground[picked[i + 8]].px));
      const GroundPixel& gp = ground[picked[i]];
      const float v = frame.at<float>(gp.px);
      // NaN: a moving camera's frame does not see this point
      // (motion/view_warp.h).
      if (std::isnan(v)) continue;
      if (k == 1) {
        band_origin.insert(band_origin.end(),
                           {gp.origin.x(), gp.origin.y(), gp.origin.z()});
      } else {
        const Eigen::Vector3f dpdx = Step(picked[i], 1, 0),
                              dpdy = Step(picked[i], 0, 1);
        for (int sy = 0; sy < k; ++sy) {
          for (int sx = 0; sx < k; ++sx) {
            const float ox = (sx + 0.5f) / k - 0.5f,
                        oy = (sy + 0.5f) / k - 0.5f;
            const Eigen::Vector3f q = gp.origin + ox * dpdx + oy * dpdy;
            band_origin.insert(band_origin.end(), {q.x(), q.y(), q.z()});
          }
        }
      }
      band_normal.push_back(gp.normal);
      band_ground.push_back(picked[i]);
      if (o.all_surfaces) band_face.push_back(face[picked[i]]);
      band_y.push_back(o.normalize_albedo ? v / gp.albedo : v);
    }
    band_x.resize(band_y.size());
    occluded.resize(band_origin.size() / 3);
  }

  double Cost(const Eigen::Vector3d& toward_sun, double scale) {
    const Eigen::Vector3f d = toward_sun.cast<float>();
    const int rays = static_cast<int>(occluded.size());
    scene.OccludedToward(rays, band_origin.data(), d, 0.f, kInf,
                         occluded.data());
    rays_cast += rays;
    ++evaluations;
    const int per_pixel = o.subsamples * o.subsamples;
    // A pixel's shading: its lit fraction (of its sub-pixel rays) times n.d.
    for (size_t i = 0; i < band_x.size(); ++i) {
      int lit = 0;
      for (int r = 0; r < per_pixel; ++r) lit += !occluded[i * per_pixel + r];
      band_x[i] = lit * std::max(0.f, band_normal[i].dot(d)) / per_pixel;
    }
    const int n = static_cast<int>(band_y.size());
    RobustAffineFit(n, band_x.data(), band_y.data(), FacesOf(band_face),
                    Faces(), scale, 3, &fit);
    return fit.cost;
  }

  // Cost steps to noise variances under the last fit: its noise is the MAD
  // of its residuals; with the Cauchy scale well above it a cost step is a
  // chi-square step times noise^2 / scale^2. 0 without residuals.
  double CostToChi2(double scale) const {
    if (fit.residual.empty()) return 0.0;
    std::vector<double> r(fit.residual.size());
    for (size_t i = 0; i < r.size(); ++i) r[i] = std::abs(fit.residual[i]);
    const double noise = std::max(1e-6, 1.4826 * MedianInPlace(&r));
    return scale * scale / (noise * noise);
  }

  // See TrackedFrame::elevation_pinned_deg; the fit at d is the last one.
  // Overwrites `fit`.
  double ElevationPinned(const Eigen::Vector3d& d, double scale) {
    if (fit.residual.empty()) return kInf;
    const double to_chi2 = CostToChi2(scale);
    const double c0 = fit.cost;
    Eigen::Vector3d up = Eigen::Vector3d::UnitZ() - d.z() * d;
    if (up.norm() < 1e-9) return 0.0;  // overhead: every way is down
    up.normalize();
    for (double delta : {0.5, 1.0, 2.0, 4.0, 8.0}) {
      bool pinned = true;
      for (double sign : {1.0, -1.0}) {
        const Eigen::Vector3d e =
            (std::cos(delta * kDeg) * d + sign * std::sin(delta * kDeg) * up)
                .normalized();
        // Below the horizon is no Sun: that side is bounded.
        if (e.z() > 0.01 && (Cost(e, scale) - c0) * to_chi2 < kPinChi2) {
          pinned = false;
          break;
        }
      }
      if (pinned) return delta;
    }
    return kInf;
  }

  // Whether `other` explains the band (as loaded) as well as `d` does: its
  // cost no more than kPinChi2 noise variances above d's (as in
  // ElevationPinned). Overwrites `fit`.
  bool FitsAsWell(const Eigen::Vector3d& d, const Eigen::Vector3d& other,
                  double scale) {
    const double c0 = Cost(d, scale);
    if (fit.residual.empty()) return false;
    const double to_chi2 = CostToChi2(scale);
    return (Cost(other, scale) - c0) * to_chi2 < kPinChi2;
  }

  // Share of the band's pixels on the wrong side of a boundary under the
  // last fit (toward d): the residuals as a mixture of noise about 0 and of
  // pixels one lit/shaded step off either way (the step: the fit's sun term
  // times the band's mean n.d), its weights and spread by EM. Texture and
  // noise widen the middle, a misplaced edge fills the sides. Each pixel is
  // the median of its 3x3 neighbourhood (albedo taken out): a misplaced
  // edge leaves strips a few pixels wide, a render's or a sensor's speckle
  // (a bright pixel in the shade) single pixels, which it drops.
  double Misfit(const cv::Mat& frame, const Eigen::Vector3d& d) const {
    if (fit.b.empty() || fit.residual.empty() || band_normal.empty())
      return 0.0;
    const Eigen::Vector3f df = d.cast<float>();
    double cos_sum = 0.0;
    for (const Eigen::Vector3f& n : band_normal)
      cos_sum += std::max(0.f, n.dot(df));
    double step = fit.b[0] * cos_sum / band_normal.size();
    if (o.all_surfaces) step = 1.0;  // each pixel's residual in its own steps
    if (!(step > 0)) return 1.0;
    std::vector<double> residual(fit.residual.size());
    float around[9];
    for (size_t i = 0; i < residual.size(); ++i) {
      const GroundPixel& gp = ground[band_ground[i]];
      const float y = band_y[i];  // the fit's value is y - residual
      int k = 0;
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const cv::Point q(gp.px.x + dx, gp.px.y + dy);
          if (q.x < 0 || q.y < 0 || q.x >= W || q.y >= H) continue;
          const int g = ground_index(q);
          if (g < 0) continue;
          const float v = frame.at<float>(q);
          if (std::isnan(v)) continue;
          around[k++] = o.normalize_albedo ? v / ground[g].albedo : v;
        }
      }
      residual[i] = fit.residual[i] +
                    (k > 0 ? MedianInPlace(around, around + k) - y : 0.0);
      if (o.all_surfaces) {
        const double own =
            fit.b[band_face[i]] * std::max(0.f, band_normal[i].dot(df));
        residual[i] = own > 0 ? residual[i] / own : 0.0;
      }
    }
    double m = 0.1, var = 0.0625 * step * step;
    const double n = static_cast<double>(residual.size());
    for (int it = 0; it < 30; ++it) {
      double sum_side = 0, sum_sq = 0;
      for (double r : residual) {
        const double w0 = (1 - m) * std::exp(-0.5 * r * r / var);
        const double wp =
            0.5 * m * std::exp(-0.5 * (r - step) * (r - step) / var);
        const double wm =
            0.5 * m * std::exp(-0.5 * (r + step) * (r + step) / var);
        const double total = w0 + wp + wm;
        if (!(total > 1e-300)) {  // far out either way: a side pixel
          sum_side += 1;
          sum_sq += std::min((r - step) * (r - step), (r + step) * (r + step));
          continue;
        }
        sum_side += (wp + wm) / total;
        sum_sq += (w0 * r * r + wp * (r - step) * (r - step) +
                   wm * (r + step) * (r + step)) /
                  total;
      }
      const double m_before = m, var_before = var;
      m = std::clamp(sum_side / n, 1e-4, 1 - 1e-4);
      var = std::max(sum_sq / n, 1e-6 * step * step);
      // Settled: further steps move the share by less than it is reported to.
      if (std::abs(m - m_before) < 1e-5 &&
          std::abs(var - var_before) < 1e-4 * var)
        break;
    }
    return m;
  }

  // Pattern search on the sphere in the tangent plane of `start`: at each
  // step size the four axis neighbours are scored, a parabola through each
  // axis's three costs proposes the minimum between them, and the best of
  // the six becomes the centre. The step shrinks unless the best lies a
  // full step away (the minimum may lie further). A third of the
  // evaluations of a plain compass search, and a better minimum (1080p
  // benchmark: 28.5 -> 9.5 candidate Suns per frame).
  // Leaves the best Sun's fit in `fit`. The walk goes at most kMaxWalkSteps
  // first steps (at least search_step_deg each) from `start`; *escaped says
  // it wanted to go further (the shadows are not where the band looks: a
  // re-acquisition's job).
  Eigen::Vector3d Search(const Eigen::Vector3d& start, double step_deg,
                         double scale, bool* escaped) {
    *escaped = false;
    Eigen::Vector3d e1 = start.cross(Eigen::Vector3d::UnitZ());
    if (e1.norm() < 1e-6) e1 = Eigen::Vector3d::UnitX();
    e1.normalize();
    const Eigen::Vector3d e2 = start.cross(e1).normalized();
    auto at = [&](const Eigen::Vector2d& c) {
      return (start + c.x() * e1 + c.y() * e2).normalized();
    };
    AffineFit best_fit;
    Eigen::Vector2d uv(0, 0);
    double best = Cost(start, scale);
    best_fit = fit;
    // Points already scored (a level that moves to a neighbour has the old
    // centre among its own neighbours): their costs are reused. A reused
    // point is never better than the centre, so its fit is not needed.
    std::vector<std::pair<Eigen::Vector2d, double>> scored = {{uv, best}};
    auto consider = [&](const Eigen::Vector2d& c, double* cost_out) {
      for (const auto& [p, cost] : scored) {
        if ((p - c).norm() < 1e-9) {
          *cost_out = cost;
          return false;
        }
      }
      const Eigen::Vector3d d = at(c);
      *cost_out = d.z() <= 0.01 ? std::numeric_limits<double>::infinity()
                                : Cost(d, scale);
      scored.emplace_back(c, *cost_out);
      return std::isfinite(*cost_out);
    };
    double h = step_deg * kDeg;
    const double max_walk =
        kMaxWalkSteps * std::max(h, o.search_step_deg * kDeg);
    Eigen::Vector2d last_move = Eigen::Vector2d::Zero();
    int guard = 0;
    while (h > o.tolerance_deg * kDeg && guard++ < 100) {
      if (uv.norm() > max_walk) {
        *escaped = true;
        break;
      }
      const Eigen::Vector2d center = uv;
      const double c0 = best;
      Eigen::Vector2d pick = center, proposal = center;
      double pick_cost = best;
      for (int axis = 0; axis < 2; ++axis) {
        Eigen::Vector2d step = Eigen::Vector2d::Zero();
        step[axis] = h;
        double cp, cm;
        consider(center + step, &cp);
        if (cp < pick_cost)
          pick_cost = cp, pick = center + step, best_fit = fit;
        consider(center - step, &cm);
        if (cm < pick_cost)
          pick_cost = cm, pick = center - step, best_fit = fit;
        const double curvature = cp + cm - 2 * c0;
        if (std::isfinite(curvature) && curvature > 0) {
          proposal[axis] += std::clamp(0.5 * h * (cm - cp) / curvature, -h, h);
        }
      }
      if ((proposal - center).norm() > 0.05 * h &&
          (proposal - pick).norm() > 0.05 * h) {
        double cq;
        if (consider(proposal, &cq) &&
            cq < pick_cost) {  // fresh, so fit is its own
          pick_cost = cq, pick = proposal, best_fit = fit;
        }
      }
      // A best point at the step's full reach (a neighbour, or a clamped
      // parabola) says the minimum may lie further: keep the step.
      // Two such moves the same way: the Sun is further off than the step
      // guessed (a clip with big jumps between captures), so it doubles.
      const Eigen::Vector2d move = pick - center;
      const bool at_reach = move.cwiseAbs().maxCoeff() >= h * (1 - 1e-6);
      uv = pick;
      best = pick_cost;
      if (!at_reach) {
        h *= kShrink;
        last_move.setZero();
      } else {
        if (move.dot(last_move) > 0)
          h = std::min(2 * h, 4 * o.search_step_deg * kDeg);
        last_move = move;
      }
    }
    fit = best_fit;
    return at(uv);
  }

  void Describe(const Eigen::Vector3d& d, TrackedFrame* out) {
    AnglesFromSunInWorld(d, &out->zenith_deg, &out->azimuth_deg);
    out->sun_in_world = d;
    // The longest modelled shadow whose tip lands on the ground in view.
    double longest = 0;
    for (const internal::Caster& c : casters) {
      Eigen::Vector3f top, tip;
      if (!internal::ShadowTip(scene, c, d, o.ground_object_ids, &top, &tip))
        continue;
      const Eigen::Vector3f foot = c.FootBelow(top);
      Eigen::Vector2d foot_px, tip_px;
      if (!camera.WorldToPixel(foot.cast<double>(), &foot_px) ||
          !camera.WorldToPixel(tip.cast<double>(), &tip_px)) {
        continue;
      }
      if (tip_px.x() < 0 || tip_px.y() < 0 || tip_px.x() > W - 1 ||
          tip_px.y() > H - 1)
        continue;
      const double length = (tip - foot).norm();
      if (length > longest) {
        longest = length;
        out->shadow_start_px = foot_px;
        out->shadow_end_px = tip_px;
      }
    }
  }

  // The frame cannot show shadows: why, or empty if it can. A sparse grid of
  // pixels tells a black or overexposed frame as well as all of them do.
  std::string Unusable(const cv::Mat& frame) const {
    if (frame.empty()) return "frame cannot be decoded";
    if (frame.cols != W || frame.rows != H)
      return "frame has another size than the clip";
    const int step = std::max(1, std::min(W, H) / 30);
    float hi = 0;
    int clipped = 0, count = 0;
    for (int y = o.ignore_top_rows; y < H - o.ignore_bottom_rows; y += step) {
      const float* row = frame.ptr<float>(y);
      for (int x = 0; x < W; x += step, ++count) {
        hi = std::max(hi, row[x]);
        clipped += row[x] >= 0.98f;
      }
    }
    if (hi < 0.01f) return "frame is black";
    if (clipped > count / 2) return "frame is overexposed";
    return {};
  }
};

ShadowTracker::ShadowTracker(const Scene& scene, const Camera& camera,
                             const ShadowTrackerOptions& options)
    : impl_((options.Check(), std::make_unique<Impl>(scene, camera, options))) {
  Require(
      options.ignore_top_rows + options.ignore_bottom_rows < camera.height(),
      "ignore_top_rows + ignore_bottom_rows leave no rows");
}

ShadowTracker::~ShadowTracker() = default;

void ShadowTracker::Prepare() {
  Impl& s = *impl_;
  if (s.mapped) return;
  s.MapGround();
  s.casters = internal::FindCasters(s.scene, s.o.ground_object_ids);
  s.mapped = true;
}

TrackedFrame ShadowTracker::Initialize(const cv::Mat& frame,
                                       const Eigen::Vector3d& sun_in_world) {
  Impl& s = *impl_;
  Require(frame.type() == CV_32FC1 && frame.cols == s.W && frame.rows == s.H,
          "frame: expected float32 gray of the camera's size");
  Require(sun_in_world.allFinite() && sun_in_world.z() > 0,
          "sun_in_world must point above the horizon");
  const auto t0 = std::chrono::steady_clock::now();
  TrackedFrame out;
  const Eigen::Vector3d d = sun_in_world.normalized();
  // The ground map and the casters depend on the scene and the camera only:
  // made once, reused by re-initialisations (a run re-acquires the Sun tens
  // of times on a hard clip); the albedo is the frame's own.
  Prepare();
  for (auto& gp : s.ground) gp.albedo = 1.f;
  s.sun = s.sun_before = d;
  s.have_velocity = false;
  s.lost = 0;
  s.initialized = true;
  // The walls' tracker starts again too, from the next frame that needs it.
  s.surfaces_started = false;
  s.Describe(d, &out);
  if (s.ground.empty()) {
    out.status = TrackedFrame::Status::kNoGroundInView;
    out.reason = "no ground in view: check the ground objects and the camera";
    return out;
  }
  // Shadows of the first frame, and the ground's albedo relative to its
  // median: I = rho (A + S shading) with A, S fitted robustly on the ground.
  const Eigen::Vector3f df = d.cast<float>();
  const std::vector<int>& all = s.every;
  const std::vector<uint8_t> lit = s.LitOf(all, df);
  // Ground a moving camera's frame does not see is NaN (view_warp.h): left
  // out of the fit (its samples first, in x and y), its albedo left at 1.
  std::vector<float>&x = s.init_x, &y = s.init_y;
  ReserveHuge(&x, all.size());
  ReserveHuge(&y, all.size());
  x.resize(all.size());
  y.resize(all.size());
  std::vector<int> faces_seen;
  size_t seen = 0;
  for (size_t i = 0; i < all.size(); ++i) {
    const float v = frame.at<float>(s.ground[all[i]].px);
    if (std::isnan(v)) continue;
    x[seen] = s.Shading(all[i], df, !lit[i]);
    y[seen++] = v;
    if (s.o.all_surfaces) faces_seen.push_back(s.face[all[i]]);
  }
  if (seen == 0 || seen < all.size() * kMinSeenShare) {
    out.status = TrackedFrame::Status::kNoGroundInView;
    out.reason = "the ground is out of view on this frame";
    return out;
  }
  std::vector<float>& sorted = s.init_sorted;
  ReserveHuge(&sorted, seen);
  sorted.assign(y.begin(), y.begin() + static_cast<std::ptrdiff_t>(seen));
  const double scale = std::max(1e-4, s.o.loss_scale * MedianInPlace(&sorted));
  AffineFit& fit = s.init_fit;
  ReserveHuge(&fit.residual, seen);
  RobustAffineFit(static_cast<int>(seen), x.data(), y.data(),
                  s.FacesOf(faces_seen), s.Faces(), scale, 4, &fit);
  std::vector<int> shadowed;
  s.band = s.BandAround(all, df, false, &shadowed, &lit);
  s.FindEdgeCasters(shadowed, d);
  s.frames_since_refresh = 0;
  std::vector<uint8_t>& near_edge = s.init_near_edge;  // per ground pixel
  near_edge.assign(s.ground.size(), 0);
  for (int g : s.band) near_edge[g] = 1;  // unreliable: lit state uncertain
  for (size_t i = 0; i < all.size(); ++i) {
    const int g = all[i];
    const float v = frame.at<float>(s.ground[g].px);
    const int f = s.o.all_surfaces ? s.face[g] : 0;
    const double model = fit.a[f] + fit.b[f] * s.Shading(g, df, !lit[i]);
    if (model > 1e-4 && !std::isnan(v) && !near_edge[g]) {
      s.ground[g].albedo =
          std::clamp(static_cast<float>(v / model), 0.05f, 20.f);
    }
  }
  std::vector<int> band_faces;  // the contrast is the band's main face's
  if (s.o.all_surfaces)
    for (int g : s.band) band_faces.push_back(s.face[g]);
  out.contrast = s.Contrast(fit, band_faces);
  out.band_pixels = static_cast<int>(s.band.size());
  out.ok = !s.band.empty();
  out.confidence = out.ok ? 1.0 : 0.0;
  out.status = out.ok ? TrackedFrame::Status::kTracked
                      : TrackedFrame::Status::kNoShadowInView;
  if (!out.ok)
    out.reason = "no cast shadow of the model falls on the ground in view";
  out.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0)
          .count();
  return out;
}

TrackedFrame ShadowTracker::Track(const cv::Mat& frame) {
  return TrackImpl(frame, nullptr);
}

TrackedFrame ShadowTracker::Track(
    const cv::Mat& frame, const Eigen::Vector3d& predicted_sun_in_world) {
  Require(predicted_sun_in_world.allFinite() && predicted_sun_in_world.z() > 0,
          "predicted_sun_in_world must point above the horizon");
  const Eigen::Vector3d p = predicted_sun_in_world.normalized();
  return TrackImpl(frame, &p);
}

TrackedFrame ShadowTracker::TrackImpl(const cv::Mat& frame,
                                      const Eigen::Vector3d* given) {
  Impl& s = *impl_;
  Require(s.initialized, "Track() before Initialize()");
  Require(frame.empty() || frame.type() == CV_32FC1,
          "frame: expected float32 gray");
  const auto t0 = std::chrono::steady_clock::now();
  TrackedFrame out;
  // Prediction: the given Sun, or the last one kept at its angular velocity.
  Eigen::Vector3d pred = given ? *given : s.sun;
  if (!given && s.have_velocity) {
    const Eigen::Vector3d axis = s.sun_before.cross(s.sun);
    const double angle = std::atan2(axis.norm(), s.sun_before.dot(s.sun));
    if (axis.norm() > 1e-12) {
      pred = Eigen::AngleAxisd(angle * (1 + s.lost), axis.normalized()) * s.sun;
    }
  }
  s.rays_cast = s.evaluations = 0;
  auto finish = [&](const Eigen::Vector3d& d) {
    s.Describe(d, &out);
    out.rays = static_cast<int>(s.rays_cast);
    out.evaluations = static_cast<int>(s.evaluations);
    out.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0)
            .count();
    return out;
  };
  out.reason = s.Unusable(frame);
  if (!out.reason.empty()) {
    ++s.lost;
    out.status = TrackedFrame::Status::kUnusableFrame;
    return finish(pred);
  }
  const Eigen::Vector3f pf = pred.cast<float>();
  // Band near the predicted boundaries. Normally the recorded caster points
  // say where the edges moved (a few pixels at most), and only a thin strip
  // around there is ray cast; every so often, or when the edges found that
  // way are much fewer than before (an edge may have entered the view), the
  // whole neighbourhood of the last boundaries is searched instead, and the
  // whole ground after a loss.
  const std::vector<int> last_boundary = s.boundary;
  std::vector<int> shadowed, band;
  if (s.lost == 0 && !s.edge_caster.empty() &&
      s.frames_since_refresh < kRefreshFrames) {
    band = s.BandAround(s.Window(s.MovedEdge(pred), 2), pf, true, &shadowed);
    ++s.frames_since_refresh;
    if (s.boundary.size() < 0.8 * last_boundary.size()) band.clear();
  }
  if (band.empty()) {
    s.frames_since_refresh = 0;
    // On every surface a wall's shadow can appear far from the last
    // boundaries: its refresh looks everywhere, first on a coarse grid.
    const std::vector<int> candidates =
        s.o.all_surfaces ? s.NearBoundaries(pf, std::max(2, s.W / 240))
        : (!last_boundary.empty() && s.lost == 0)
            ? s.Window(last_boundary, s.o.band_radius_px + 2)
            : s.every;
    band = s.BandAround(candidates, pf, true, &shadowed);
    if (band.empty() && s.lost == 0 && !s.o.all_surfaces)
      band = s.BandAround(s.every, pf, true, &shadowed);
  }
  if (band.empty()) {
    ++s.lost;
    out.status = TrackedFrame::Status::kNoShadowInView;
    out.reason = "no cast shadow of the model falls on the ground in view";
    return finish(pred);
  }
  s.FindEdgeCasters(shadowed, pred);
  s.band = band;
  s.LoadBand(frame);
  // A moving camera's frame may not see the band (view_warp.h).
  if (s.band_y.empty() || s.band_y.size() < s.band_picked * kMinSeenShare) {
    ++s.lost;
    out.status = TrackedFrame::Status::kBandOutOfView;
    out.reason = "the shadows' band is out of view on this frame";
    return finish(pred);
  }
  // On every surface, a band on the ground alone is the ground's fit again
  // on another band, not the walls' say: on the real sundial clips taking
  // it moved the low Sun's frames by up to 2 deg, and their smoothed Sun
  // 0.1 deg further off.
  if (s.o.all_surfaces && s.OffGroundShare() < kMinOffGroundShare) {
    out.status = TrackedFrame::Status::kBandOnGroundOnly;
    out.reason = "the shadows' band lies on the ground alone";
    return finish(pred);
  }
  std::vector<float> sorted = s.band_y;
  const double scale = std::max(1e-4, s.o.loss_scale * MedianInPlace(&sorted));
  // The search starts at twice the last frame's correction of the prediction
  // (a steady Sun needs few evaluations), at most search_step_deg.
  // A given prediction (a whole-clip path's grid cell) may be a few degrees
  // off: it is searched around as widely as after a loss.
  const double step = (s.lost > 0 || given)
                          ? 4.0 * s.o.search_step_deg
                          : std::clamp(2.0 * s.last_correction_deg,
                                       std::max(0.05, 2 * s.o.tolerance_deg),
                                       s.o.search_step_deg);
  bool escaped = false;
  const Eigen::Vector3d found =
      s.Search(pred, step, scale, &escaped);  // leaves its fit in s.fit
  if (escaped) {
    ++s.lost;
    out.status = TrackedFrame::Status::kNoMatch;
    out.reason = "shadow lost: no match within " +
                 std::to_string(static_cast<int>(std::lround(
                     kMaxWalkSteps * std::max(step, s.o.search_step_deg)))) +
                 " deg of the predicted Sun";
    return finish(pred);
  }
  out.contrast = s.Contrast(s.fit, s.band_face);
  out.band_pixels = static_cast<int>(s.band_y.size());
  int inliers = 0;
  for (double r : s.fit.residual) inliers += std::abs(r) < 3 * scale;
  const double inlier_fraction =
      s.band_y.empty() ? 0.0 : double(inliers) / s.band_y.size();
  if (out.contrast < s.o.min_contrast) {
    ++s.lost;
    out.status = TrackedFrame::Status::kNoContrast;
    out.reason =
        "shadow lost: no sun/shade contrast on the ground (cloud, haze or "
        "glare?)";
    return finish(pred);
  }
  out.ok = true;
  out.status = TrackedFrame::Status::kTracked;
  out.confidence =
      inlier_fraction * std::min(1.0, out.contrast / (3 * s.o.min_contrast));
  out.misfit = s.Misfit(frame, found);
  out.elevation_pinned_deg = s.ElevationPinned(found, scale);
  Eigen::Vector3d kept = found;
  // The ground's shadows leave the Sun's height open (their far ends out of
  // view, or on a wall): the frame is fitted again on every surface in view,
  // from here. Its Sun is taken only when it pins the height and explains
  // the ground's shadows as well (a misplaced box's faces can pin a wrong
  // Sun); the ground's fit keeps its say on the contrast and the misfit,
  // which the clip's rules were set on.
  if (s.surfaces && out.elevation_pinned_deg > s.o.surfaces_pin_deg) {
    if (!s.surfaces_started) {
      s.surfaces->Initialize(frame, found);
      s.surfaces_started = true;
    }
    const TrackedFrame w = s.surfaces->Track(frame, found);
    s.rays_cast += w.rays;
    s.evaluations += w.evaluations;
    if (w.ok && w.elevation_pinned_deg <= s.o.surfaces_pin_deg &&
        s.FitsAsWell(found, w.sun_in_world, scale)) {
      kept = w.sun_in_world;
      out.elevation_pinned_deg = w.elevation_pinned_deg;
    }
  }
  // After a loss the velocity is unknown again: it restarts from this frame.
  s.have_velocity = s.lost == 0;
  s.sun_before = s.sun;
  s.last_correction_deg = AngleBetweenDeg(kept, pred);
  s.sun = kept;
  s.lost = 0;
  return finish(kept);
}

}  // namespace sunlapse
