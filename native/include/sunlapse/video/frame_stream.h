// Frames decoded ahead on a thread of their own, so that decoding a clip
// overlaps with estimating on it, and converted there to what the estimate
// reads (linear gray). The queue between the two is bounded: memory holds a
// few frames whatever the clip's length.
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "sunlapse/video/video_reader.h"

namespace sunlapse {

struct FrameStreamOptions {
  // Decoded frames waiting for the consumer at most.
  int queue_frames = 3;
  // Linear gray is value^gamma (ToLinearGray).
  double gamma = kDisplayGamma;
  // Also hand out the 8-bit BGR frame (for a colour background), scaled to
  // bgr_width x bgr_height as it is converted (0 x 0: the decoded size).
  bool keep_bgr = false;
  int bgr_width = 0, bgr_height = 0;
  // Frames need not be exact (samples spread over the clip): each is the
  // key frame at or before the index asked when that is one not handed out
  // yet (one decode after a seek, VideoReader::SeekNear), else the exact
  // frame; `index` says which. When the clip has at least near_min_frames
  // distinct key frames for the indices asked, only those key frames are
  // read (fewer frames than asked, each costing one decode); else each
  // index gives one frame as above.
  bool near = false;
  int near_min_frames = 8;
  // The gray frames' size: reduced by area averaging (AreaReduced) from the
  // decoded 8-bit luma, before linearising; 0 x 0 keeps the decoded size.
  // Reducing first costs a fraction of linearising the whole frame.
  int width = 0, height = 0;
  // Threads decoding an image sequence's frames side by side (its images
  // are independent; a movie's frames are not, and FFmpeg threads its own
  // decoder): 0 one per core. Frames still come out in order, and at most
  // queue_frames + decode_threads are held at once.
  int decode_threads = 0;
  void Check() const;
};

struct StreamedFrame {
  enum class Status {
    kOk,        // gray (and bgr when asked) hold the frame
    kUnusable,  // the reader could not give it (report says why)
    kPastEnd,   // the clip has no such frame
  };
  int index = -1;  // 0-based clip index (as asked, unless near)
  Status status = Status::kPastEnd;
  FrameReport report;   // the reader's own report of the frame
  std::string message;  // why not, for kUnusable and kPastEnd
  cv::Mat gray;         // CV_32F linear gray (options' size), kOk only
  // The 8-bit luma gray was made from, gray = LUT(luma, table) (FrameStream
  // only; other sources leave them empty): a quarter of gray's memory for a
  // frame to be kept, and exact.
  cv::Mat luma, table;
  cv::Mat bgr;  // CV_8UC3 (options' bgr size), kOk with keep_bgr only
};

// Where a pass over a clip takes its frames from, one after another.
class FrameSource {
 public:
  virtual ~FrameSource() = default;
  // The next frame; false after the last.
  virtual bool Next(StreamedFrame* frame) = 0;
};

// Frames already in memory (tests, synthetic clips).
class FrameList : public FrameSource {
 public:
  explicit FrameList(std::vector<StreamedFrame> frames)
      : frames_(std::move(frames)) {}
  bool Next(StreamedFrame* frame) override {
    if (next_ >= frames_.size()) return false;
    *frame = std::move(frames_[next_++]);
    return true;
  }

 private:
  std::vector<StreamedFrame> frames_;
  size_t next_ = 0;
};

class FrameStream : public FrameSource {
 public:
  // Reads `indices` (0-based clip frames, in that order; consecutive ones
  // without seeking) on a thread of its own. Throws std::invalid_argument
  // like VideoReader, or for bad options.
  FrameStream(const std::string& path, std::vector<int> indices,
              const FrameStreamOptions& options);
  // Stops the thread (the frame being decoded is finished first).
  ~FrameStream();
  FrameStream(const FrameStream&) = delete;
  FrameStream& operator=(const FrameStream&) = delete;

  // The next frame in the order asked; false after the last. Blocks until it
  // is decoded. size() frames in all.
  bool Next(StreamedFrame* frame) override;
  // Seconds Next() spent waiting for the decoder so far (the consumer idle:
  // decoding is the bottleneck when this is most of the run).
  double wait_seconds() const;
  // The clip's frames decode on their own (VideoReader::frames_independent).
  bool frames_independent() const;
  int width() const;
  int height() const;
  // How many frames Next() gives in all.
  int size() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sunlapse
