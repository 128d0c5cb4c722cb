// Per-frame evidence for the Sun over the whole sky, by table look-ups.
//
// The model and the camera do not move, so which sky directions reach which
// visible surface point never changes during a clip. A visibility table is
// made once per run (in the spirit of precomputed radiance transfer, Gruber et
// al., ISMAR 2012, which the thesis cites): for a set of surface samples seen
// by the camera and a dense grid of sky directions, whether the sample is lit
// from that direction (in front of its surface and not occluded). Kept in
// world space on the model's surfaces, so a per-frame camera only changes
// which samples are looked at, not the table's meaning.
//
// Each frame is then scored against every direction at once: each sample's
// intensity is divided by its own reference level taken from the clip (a high
// quantile over frames spread through it: its albedo times its usual lit
// level), which cancels texture, view-dependent reflection and vignetting.
// A direction scores by the contrast between the lit and the shaded side of
// its predicted shadow boundaries (a band a few grid steps wide, per planar
// group of samples: same object, same normal), only when its predicted shade
// is the darker side, in log-likelihood units against the noise of
// neighbouring samples. So a Sun whose shadows are not dark scores nothing, a
// smooth brightness gradient has no contrast across an edge, and an exposure
// change is only a scale.
//
// Departure from the thesis: it fits shading on frame 1 alone and then
// follows one shadow; here every frame is scored over the whole sky and the
// choice is made over the whole clip (sun_path.h).
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "sunlapse/common/angles.h"
#include "sunlapse/scene/camera.h"
#include "sunlapse/scene/scene.h"

namespace sunlapse {

// Nearly uniform directions over the sky above the horizon (a Fibonacci
// spiral), world frame, with their neighbours for path searches.
class SkyGrid {
 public:
  // num_directions over zenith angles [0, max_zenith_deg].
  SkyGrid(int num_directions, double max_zenith_deg);
  int size() const { return static_cast<int>(directions_.size()); }
  const Eigen::Vector3d& direction(int i) const { return directions_[i]; }
  const std::vector<Eigen::Vector3d>& directions() const { return directions_; }
  // Typical angle between neighbouring directions (deg).
  double spacing_deg() const { return spacing_deg_; }
  // Indices within radius_deg of direction i (i included), from a cached
  // list when radius_deg <= the cache's radius, else by a scan.
  std::vector<int> Within(int i, double radius_deg) const;
  // Neighbours within the cache's radius of i with their angles (deg),
  // nearest first.
  struct Neighbour {
    int index;
    float angle_deg;
  };
  const std::vector<Neighbour>& Cached(int i) const { return Lists()[i]; }
  double cached_radius_deg() const { return cached_radius_deg_; }
  // Index of the grid direction closest to `d`.
  int Nearest(const Eigen::Vector3d& d) const;

 private:
  std::vector<Eigen::Vector3d> directions_;
  double spacing_deg_ = 0.0;
  double max_zenith_deg_ = 0.0;
  double cached_radius_deg_ = 0.0;
  // The neighbour lists are made on first use: only the path reads them, not
  // the table or the frames' evidence (30-60 ms of a run's fixed costs).
  // Shared by copies, as the directions are.
  struct Lazy {
    std::once_flag once;
    std::vector<std::vector<Neighbour>> lists;
  };
  std::shared_ptr<Lazy> cached_ = std::make_shared<Lazy>();
  const std::vector<std::vector<Neighbour>>& Lists() const;
};

struct SkyEvidenceOptions {
  // Sky directions scored per frame. 1200 gives ~4.5 deg spacing; the path is
  // refined to sub-degree afterwards by the shadow tracker.
  int num_directions = 3000;
  // Directions lower than this are not candidates (deg from the zenith).
  double max_zenith_deg = 88.0;
  // Surface samples at most (a regular pixel grid over what the model covers;
  // at most 65,535).
  int max_samples = 4000;
  // Rows at the top / bottom that are not scene content (banners).
  int ignore_top_rows = 0;
  int ignore_bottom_rows = 0;
  // Samples are grouped into planes by object and normal within this (deg).
  double normal_bin_deg = kFaceNormalBinDeg;
  // Only samples within this many grid steps of a candidate's predicted
  // shadow boundary are scored (the band); the boundary itself is step 0.
  int band_steps = 2;
  // A group scores only with at least this many band samples on each side of
  // a candidate's lit/shaded split (fewer are noise).
  int min_side_samples = 3;
  // Intensity / reference ratios are clipped to [0, max_ratio] (specular
  // glints, unmodelled objects).
  double max_ratio = 2.0;
  // Reference level: this quantile of a sample over the reference frames.
  double reference_quantile = 0.8;
  // Directions within this of the best one do not count as its rival when
  // the frame's margin is measured (deg).
  double rival_exclusion_deg = 12.0;
  // Neighbouring samples are not independent (texture, blur, the model's
  // misfit): this many count as one observation in the costs.
  double samples_per_observation = 8.0;
  // A frame has evidence when its best direction explains the frame this
  // much better than no shadows at all (log-likelihood units). A thin
  // gnomon's shadow on an engraved plate explains 1-2% of the variance and
  // is still unmistakable, so the share alone cannot be the test.
  double min_significance = 4.0;

