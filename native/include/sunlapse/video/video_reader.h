// Frames from a movie file or a numbered image sequence, streamed one by one
// (memory does not grow with the clip's length). Decoding goes through
// FFmpeg's libavformat/libavcodec/libswscale directly, so the module does not
// drag in OpenCV's imgcodecs/videoio (GDAL, GStreamer, camera drivers ...).
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include <opencv2/core.hpp>

#include "sunlapse/video/image_sequence.h"

namespace sunlapse {

class ScaledJpeg;
class PlainTiff;

// The display gamma footage is encoded with (sRGB's, about 2.2): the
// estimate's shading model is linear, so 8-bit values are raised to it.
inline constexpr double kDisplayGamma = 2.2;

// What became of one frame that Read() returned.
enum class FrameStatus {
  kOk = 0,
  kUndecodable,  // the file or packet is corrupt; the frame comes back empty
  kSizeChanged,  // decoded at another size than the first frame; comes back
                 // empty
  kMissingFile,  // a sequence has no file for this number; comes back empty
};

struct FrameReport {
  int index = -1;  // 0-based frame index
  FrameStatus status = FrameStatus::kOk;
  int width = 0, height = 0;  // as decoded (0 when nothing could be decoded)
  std::string message;        // empty for kOk
};

class VideoReader {
 public:
  // Frames larger than this (8192 x 8192) are refused: no footage is, and a
  // tiny corrupt header must not make the reader allocate gigabytes.
  static constexpr int64_t kMaxFramePixels = int64_t{1} << 26;

  // `path`: a movie file, or the first image of a numbered sequence
  // (frame_0001.png, as Blender's MovieClip stores it). Throws
  // std::invalid_argument when the file is missing or cannot be decoded, or
  // its frames are larger than kMaxFramePixels.
  // `gray_only`: the reader will only be asked for gray (ReadGray); a
  // movie's decoder may then skip the colour planes (FFmpeg's ProRes
  // decoder does: a third of its time), and Read / ReadGrayAndBgr throw
  // std::logic_error. Its gray asked for at half the size or less each way
  // skips B-frames' deblocking filter (H.264, HEVC): that gray, and the
  // gray of frames predicted from them, differs from a full decode's by a
  // few levels; key frames' not at all.
  explicit VideoReader(const std::string& path, bool gray_only = false);
  ~VideoReader();
  VideoReader(const VideoReader&) = delete;
  VideoReader& operator=(const VideoReader&) = delete;

  // Size of the first frame, in pixels; every frame must have it.
  int width() const { return width_; }
  int height() const { return height_; }
  double fps() const { return fps_; }
  // Number of frames. Sequences: from the first file's number to the highest
  // number present (gaps included, they read as kMissingFile). Movies: the
  // container's count, or duration x rate when it has none (then
  // num_frames_exact() is false until CountFrames()).
  int num_frames() const { return num_frames_; }
  bool num_frames_exact() const { return num_frames_exact_; }
  // Movies: counts the video packets of the whole file (no decoding) and
  // makes num_frames() exact. Sequences: num_frames(). Does not move the
  // reader.
  int CountFrames();
  // 0-based index of the frame the next Read() returns.
  int position() const { return position_; }
  bool is_sequence() const { return is_sequence_; }
  // Whether each frame decodes on its own (an image sequence, an intra-only
  // codec): skipping frames then saves their decoding, and seeking is cheap.
  bool frames_independent() const;

