#include "sunlapse/video/frame_stream.h"

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <exception>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
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
  if (decode_threads < 0 || decode_threads > 16)
    throw std::invalid_argument(
        "decode_threads must be in [0, 16] (0: one per core)");
  if (bgr_width < 0 || bgr_height < 0 || (bgr_width == 0) != (bgr_height == 0))
    throw std::invalid_argument(
        "bgr_width and bgr_height must both be > 0, or both 0 (the decoded "
        "size)");
}

struct FrameStream::Impl {
  FrameStreamOptions options;
  std::string path;
  std::vector<int> indices;
  VideoReader reader;
  std::mutex mutex;
  std::condition_variable ready, space;
  std::deque<StreamedFrame> queue;
  size_t handed = 0;   // frames given to the consumer
  size_t taken = 0;    // frames a decoding thread has started on
  size_t queued = 0;   // frames put in the queue (in order)
  int last_near = -1;  // the last frame decoded (near: never twice)
  // Near, with enough key frames: the indices are distinct key frames, each
  // decoded alone after a seek, so several readers share them out.
  bool keys_only = false;
  bool stop = false;
  double wait_seconds = 0.0;
  int decoders = 1;  // decoding threads (set before any starts)
  std::vector<std::thread> threads;

  Impl(const std::string& p, std::vector<int> idx, const FrameStreamOptions& o)
      : options(o),
        path(p),
        indices(std::move(idx)),
        reader(p, !o.keep_bgr),
        table(LinearGrayTable(o.gamma)) {}

  // Float frames whose consumers have let go are filled again: a fresh
  // 8 MB buffer per 1080p frame cost as much as the conversion itself (page
  // faults). A buffer is free when the pool holds its only reference.
  std::mutex pool_mutex;
  std::vector<cv::Mat> pool;
  cv::Mat table;  // 8-bit value -> linear float

  cv::Mat Recycled(int rows, int cols) {
    std::lock_guard<std::mutex> lock(pool_mutex);
    for (const cv::Mat& m : pool) {
      if (m.rows == rows && m.cols == cols && m.u != nullptr &&
          m.u->refcount == 1)
        return m;
    }
    cv::Mat m(rows, cols, CV_32F);
    if (pool.size() < static_cast<size_t>(options.queue_frames + 4 + decoders))
      pool.push_back(m);
    return m;
  }

  // `r`: this thread's reader. `near`: the near rule applies (one thread).
  StreamedFrame Decode(VideoReader& r, int index, bool near) {
    StreamedFrame f;
    f.index = index;
    // Near: the key frame before the index when it is one not handed out
    // yet (one decode after a seek), else the exact frame.
    const int key = near && !keys_only ? r.KeyFrameAtOrBefore(index) : -1;
    if (keys_only) {
      f.index = r.SeekNear(index);
      if (f.index < 0) {
        f.message = "the clip has no frame " + std::to_string(index + 1);
        f.index = index;
        return f;
      }
    } else if (key > last_near) {
      f.index = r.SeekNear(key);
      if (f.index < 0) {
        f.message = "the clip has no frame " + std::to_string(index + 1);
        f.index = index;
        return f;
      }
      last_near = f.index;
    } else if (index < 0 || (r.position() != index && !r.Seek(index))) {
      f.message = "the clip has no frame " + std::to_string(index + 1);
      return f;
    }
    // Colour only when asked for, and scaled as it is converted; gray from
    // the decoder's luma (no colour conversion).
    const cv::Size size(options.width, options.height);
    cv::Mat gray8, bgr;
    if (!(options.keep_bgr ? r.ReadGrayAndBgr(&gray8, size, &bgr,
                                              cv::Size(options.bgr_width,
                                                       options.bgr_height))
                           : r.ReadGray(&gray8, size))) {
      f.message = "the clip ended before frame " + std::to_string(f.index + 1);
      return f;
    }
    f.report = r.last_frame();
    if (near && !keys_only) last_near = std::max(last_near, f.index);
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

  StreamedFrame SafeDecode(VideoReader& r, int index, bool near) {
    try {
      return Decode(r, index, near);
    } catch (const std::exception& e) {  // e.g. out of memory on one frame
      StreamedFrame f;
      f.index = index;
      f.status = StreamedFrame::Status::kUnusable;
      f.message = e.what();
      return f;
    }
  }

  // One decoding thread: takes the next frame not started, decodes it, and
  // queues it in its turn (a thread ahead waits for the ones before).
  void Run(VideoReader& r, bool near) {
    while (true) {
      size_t k;
      {
        std::lock_guard<std::mutex> lock(mutex);
        if (stop || taken >= indices.size()) return;
        k = taken++;
      }
      StreamedFrame f = SafeDecode(r, indices[k], near);
      std::unique_lock<std::mutex> lock(mutex);
      space.wait(lock, [&] {
        return stop ||
               (queued == k &&
                queue.size() < static_cast<size_t>(options.queue_frames));
      });
      if (stop) return;
      queue.push_back(std::move(f));
      ++queued;
      ready.notify_one();
      space.notify_all();  // the thread with the next frame may go on
    }
  }

  void Start() {
    // An image sequence's frames decode side by side, each thread with its
    // own reader; so do a long-GOP movie's lone key frames (a decoder's
    // frame threads give one frame a single core). Other movies' frames in
    // one thread: its decoder has threads (an intra-only codec's slice
    // threads put every core on each frame, and a second 4K ProRes reader
    // made its reference frames slower: 1.5 -> 1.9 s).
    int n = 1;
    if (reader.is_sequence() || (keys_only && !reader.frames_independent())) {
      const int cores =
          std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
      n = options.decode_threads > 0 ? options.decode_threads : cores;
      n = std::max(1, std::min<int>(n, static_cast<int>(indices.size())));
    }
    decoders = n;
    const bool near = options.near && (n == 1 || keys_only);
    threads.emplace_back([this, near] { Run(reader, near); });
    // The other readers open on their own threads (a movie's: a probe and a
    // first frame each), the first decoding meanwhile. One that cannot open
    // leaves its share to the others.
    for (int t = 1; t < n; ++t) {
      threads.emplace_back([this, near] {
        std::unique_ptr<VideoReader> own;
        try {
          own = std::make_unique<VideoReader>(path, !options.keep_bgr);
        } catch (const std::exception&) {
          return;
        }
        Run(*own, near);
      });
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
    if (known && static_cast<int>(keys.size()) >= options.near_min_frames) {
      impl_->indices = keys;
      impl_->keys_only = true;
    }
  }
  impl_->Start();
}

FrameStream::~FrameStream() {
  {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    impl_->stop = true;
  }
  impl_->space.notify_all();
  for (std::thread& t : impl_->threads) t.join();
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
  s.space.notify_all();  // the thread holding the next frame waits on it
  return true;
}

double FrameStream::wait_seconds() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->wait_seconds;
}

int FrameStream::width() const { return impl_->reader.width(); }
bool FrameStream::frames_independent() const {
  return impl_->reader.frames_independent();
}
int FrameStream::size() const {
  return static_cast<int>(impl_->indices.size());
}
int FrameStream::height() const { return impl_->reader.height(); }

}  // namespace sunlapse