  void Check() const;
};

struct FrameEvidence {
  enum class Status {
    kOk,         // the frame was scored
    kNoFrame,    // no frame (not decodable)
    kUnusable,   // black, overexposed or uniform where the model is seen
    kNoShadows,  // scored, but no direction explains anything (overcast?)
  };
  Status status = Status::kNoFrame;
  std::string message;
  // Best direction on this frame alone, its explained share of variance
  // (0..1) and its lead, in cost units (log-likelihood), over the best
  // direction rival_exclusion_deg away.
  int best_direction = -1;
  double best_explained = 0.0;
  double margin = 0.0;
  // How much better the best direction explains the frame than no shadows
  // at all (log-likelihood units).
  double significance = 0.0;
  // The median ratio of intensity to reference: the frame's exposure
  // relative to the reference frames.
  double exposure = 0.0;
  // Share of the samples where shadows can show (some direction's band)
  // that the frame sees: below 1 only for a moving camera's frame that
  // does not see all of the reference view (motion/view_warp.h).
  double shadow_view = 1.0;
  double seconds = 0.0;
};

class SkyEvidence {
 public:
  // The scene and camera must outlive this. Casts samples x directions rays
  // once. Throws std::invalid_argument on bad options or when the camera sees
  // no model surface.
  SkyEvidence(const Scene& scene, const Camera& camera,
              const SkyEvidenceOptions& options);
  ~SkyEvidence();

  const SkyGrid& grid() const;
  int num_samples() const;
  // Sample pixels (OpenCV), n x 2.
  std::vector<Eigen::Vector2f> sample_pixels() const;
  double build_seconds() const;
  // Band samples looked up per frame, all directions together (the
  // per-frame cost).
  int64_t band_entries() const;

  // The reference level of every sample from frames spread over the clip
  // (CV_32F linear gray, the camera's size; empty Mats are skipped). Needs
  // at least one usable frame; returns how many were used.
  int SetReference(const std::vector<cv::Mat>& frames);
  bool has_reference() const;

  // Scores one frame (empty Mat: not decodable) against every direction and
  // keeps the costs for the path (sun_path.h), in the order given.
  // explained_out, when not null, receives each direction's explained share.
  FrameEvidence AddFrame(const cv::Mat& frame,
                         std::vector<float>* explained_out = nullptr);
  int num_frames() const;
  // Room for `more` frames' costs, allocated once rather than grown by
  // doubling (each doubling copies every cost so far: 30 MB at 10,000
  // frames).
  void ReserveFrames(int more);
  // Cost of each direction on frame k (log-likelihood below the frame's best
  // direction; 0 everywhere on a frame without evidence), as kept: quantised
  // to 0.1 and clipped at 25.5 (a frame never weighs more than that).
  std::vector<float> Cost(int k) const;
  double BestExplained(int k) const;
  double Significance(int k) const;
  // All kept costs, frames x directions, in tenths.
  const std::vector<uint8_t>& scores() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sunlapse