  // Reads the next frame as 8-bit BGR. Returns false at the end. A frame that
  // cannot be used (corrupt, another size than the first, a file missing from
  // a sequence) comes back as an empty Mat with true, last_frame() says why,
  // and reading goes on.
  bool Read(cv::Mat* bgr);
  // The same as 8-bit gray: the luma as decoded (no colour conversion, video
  // range expanded to 0-255), cheaper than BGR when colour is not needed.
  // `size`, when not empty, reduces the frame to it by area averaging
  // (AreaReduced), straight from the decoder's picture. A sequence's JPEG
  // images are then decoded by TurboJPEG, luma only, at 1/2, 1/4 or 1/8 of
  // their size when every pixel of `size` covers whole blocks of that many
  // (the scaled inverse DCT's block means: the same average), else whole;
  // anything TurboJPEG refuses is decoded by FFmpeg (JpegShrinkFor in
  // jpeg_scaled.h).
  bool ReadGray(cv::Mat* gray, cv::Size size = cv::Size());
  // Both from the same frame: gray as ReadGray, and 8-bit BGR scaled to
  // `bgr_size` (empty: as decoded) by the colour conversion itself, cheaper
  // than converting the whole frame (4K: a fraction of the 8 Mpixel BGR).
  // A sequence's JPEG images, when both sizes reduce: both from one
  // TurboJPEG decode of the Y, Cb, Cr planes at the gray's scaling (the
  // colour, a background, within a block's mean of its geometry).
  bool ReadGrayAndBgr(cv::Mat* gray, cv::Size gray_size, cv::Mat* bgr,
                      cv::Size bgr_size);
  // What the last Read() returned.
  const FrameReport& last_frame() const { return last_; }
  // Moves to 0-based frame `index`; false if out of range.
  bool Seek(int index);
  // Moves to a frame at or shortly before `index` that is cheap to reach (a
  // movie's key frame, unless `index` is next); returns its index, or -1 if
  // out of range. For frames that need not be exact (spread samples).
  int SeekNear(int index);
  // The key frame at or before `index` from the container's index, without
  // decoding (sequences: `index`); -1 when the container does not say.
  int KeyFrameAtOrBefore(int index) const;

 private:
  struct Movie;
  // What a read makes of a frame (outputs left null are not made).
  struct Wanted {
    cv::Mat* gray = nullptr;
    cv::Size gray_size;
    cv::Mat* bgr = nullptr;
    cv::Size bgr_size;
    void Release() const;
  };
  bool SeekFar(int index);  // a movie's seek through its key frame
  bool ReadSequence(const Wanted& want);
  // `file` (a sequence's image) as `want` asks, decoded scaled by
  // TurboJPEG; false when it was not (no size that gains, not a JPEG, one
  // TurboJPEG refuses, another size than the clip's: FFmpeg reads it then).
  bool ReadScaledJpeg(const std::string& file, const Wanted& want);
  // The same for an uncompressed 16-bit RGB TIFF read straight from its
  // strips (tiff_plain.h); false for any other (FFmpeg reads it then).
  bool ReadPlainTiff(const std::string& file, const Wanted& want);
  bool ReadMovie(const Wanted& want);

  std::unique_ptr<Movie> movie_;
  std::unique_ptr<ScaledJpeg> jpeg_;  // made at a sequence's first JPEG read
  std::unique_ptr<PlainTiff> tiff_;   // made at a sequence's first TIFF read
  std::string path_;
  bool is_sequence_ = false;
  bool gray_only_ = false;
  ImageSequence sequence_;  // when is_sequence_
  int width_ = 0, height_ = 0, num_frames_ = 0, position_ = 0;
  bool num_frames_exact_ = false;
  double fps_ = 0.0;
  FrameReport last_;
};

// `image` averaged down to `size` (cv::INTER_AREA). Halvings go one at a
// time: OpenCV's area resize is fast for a factor of two and several times
// slower for others (a 4K frame to 960x540: 0.5 against 2.7 ms). `image`
// itself when it has that size already.
cv::Mat AreaReduced(const cv::Mat& image, cv::Size size);

// 8-bit `image` (1-4 channels) read through `table` (1 x 256 CV_32F, a
// transfer function: linear light) and averaged over stride x stride blocks
// each centred on full-size pixel (i * stride, j * stride), the border
// repeated: float32 of the size of image[::stride, ::stride]. Where a
// reduced pixel stands for the ray through that full-size pixel (a mask cast
// at those pixels), a point sample kept a 20-45 MP still's grain and this
// keeps the mean. Made in bands of rows (memory of a band, not a frame).
cv::Mat CentredBlockMeans(const cv::Mat& image, int stride,
                          const cv::Mat& table);

// 8-bit BGR (or gray) -> single-channel float32 in [0, 1], with the display
// gamma undone (value^gamma; gamma 1 keeps the encoded values).
cv::Mat ToLinearGray(const cv::Mat& image, double gamma = kDisplayGamma);

// ToLinearGray's 8-bit value -> linear float table (1 x 256, CV_32F), for
// cv::LUT: a table of the 256 values, as pow() per pixel cost more than
// decoding a 1080p frame.
cv::Mat LinearGrayTable(double gamma);

}  // namespace sunlapse
