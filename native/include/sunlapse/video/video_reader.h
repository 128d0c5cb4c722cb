// Frames from a movie file or a numbered image sequence, streamed one by one
// (memory does not grow with the clip's length).
#pragma once

#include <memory>
#include <string>

#include <opencv2/core.hpp>

namespace cv {
class VideoCapture;
}  // namespace cv

namespace sunlapse {

class VideoReader {
 public:
  // `path`: a movie file, or the first image of a numbered sequence
  // (frame_0001.png, as Blender's MovieClip stores it). Throws
  // std::invalid_argument when the file is missing or cannot be decoded.
  explicit VideoReader(const std::string& path);
  ~VideoReader();

  int width() const { return width_; }
  int height() const { return height_; }
  double fps() const { return fps_; }
  // Number of frames (as the container reports it for movies).
  int num_frames() const { return num_frames_; }
  // 0-based index of the frame the next Read() returns.
  int position() const { return position_; }
  bool is_sequence() const { return is_sequence_; }

  // Reads the next frame as 8-bit BGR. Returns false at the end; a frame that
  // cannot be decoded comes back as an empty Mat with true (the caller
  // decides how to treat a corrupt frame) and reading goes on.
  bool Read(cv::Mat* bgr);
  // Moves to 0-based frame `index`; false if out of range.
  bool Seek(int index);

 private:
  std::string SequencePath(int index) const;

  std::unique_ptr<cv::VideoCapture> capture_;
  bool is_sequence_ = false;
  std::string prefix_, suffix_;
  int digits_ = 0, first_number_ = 0;
  int width_ = 0, height_ = 0, num_frames_ = 0, position_ = 0;
  double fps_ = 0.0;
};

// 8-bit BGR (or gray) -> single-channel float32 in [0, 1], with the display
// gamma undone (value^gamma; gamma 1 keeps the encoded values).
cv::Mat ToLinearGray(const cv::Mat& image, double gamma = 2.2);

}  // namespace sunlapse
