#include "sunlapse/video/video_reader.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <regex>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

namespace sunlapse {
namespace fs = std::filesystem;

namespace {
bool IsImageExtension(std::string ext) {
  for (auto& c : ext) c = static_cast<char>(std::tolower(c));
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".tif" ||
         ext == ".tiff" || ext == ".exr" || ext == ".bmp" || ext == ".webp";
}
}  // namespace

VideoReader::VideoReader(const std::string& path) {
  if (!fs::exists(path)) {
    throw std::invalid_argument("path: no such file: " + path);
  }
  const fs::path p(path);
  std::smatch m;
  const std::string name = p.filename().string();
  static const std::regex kNumbered(R"((.*?)(\d+)(\.[A-Za-z]+)$)");
  if (IsImageExtension(p.extension().string()) &&
      std::regex_match(name, m, kNumbered)) {
    is_sequence_ = true;
    prefix_ = (p.parent_path() / m[1].str()).string();
    digits_ = static_cast<int>(m[2].str().size());
    first_number_ = std::stoi(m[2].str());
    suffix_ = m[3].str();
    while (fs::exists(SequencePath(num_frames_))) ++num_frames_;
    cv::Mat first = cv::imread(path, cv::IMREAD_COLOR);
    if (first.empty()) {
      throw std::invalid_argument("path: cannot decode image " + path);
    }
    width_ = first.cols;
    height_ = first.rows;
    fps_ = 0.0;
    return;
  }
  capture_ = std::make_unique<cv::VideoCapture>(path, cv::CAP_FFMPEG);
  if (!capture_->isOpened()) {
    throw std::invalid_argument("path: cannot open video " + path);
  }
  width_ = static_cast<int>(capture_->get(cv::CAP_PROP_FRAME_WIDTH));
  height_ = static_cast<int>(capture_->get(cv::CAP_PROP_FRAME_HEIGHT));
  fps_ = capture_->get(cv::CAP_PROP_FPS);
  num_frames_ = static_cast<int>(capture_->get(cv::CAP_PROP_FRAME_COUNT));
  if (width_ <= 0 || height_ <= 0) {
    throw std::invalid_argument("path: video has no frames: " + path);
  }
}

VideoReader::~VideoReader() = default;

std::string VideoReader::SequencePath(int index) const {
  char number[32];
  std::snprintf(number, sizeof(number), "%0*d", digits_, first_number_ + index);
  return prefix_ + number + suffix_;
}

bool VideoReader::Read(cv::Mat* bgr) {
  if (is_sequence_) {
    if (position_ >= num_frames_) return false;
    *bgr = cv::imread(SequencePath(position_), cv::IMREAD_COLOR);
    if (!bgr->empty() && (bgr->cols != width_ || bgr->rows != height_)) {
      bgr->release();  // a frame of another size is as unusable as a corrupt
                       // one
    }
    ++position_;
    return true;
  }
  if (!capture_->read(*bgr)) {
    // Containers often over-report their length; the end is where reading
    // stops.
    if (num_frames_ <= 0 || position_ >= num_frames_ - 1) return false;
    bgr->release();
    ++position_;
    return position_ < num_frames_;
  }
  ++position_;
  return true;
}

bool VideoReader::Seek(int index) {
  if (index < 0 || (num_frames_ > 0 && index >= num_frames_)) return false;
  if (!is_sequence_) {
    if (index < position_ || index > position_ + 50) {
      capture_->set(cv::CAP_PROP_POS_FRAMES, index);
      position_ = static_cast<int>(capture_->get(cv::CAP_PROP_POS_FRAMES));
    }
    cv::Mat skip;
    while (position_ < index && capture_->grab())
      ++position_;  // exact, decodes
    if (position_ != index) return false;
  }
  position_ = index;
  return true;
}

cv::Mat ToLinearGray(const cv::Mat& image, double gamma) {
  if (image.empty()) return {};
  cv::Mat gray;
  if (image.channels() == 3) {
    cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
  } else if (image.channels() == 4) {
    cv::cvtColor(image, gray, cv::COLOR_BGRA2GRAY);
  } else {
    gray = image;
  }
  cv::Mat out;
  const double scale = gray.depth() == CV_8U    ? 1.0 / 255.0
                       : gray.depth() == CV_16U ? 1.0 / 65535.0
                                                : 1.0;
  gray.convertTo(out, CV_32F, scale);
  if (gamma != 1.0) cv::pow(out, gamma, out);
  return out;
}

}  // namespace sunlapse
