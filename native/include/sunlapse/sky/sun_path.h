// The Sun's path over a clip, chosen globally from every frame's evidence.
//
// A Viterbi search over the sky grid: each frame's cost is how much less its
// evidence explains than its best direction, each step's cost grows with the
// angle the Sun moves (bounded by how far it can move in the time between the
// two frames: 15 deg per hour, or a generous bound when times are unknown).
// No frame decides alone: an ambiguous or broken frame is carried by its
// neighbours, and a wrong start cannot propagate. A time jump the caller does
// not know of (a looped clip, a missing night) is allowed as a costly jump
// anywhere, and reported so smoothing never crosses it.
//
// Departure from the thesis: the thesis estimates the Sun once on frame 1 and
// tracks it frame by frame; a bad first frame or one lost frame derails it.
#pragma once

#include <string>
#include <vector>

#include "sunlapse/sky/sky_evidence.h"

namespace sunlapse {

struct SunPathOptions {
  // Weight of the evidence's costs (sky_evidence.h: log-likelihood units).
  double evidence_weight = 1.0;
  // Cost of a step of the whole allowed radius (grows with its square).
  double step_weight = 0.1;
  // Cost of a jump beyond the allowed radius (a time jump in the clip).
  // Negative: jumps are not allowed.
  double jump_cost = 40.0;
  // Largest Sun motion per frame when the frames' times are unknown (deg).
  double max_step_deg = 12.0;
  // Apparent angular speed bound of the Sun (deg per hour) when times are
  // known, plus the grid's quantisation (1.5 spacings) as slack.
  double max_speed_deg_per_hour = 15.5;
  // A frame counts as measured when its evidence is significant (its best
  // direction beats no shadows by this much) and the chosen direction leads
  // every direction rival_exclusion_deg away by min_margin (log-likelihood).
  double min_significance = 4.0;
  double min_margin = 2.0;
  double rival_exclusion_deg = 12.0;
  // A prior direction per frame (SolveSunPath's `prior`, e.g. the Sun's
  // small circle about the pole fitted to a first path): a direction further
  // than prior_tolerance_deg from it costs prior_weight per squared degree
  // beyond, at most prior_max_cost (log-likelihood units, as a frame's
  // evidence: sky_evidence.h clips those at 25.5). The sky's evidence along
  // a long thin shadow ranks grid cells by how well their azimuth matches
  // it, whatever their zenith; the Sun's path over the clip does not zigzag.
  double prior_tolerance_deg = 2.0;
  double prior_weight = 1.0;
  double prior_max_cost = 25.0;
  // The forward pass's costs and back-pointers (9 bytes a frame and
  // direction) are kept for the whole clip when they take at most this many
  // MB: the backtrack then reads them, a third of a solve saved. Beyond, the
  // pass keeps a checkpoint every 64 frames and recomputes each block from
  // it on the way back, so that memory stays flat in the clip's length. The
  // path is the same either way. 0: always checkpoints.
  double keep_forward_mb = 32.0;

  void Check() const;
};

struct SunPathResult {
  enum class Status {
    kSuccess,     // a path through every frame
    kNoEvidence,  // no frame has evidence for any direction
  };
  Status status = Status::kNoEvidence;
  std::string message;
  // Per frame: grid direction (-1 when the segment has no evidence at all),
  // whether a jump (unknown time jump) or a segment start precedes it, and
  // whether the frame's own evidence supports the chosen direction.
  std::vector<int> direction;
  std::vector<uint8_t> jump_before;
  std::vector<uint8_t> measured;
  // Per frame: the best explained share of the frame (0..1), and the chosen
  // direction's lead over the best direction rival_exclusion_deg away from it
  // (log-likelihood; negative when a far direction fits the frame better).
  std::vector<float> explained;
  std::vector<float> margin;
  std::vector<float> significance;
  // Per frame: how much more the best whole path through a direction
  // rival_exclusion_deg away costs than the chosen path (log-likelihood):
  // the frame's support including its neighbours'.
  std::vector<float> path_margin;
  double cost = 0.0;
};

// frames: the evidence's frames in order; times_s: each frame's capture time
// in seconds (NaN when unknown); segment_start: 1 where the caller knows the
// clip jumps (capture times going back, a cut) and no step is taken;
// prior: none, or one unit vector toward the Sun per frame in the world
// frame (a non-finite one: no prior on that frame), added to the frames'
// costs as options.prior_* say. Margins and `measured` stay the evidence's
// own; path_margin includes the prior. ignored: none, or 1 per frame whose
// evidence is not to be used (found without direct sunlight: ambient
// shading resembles a high Sun's shadows): such a frame is carried, as one
// without evidence.
SunPathResult SolveSunPath(const SkyEvidence& evidence,
                           const std::vector<double>& times_s,
                           const std::vector<uint8_t>& segment_start,
                           const SunPathOptions& options,
                           const std::vector<Eigen::Vector3d>& prior = {},
                           const std::vector<uint8_t>& ignored = {});

}  // namespace sunlapse
