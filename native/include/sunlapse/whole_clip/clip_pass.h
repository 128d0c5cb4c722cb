// The pass over a clip of the whole-clip estimator: every frame decoded once
// (read ahead by a FrameSource), scored against the whole sky (SkyEvidence)
// and followed by the shadow tracker on the same frame, in native code
// without Python's lock. The global path (sun_path.h) and the check of the
// tracked Suns against it come after (addon/estimate/whole_clip.py).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "sunlapse/scene/camera.h"
#include "sunlapse/sky/sky_evidence.h"
#include "sunlapse/tracking/shadow_tracker.h"
#include "sunlapse/video/frame_stream.h"

namespace sunlapse {

struct ClipPassOptions {
  // The tracker starts on the first frame whose own evidence leads every
  // far direction by this much (log-likelihood units): a wrong start costs
  // only a second reading of the frames it spoilt.
  double start_margin = 6.0;
  // A tracked Sun further than this from a frame's unmistakable evidence
  // has drifted: it is searched for again around the evidence (deg).
  double steer_deg = 8.0;
  // The progress callback is called every this many frames.
  int progress_every = 8;
  // Frames the check after the path is likely to read again are kept (at
  // most keep_max_frames of them, copies): those with usable evidence the
  // tracker did not follow, or whose tracked Sun is further than
  // keep_off_deg from the frame's own best direction. Reading a frame of a
  // long-GOP movie again decodes from its key frame: at 4K, half a second a
  // frame. Kept exact: as half floats, the refinement of the Marseille
  // January clip's sunset frames came out degrees apart.
  double keep_off_deg = 3.0;
  int keep_max_frames = 32;
  void Check() const;
};

struct ClipPassFrame {
  int index = -1;            // as the source said
  std::string read_message;  // why the frame could not be used (empty: read)
  FrameEvidence evidence;
  bool tracked = false;  // `track` holds the tracker's Sun on the frame
  TrackedFrame track;
  // The frame as tracked, when kept (ClipPassOptions): the source's 8-bit
  // luma and its table to linear gray when it gave them (StreamedFrame),
  // else the float frame.
  cv::Mat kept_luma, kept_table, kept_gray;
  // The kept frame as CV_32F linear gray; empty when not kept.
  cv::Mat Kept() const;
};

struct ClipPassResult {
  enum class Status {
    kSuccess,
    kCancelled,  // the progress callback asked to stop
  };
  Status status = Status::kSuccess;
  std::string message;
  std::vector<ClipPassFrame> frames;
  bool tracker_started = false;  // on some frame of the pass
  double tracking_seconds = 0.0;
  double start_seconds = 0.0;  // starting the tracker (its ground map, ...)
  double seconds = 0.0;
};

// The tracker started on `frame` under a grid direction, then refined there
// and started again from the refined Sun (it takes the ground's albedo from
// the frame under the Sun it is given; the grid cell's shadows are a little
// off). Returns whether it started; *refined gets its Sun on the frame when
// within refine_max_deg of the direction (else ok=false).
bool StartTracker(ShadowTracker* tracker, const cv::Mat& frame,
                  const Eigen::Vector3d& sun_in_world, double refine_max_deg,
                  TrackedFrame* refined);

// Runs the pass over `count` frames: frame k is kept[k] when that is not
// empty (frames already read), else the source's next one, which must have
// index source_index[k]. segment_start[k] = 1 where the clip is known to
// jump (capture times going back): the tracker starts again after it.
// progress(fraction) returning false cancels. The camera gives the size
// every frame must have (the sky's and the tracker's: a large clip's frames
// come reduced by the source, FrameStreamOptions::width).
ClipPassResult RunClipPass(FrameSource* source,
                           const std::vector<int>& source_index,
                           const std::vector<cv::Mat>& kept,
                           const std::vector<uint8_t>& segment_start,
                           const Camera& camera, SkyEvidence* sky,
                           ShadowTracker* tracker,
                           const ClipPassOptions& options,
                           const std::function<bool(double)>& progress);

}  // namespace sunlapse
