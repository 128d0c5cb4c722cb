#include "sunlapse/whole_clip/clip_pass.h"

#include <chrono>
#include <stdexcept>
#include <utility>

#include "sunlapse/common/angles.h"

namespace sunlapse {

void ClipPassOptions::Check() const {
  if (!(start_margin >= 0.0))
    throw std::invalid_argument("start_margin must be >= 0");
  if (!(steer_deg > 0.0 && steer_deg <= 180.0))
    throw std::invalid_argument("steer_deg must be in (0, 180]");
  if (progress_every < 1)
    throw std::invalid_argument("progress_every must be >= 1");
  if (!(keep_off_deg >= 0.0))
    throw std::invalid_argument("keep_off_deg must be >= 0");
  if (keep_max_frames < 0)
    throw std::invalid_argument("keep_max_frames must be >= 0");
}

bool StartTracker(ShadowTracker* tracker, const cv::Mat& frame,
                  const Eigen::Vector3d& sun_in_world, double refine_max_deg,
                  TrackedFrame* refined) {
  *refined = TrackedFrame();
  if (!tracker->Initialize(frame, sun_in_world).ok) return false;
  TrackedFrame r = tracker->Track(frame, sun_in_world);
  if (r.ok && AngleBetweenDeg(r.sun_in_world, sun_in_world) <= refine_max_deg) {
    const Eigen::Vector3d first = r.sun_in_world;
    tracker->Initialize(frame, first);
    r = tracker->Track(frame, first);
  }
  r.ok =
      r.ok && AngleBetweenDeg(r.sun_in_world, sun_in_world) <= refine_max_deg;
  *refined = std::move(r);
  return true;
}

cv::Mat ClipPassFrame::Kept() const {
  if (kept_luma.empty()) return kept_gray;
  cv::Mat gray;
  cv::LUT(kept_luma, kept_table, gray);
  return gray;
}

ClipPassResult RunClipPass(FrameSource* source,
                           const std::vector<int>& source_index,
                           const std::vector<cv::Mat>& kept,
                           const std::vector<uint8_t>& segment_start,
                           const Camera& camera, SkyEvidence* sky,
                           ShadowTracker* tracker,
                           const ClipPassOptions& options,
                           const std::function<bool(double)>& progress) {
  options.Check();
  const size_t n = kept.size();
  if (source_index.size() != n ||
      (!segment_start.empty() && segment_start.size() != n))
    throw std::invalid_argument(
        "source_index, kept and segment_start: one per frame");
  const auto t0 = std::chrono::steady_clock::now();
  ClipPassResult out;
  out.frames.resize(n);
  sky->ReserveFrames(static_cast<int>(n));
  const SkyGrid& grid = sky->grid();
  bool following = false;
  int kept_frames = 0;
  // Keeps the frame when the check is likely to want it again: its 8-bit
  // luma when the source gave it (exact, a quarter of the float frame).
  cv::Mat luma, table;
  auto keep_if_doubtful = [&](ClipPassFrame* pf, const cv::Mat& frame) {
    const FrameEvidence& e = pf->evidence;
    const bool doubtful =
        !pf->tracked || (e.best_direction >= 0 &&
                         AngleBetweenDeg(pf->track.sun_in_world,
                                         grid.direction(e.best_direction)) >
                             options.keep_off_deg);
    if (doubtful && kept_frames < options.keep_max_frames) {
      if (!luma.empty()) {
        pf->kept_luma = luma;  // the source's own, handed over
        pf->kept_table = table;
      } else {
        pf->kept_gray = frame.clone();  // never a view of the caller's frames
      }
      ++kept_frames;
    }
  };
  for (size_t k = 0; k < n; ++k) {
    if (progress && k % options.progress_every == 0 &&
        !progress(static_cast<double>(k) / n)) {
      out.status = ClipPassResult::Status::kCancelled;
      out.message = "cancelled";
      out.frames.resize(k);
      return out;
    }
    ClipPassFrame& pf = out.frames[k];
    cv::Mat gray;
    luma.release();
    table.release();
    if (!kept[k].empty()) {
      gray = kept[k];
      pf.index = source_index[k];
    } else {
      StreamedFrame f;
      if (!source->Next(&f) || f.index != source_index[k]) {
        throw std::runtime_error("the frame source gave another frame than " +
                                 std::to_string(source_index[k] + 1));
      }
      pf.index = f.index;
      if (f.status != StreamedFrame::Status::kOk) {
        pf.read_message = f.message.empty() ? "frame not decodable" : f.message;
      } else if (f.gray.cols != camera.width() ||
                 f.gray.rows != camera.height()) {
        pf.read_message = "frame is " + std::to_string(f.gray.cols) + "x" +
                          std::to_string(f.gray.rows) + ", not the camera's " +
                          std::to_string(camera.width()) + "x" +
                          std::to_string(camera.height()) +
                          ": not the scene's footage";
      } else {
        gray = std::move(f.gray);
        luma = std::move(f.luma);
        table = std::move(f.table);
      }
    }
    pf.evidence = sky->AddFrame(gray);
    if (!segment_start.empty() && segment_start[k]) following = false;
    const FrameEvidence& e = pf.evidence;
    if (gray.empty() || (e.status != FrameEvidence::Status::kOk &&
                         e.status != FrameEvidence::Status::kNoShadows))
      continue;
    const bool sure = e.status == FrameEvidence::Status::kOk &&
                      e.best_direction >= 0 && e.margin >= options.start_margin;
    if (!following) {
      if (sure) {
        const auto start = std::chrono::steady_clock::now();
        following =
            StartTracker(tracker, gray, grid.direction(e.best_direction),
                         options.steer_deg, &pf.track);
        out.start_seconds += std::chrono::duration<double>(
                                 std::chrono::steady_clock::now() - start)
                                 .count();
        pf.tracked = following && pf.track.ok;
        out.tracker_started = out.tracker_started || following;
        out.tracking_seconds += pf.track.seconds;
      }
      keep_if_doubtful(&pf, gray);
      continue;
    }
    // A frame where the tracker loses the shadow (a cloud, a person) does
    // not stop it: it widens its own search on the next ones.
    TrackedFrame r = tracker->Track(gray);
    out.tracking_seconds += r.seconds;
    if (sure) {
      const Eigen::Vector3d& best = grid.direction(e.best_direction);
      if (!r.ok || AngleBetweenDeg(r.sun_in_world, best) > options.steer_deg) {
        // The frame's own evidence is unmistakable and elsewhere: the
        // tracker has drifted; steer it back (the path checks again).
        r = tracker->Track(gray, best);
        out.tracking_seconds += r.seconds;
      }
    }
    pf.tracked = r.ok;
    pf.track = std::move(r);
    keep_if_doubtful(&pf, gray);
  }
  if (progress) progress(1.0);
  out.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0)
          .count();
  return out;
}

}  // namespace sunlapse
