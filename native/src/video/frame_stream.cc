#include "sunlapse/video/frame_stream.h"

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <exception>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <utility>

#include <opencv2/core.hpp>

namespace sunlapse {

void FrameStreamOptions::Check() const {
  if (queue_frames < 1 || queue_frames > 64)
    throw std::invalid_argument("queue_frames must be in [1, 64]");
  if (near_min_frames < 1)
    throw std::invalid_argument("near_min_frames must be >= 1");
  if (!(gamma > 0.0 && gamma <= 10.0))
    throw std::invalid_argument("gamma must be in (0, 10]");
  if (width < 0 || height < 0 || (width == 0) != (height == 0))
    throw std::invalid_argument(
        "width and height must both be > 0, or both 0 (the decoded size)");
  if (bgr_width < 0 || bgr_height < 0 || (bgr_width == 0) != (bgr_height == 0))
    throw std::invalid_argument(
        "bgr_width and bgr_height must both be > 0, or both 0 (the decoded "
        "size)");
}

struct FrameStream::Impl {
  FrameStreamOptions options;
  std::vector<int> indices;
  VideoReader reader;
  std::mutex mutex;
  std::condition_variable ready, space;
  std::deque<StreamedFrame> queue;
  size_t handed = 0;   // frames given to the consumer
  int last_near = -1;  // the last frame decoded (near: never twice)
  bool stop = false;
  double wait_seconds = 0.0;
  std::thread thread;

  Impl(const std::string& path, std::vector<int> idx,
       const FrameStreamOptions& o)
      : options(o),
        indices(std::move(idx)),
        reader(path),
        table(LinearGrayTable(o.gamma)) {}

  // Float frames whose consumers have let go are filled again: a fresh
  // 8 MB buffer per 1080p frame cost as much as the conversion itself (page
  // faults). A buffer is free when the pool holds its only reference.
  std::vector<cv::Mat> pool;
  cv::Mat table;  // 8-bit value -> linear float

  cv::Mat Recycled(int rows, int cols) {
    for (const cv::Mat& m : pool) {
      if (m.rows == rows && m.cols == cols && m.u != nullptr &&
          m.u->refcount == 1)
        return m;
    }
    cv::Mat m(rows, cols, CV_32F);
    if (pool.size() < static_cast<size_t>(options.queue_frames) + 4)
      pool.push_back(m);
    return m;
  }

  StreamedFrame Decode(int index) {
    StreamedFrame f;
    f.index = index;
    // Near: the key frame before the index when it is one not handed out
    // yet (one decode after a seek), else the exact frame.
    const int key = options.near ? reader.KeyFrameAtOrBefore(index) : -1;
    if (key > last_near) {
      f.index = reader.SeekNear(key);
      if (f.index < 0) {
        f.message = "the clip has no frame " + std::to_string(index + 1);
        f.index = index;
        return f;
      }
      last_near = f.index;
    } else if (index < 0 ||
               (reader.position() != index && !reader.Seek(index))) {
      f.message = "the clip has no frame " + std::to_string(index + 1);
      return f;
    }
    // Colour only when asked for, and scaled as it is converted; gray from
    // the decoder's luma (no colour conversion).
    const cv::Size size(options.width, options.height);
    cv::Mat gray8, bgr;
    if (!(options.keep_bgr ? reader.ReadGrayAndBgr(&gray8, size, &bgr,
                                                   cv::Size(options.bgr_width,
                                                            options.bgr_height))
                           : reader.ReadGray(&gray8, size))) {
      f.message = "the clip ended before frame " + std::to_string(f.index + 1);
      return f;
    }
    f.report = reader.last_frame();
    last_near = std::max(last_near, f.index);
    if (gray8.empty()) {
      f.status = StreamedFrame::Status::kUnusable;
      f.message =
          f.report.message.empty() ? "frame not decodable" : f.report.message;
      return f;
    }
    f.status = StreamedFrame::Status::kOk;
    f.gray = Recycled(gray8.rows, gray8.cols);
    cv::LUT(gray8, table, f.gray);
    f.luma = std::move(gray8);
    f.table = table;
    if (options.keep_bgr) f.bgr = std::move(bgr);
    return f;
  }

  void Run() {
    for (int index : indices) {
      StreamedFrame f;
      try {
        f = Decode(index);
      } catch (const std::exception& e) {  // e.g. out of memory on one frame
        f = StreamedFrame();
        f.index = index;
        f.status = StreamedFrame::Status::kUnusable;
        f.message = e.what();
      }
      std::unique_lock<std::mutex> lock(mutex);
      space.wait(lock, [&] {
        return stop || queue.size() < static_cast<size_t>(options.queue_frames);
      });
      if (stop) return;
      queue.push_back(std::move(f));
      ready.notify_one();
    }
  }
};

FrameStream::FrameStream(const std::string& path, std::vector<int> indices,
                         const FrameStreamOptions& options) {
  options.Check();
  impl_ = std::make_unique<Impl>(path, std::move(indices), options);
  if (options.near) {
    // The distinct key frames of the indices, from the container's index
    // (no decoding): enough of them make the frames read.
    std::vector<int> keys;
    bool known = true;
    for (int index : impl_->indices) {
      const int key = impl_->reader.KeyFrameAtOrBefore(index);
      known = known && key >= 0;
      if (key >= 0 && std::find(keys.begin(), keys.end(), key) == keys.end())
        keys.push_back(key);
    }
    if (known && static_cast<int>(keys.size()) >= options.near_min_frames)
      impl_->indices = keys;
  }
  impl_->thread = std::thread([this] { impl_->Run(); });
}

FrameStream::~FrameStream() {
  {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    impl_->stop = true;
  }
  impl_->space.notify_all();
  impl_->thread.join();
}

bool FrameStream::Next(StreamedFrame* frame) {
  Impl& s = *impl_;
  std::unique_lock<std::mutex> lock(s.mutex);
  if (s.handed >= s.indices.size()) return false;
  const auto t0 = std::chrono::steady_clock::now();
  s.ready.wait(lock, [&] { return !s.queue.empty(); });
  s.wait_seconds +=
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0)
          .count();
  *frame = std::move(s.queue.front());
  s.queue.pop_front();
  ++s.handed;
  s.space.notify_one();
  return true;
}

double FrameStream::wait_seconds() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->wait_seconds;
}

int FrameStream::width() const { return impl_->reader.width(); }
int FrameStream::size() const {
  return static_cast<int>(impl_->indices.size());
}
int FrameStream::height() const { return impl_->reader.height(); }

}  // namespace sunlapse
