// A moving camera's frames seen from one fixed view (issue 26).
//
// Everything the estimate measures lives on the model's surfaces: the sky
// table's samples, the tracker's ground, the reference levels. With a fixed
// camera each surface point stays on one pixel. With a camera that moves
// (a slider, a pan head, a solved motion-control shot) the point moves in
// the image, but the model says where: the reference view's pixel p sees
// the surface point X(p), and frame k shows X(p) at its camera's projection
// of X(p), when nothing in the model hides it from that camera. So each
// frame is resampled into the reference view, and the estimate runs on the
// resampled frames as on a fixed camera's. Points the frame does not see
// (outside its image, hidden behind another part of the model) come out NaN:
// the evidence and the tracker leave them out on that frame.
//
// Resampling is bilinear: at a working size of at most 1280 pixels, a
// shadow edge blurs by under half a pixel, less than the reduction already
// does.
#pragma once

#include <condition_variable>
#include <deque>
#include <exception>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "sunlapse/scene/camera.h"
#include "sunlapse/scene/scene.h"
#include "sunlapse/video/frame_stream.h"

namespace sunlapse {

struct ViewWarpOptions {
  // A frame is used when it sees at least this share of the model surface
  // the reference view sees; below, it is reported out of view.
  double min_seen_share = 0.2;
  // A surface point is hidden from a frame's camera when the model is this
  // much nearer than the point along the camera's ray toward it (share of
  // the distance; a grazing wall's depth varies within a pixel).
  double hidden_share = 0.01;
  // The frame camera's distance to the model is cast on every depth_step-th
  // pixel of the frame and interpolated between (pixels; 1: every pixel).
  // Behind an outline a band of up to this many pixels is left out.
  int depth_step = 8;
  void Check() const;
};

struct ViewWarpResult {
  enum class Status {
    kOk,         // the frame was resampled into the reference view
    kOutOfView,  // the frame sees too little of the model (message says)
    kNoFrame,    // no frame was given (not decodable)
  };
  Status status = Status::kNoFrame;
  std::string message;
  // Share of the reference view's model pixels the frame sees.
  double seen_share = 0.0;
};

class ViewWarp {
 public:
  // The scene must outlive this. Casts one ray per pixel of the reference
  // camera. Throws std::invalid_argument on bad options or when the
  // reference camera sees no model surface.
  ViewWarp(const Scene& scene, const Camera& reference,
           const ViewWarpOptions& options = {});
  ~ViewWarp();
  ViewWarp(const ViewWarp&) = delete;
  ViewWarp& operator=(const ViewWarp&) = delete;

  const Camera& reference() const;
  // Pixels of the reference view that see the model.
  int model_pixels() const;

  // Work buffers one caller keeps from frame to frame.
  struct Scratch {
    std::vector<Eigen::Vector2d> grid;  // for grid_size's frames
    Eigen::Vector2i grid_size{0, 0};
    std::vector<float> depth;
    std::vector<Eigen::Vector2f> at;
    std::vector<uint8_t> outline;
    std::vector<int> cast;
    std::vector<float> origins, directions, distance;  // rays near outlines
  };

  // Frame (CV_32F gray of `camera`'s size, or empty) taken by `camera` ->
  // *out, CV_32F of the reference camera's size, NaN where the frame does
  // not see the reference pixel's surface point (and where the reference
  // view sees no model). Thread-safe with a scratch per thread (none: its
  // own, allocated for the call).
  ViewWarpResult Warp(const cv::Mat& frame, const Camera& camera, cv::Mat* out,
                      Scratch* scratch = nullptr) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// A FrameSource whose frames come resampled into a ViewWarp's reference
// view: the frame with index i from `inner` was taken by cameras[i]. A
// frame without a camera comes out unusable with why_not[i] (when given and
// not empty) as its reason, one out of view with the warp's. Frames are
// read from `inner` and resampled ahead on a thread of its own, at most
// queue_frames of them waiting (0: in Next, on the caller's thread), so
// that resampling overlaps with the caller's work on the frame before.
// Both must outlive this; `inner` is read from that thread only.
class WarpedSource : public FrameSource {
 public:
  WarpedSource(FrameSource* inner, const ViewWarp* warp,
               std::vector<std::optional<Camera>> cameras_by_index,
               std::vector<std::string> why_not = {}, int queue_frames = 2);
  // Stops the thread (the frame being resampled is finished first).
  ~WarpedSource();
  WarpedSource(const WarpedSource&) = delete;
  WarpedSource& operator=(const WarpedSource&) = delete;
  // Rethrows what reading or resampling threw, in order.
  bool Next(StreamedFrame* frame) override;
  // Seconds spent resampling so far.
  double seconds() const;

 private:
  bool Produce(StreamedFrame* frame);
  void Work();

  FrameSource* inner_;
  const ViewWarp* warp_;
  std::vector<std::optional<Camera>> cameras_;
  std::vector<std::string> why_not_;
  int queue_frames_;
  ViewWarp::Scratch scratch_;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<StreamedFrame> queue_;
  bool done_ = false, stop_ = false;
  std::exception_ptr error_;
  double seconds_ = 0.0;
  std::thread worker_;
};

}  // namespace sunlapse
