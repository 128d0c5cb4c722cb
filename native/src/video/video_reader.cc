#include "sunlapse/video/video_reader.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <initializer_list>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include <tbb/parallel_for.h>
#include <opencv2/imgproc.hpp>

#include "jpeg_scaled.h"
#include "sunlapse/common/require.h"
#include "tiff_plain.h"

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/log.h>
#include <libswscale/swscale.h>
}

namespace sunlapse {
namespace fs = std::filesystem;

namespace {

std::string AvError(int err) {
  char text[AV_ERROR_MAX_STRING_SIZE] = {0};
  av_strerror(err, text, sizeof(text));
  return text;
}

void QuietFfmpeg() {
  // FFmpeg prints every concealed error to stderr; the reader reports per
  // frame.
  static std::once_flag once;
  std::call_once(once, [] { av_log_set_level(AV_LOG_FATAL); });
}

constexpr int64_t kMaxPixels = VideoReader::kMaxFramePixels;

// Every frame of the codec a key frame by its nature (ProRes, DNxHD, MJPEG).
bool IntraOnly(AVCodecID id) {
  const AVCodecDescriptor* d = avcodec_descriptor_get(id);
  return d != nullptr && (d->props & AV_CODEC_PROP_INTRA_ONLY) != 0;
}

// A QuickTime/MP4 header that gives every video stream's codec, size, frame
// count and rate (a fragmented MP4's header has no count: it is probed).
bool HeaderTellsEnough(const AVFormatContext* format) {
  if (format->iformat == nullptr ||
      std::string(format->iformat->name).find("mov") == std::string::npos)
    return false;
  bool video = false;
  for (unsigned i = 0; i < format->nb_streams; ++i) {
    const AVCodecParameters* par = format->streams[i]->codecpar;
    if (par->codec_type != AVMEDIA_TYPE_VIDEO) continue;
    const AVStream* st = format->streams[i];
    if (par->codec_id == AV_CODEC_ID_NONE || par->width <= 0 ||
        par->height <= 0 || st->nb_frames <= 0 || st->avg_frame_rate.num <= 0 ||
        st->avg_frame_rate.den <= 0)
      return false;
    video = true;
  }
  return video;
}

// One opened video stream and its decoder (a movie, or one image file).
class Decoder {
 public:
  ~Decoder() {
    av_frame_free(&frame_);
    av_packet_free(&packet_);
    avcodec_free_context(&codec_);
    avformat_close_input(&format_);
    sws_freeContext(sws_);
  }

  // Empty on success, else why the file cannot be read.
  std::string Open(const std::string& path, bool single_image,
                   bool gray_only = false) {
    QuietFfmpeg();
    AVDictionary* options = nullptr;
    // A single image: never expand '%d' or globs in its name.
    if (single_image) av_dict_set(&options, "pattern_type", "none", 0);
    int err = avformat_open_input(&format_, path.c_str(), nullptr, &options);
    av_dict_free(&options);
    if (err < 0) return AvError(err);
    // Images carry their codec in the name or the header, and so do
    // QuickTime/MP4 movies (size, codec, frame count and rate in their
    // header): probing decodes frames (one whole 4K ProRes frame, single
    // threaded: 0.2 s an opening, and a run opens the clip three times).
    // Other movies are probed; every reader decodes its first frame anyway.
    if (!(single_image || HeaderTellsEnough(format_)) ||
        format_->nb_streams == 0 ||
        format_->streams[0]->codecpar->codec_id == AV_CODEC_ID_NONE) {
      // Probing decodes too: the same size limit for its decoders.
      std::vector<AVDictionary*> probe(format_->nb_streams, nullptr);
      for (auto& d : probe) av_dict_set_int(&d, "max_pixels", kMaxPixels, 0);
      err = avformat_find_stream_info(format_, probe.data());
      for (auto& d : probe) av_dict_free(&d);
      if (err < 0) return AvError(err);
    }
    const AVCodec* codec = nullptr;
    stream_ =
        av_find_best_stream(format_, AVMEDIA_TYPE_VIDEO, -1, -1, &codec, 0);
    if (stream_ < 0 || codec == nullptr)
      return "no video stream with a known codec";
    const AVCodecParameters* par = format_->streams[stream_]->codecpar;
    if (static_cast<int64_t>(par->width) * par->height > kMaxPixels) {
      return "frames of " + std::to_string(par->width) + "x" +
             std::to_string(par->height) + " pixels, more than the " +
             std::to_string(kMaxPixels) + " a frame may have";
    }
    codec_ = avcodec_alloc_context3(codec);
    if ((err = avcodec_parameters_to_context(codec_, par)) < 0)
      return AvError(err);
    // The header may not say the size; the decoder then refuses a frame
    // larger than the limit before allocating it.
    codec_->max_pixels = kMaxPixels;
    codec_->thread_count =
        single_image ? 1 : 0;  // 0: FFmpeg picks (one per core)
    // Intra-only frames (ProRes, DNxHD) are independent: slice threads put
    // every core on each frame, so a lone frame after a seek (SeekNear)
    // decodes as fast as one read in order; frame threads would give it one
    // core. In order, both are as fast.
    if (!single_image && IntraOnly(codec->id) &&
        (codec->capabilities & AV_CODEC_CAP_SLICE_THREADS) != 0)
      codec_->thread_type = FF_THREAD_SLICE;
    if (gray_only) codec_->flags |= AV_CODEC_FLAG_GRAY;
    if ((err = avcodec_open2(codec_, codec, nullptr)) < 0) return AvError(err);
    packet_ = av_packet_alloc();
    frame_ = av_frame_alloc();
    return {};
  }

  AVStream* stream() const { return format_->streams[stream_]; }
  // Every frame a key frame by the codec's nature (ProRes, DNxHD, MJPEG).
  bool intra_only() const { return IntraOnly(codec_->codec_id); }
  AVFormatContext* format() const { return format_; }
  const AVFrame* frame() const { return frame_; }

  // Gray averaged down at least twice each way (the estimate's reads):
  // B-frames skip the deblocking filter (H.264, HEVC), a sixth of an H.264
  // decode. Frames predicted from reference B-frames carry the difference
  // on until the next key frame (42 dB at worst over a 250-frame group);
  // averaged down, the estimate's Suns on the benchmark's 1080p clips moved
  // by 0.04 deg mean and came no further from the truth, where at the
  // suite's 320x180, read whole, they moved by up to 0.4 deg
  // (docs/performance.md). FFmpeg reads the field for each frame (its
  // frame threads take it up as they start one), so it may change between
  // reads.
  void SkipDeblocking(bool skip) {
    codec_->skip_loop_filter = skip ? AVDISCARD_BIDIR : AVDISCARD_DEFAULT;
  }

  // Decodes the next frame into frame(): 0, AVERROR_EOF at the end, or another
  // negative code for a packet the decoder refused (that frame is lost).
  int Next() {
    while (true) {
      int err = avcodec_receive_frame(codec_, frame_);
      if (err == 0 || err == AVERROR_EOF) return err;
      if (err != AVERROR(EAGAIN)) return err;
      if (flushed_) return AVERROR_EOF;
      err = av_read_frame(format_, packet_);
      if (err < 0) {  // end of file (or a read error): drain the decoder
        avcodec_send_packet(codec_, nullptr);
        flushed_ = true;
        continue;
      }
      if (packet_->stream_index == stream_) {
        err = avcodec_send_packet(codec_, packet_);
        av_packet_unref(packet_);
        if (err < 0 && err != AVERROR(EAGAIN)) return err;
      } else {
        av_packet_unref(packet_);
      }
    }
  }

  // After a seek: decodes the next packet alone when it is a key frame and
  // drains the decoder, so the frame comes out without the frames after it
  // that the decoder's reordering and threads would otherwise decode first
  // (four or five at 4K: 175 against 40 ms). The decoder is left drained:
  // reading on needs a seek. 1 when the next packet is no key frame (nothing
  // consumed then is lost: the caller seeks again).
  int NextKeyFrameAlone() {
    while (true) {
      int err = av_read_frame(format_, packet_);
      if (err < 0) return err == AVERROR_EOF ? AVERROR_EOF : err;
      if (packet_->stream_index != stream_) {
        av_packet_unref(packet_);
        continue;
      }
      const bool key = (packet_->flags & AV_PKT_FLAG_KEY) != 0;
      if (key) err = avcodec_send_packet(codec_, packet_);
      av_packet_unref(packet_);
      if (!key) return 1;
      if (err < 0) return err;
      avcodec_send_packet(codec_, nullptr);
      flushed_ = true;
      return avcodec_receive_frame(codec_, frame_);
    }
  }

  // Positions the demuxer at or before `timestamp` (stream time base).
  bool SeekTo(int64_t timestamp) {
    if (av_seek_frame(format_, stream_, timestamp, AVSEEK_FLAG_BACKWARD) < 0)
      return false;
    avcodec_flush_buffers(codec_);
    flushed_ = false;
    return true;
  }

  // frame() as 8-bit BGR scaled to `size`, or 8-bit gray reduced to it
  // (empty: as decoded). BGR at its own size: the same conversion as
  // OpenCV's FFmpeg backend (bicubic, swscale's default colour matrix) so
  // tracks match those read through it; scaled, an area average.
  void ToImage(cv::Mat* out, bool gray, cv::Size size = cv::Size()) {
    if (gray && (ToGrayFromLuma(out, size) || ToGrayFromDeepLuma(out, size) ||
                 ToGrayFromDeepRgb(out, size)))
      return;
    const AVFrame* f = frame_;
    const cv::Size to =
        gray || size.empty() ? cv::Size(f->width, f->height) : size;
    const bool same = to == cv::Size(f->width, f->height);
    sws_ = sws_getCachedContext(
        sws_, f->width, f->height, static_cast<AVPixelFormat>(f->format),
        to.width, to.height, gray ? AV_PIX_FMT_GRAY8 : AV_PIX_FMT_BGR24,
        same ? SWS_BICUBIC : SWS_AREA, nullptr, nullptr, nullptr);
    if (sws_ == nullptr) {
      out->release();
      return;
    }
    out->create(to.height, to.width, gray ? CV_8UC1 : CV_8UC3);
    uint8_t* dst[4] = {out->data, nullptr, nullptr, nullptr};
    int dst_stride[4] = {static_cast<int>(out->step[0]), 0, 0, 0};
    sws_scale(sws_, f->data, f->linesize, 0, f->height, dst, dst_stride);
    if (gray && !size.empty()) *out = AreaReduced(*out, size);
  }

 private:
  // Gray from an 8-bit planar YUV picture's luma plane, read in place: no
  // copy through swscale (which cost 1.7 ms a 1080p frame, a fifth of the
  // decoding), reduced first and the video range expanded on the result.
  // False for other pixel formats (then swscale converts).
  bool ToGrayFromLuma(cv::Mat* out, cv::Size size) {
    const AVFrame* f = frame_;
    bool full_range = f->color_range == AVCOL_RANGE_JPEG;
    switch (static_cast<AVPixelFormat>(f->format)) {
      case AV_PIX_FMT_YUVJ420P:
      case AV_PIX_FMT_YUVJ422P:
      case AV_PIX_FMT_YUVJ444P:
      case AV_PIX_FMT_YUVJ440P:
        full_range = true;
        break;
      case AV_PIX_FMT_YUV420P:
      case AV_PIX_FMT_YUV422P:
      case AV_PIX_FMT_YUV444P:
      case AV_PIX_FMT_YUV440P:
      case AV_PIX_FMT_YUV411P:
      case AV_PIX_FMT_YUV410P:
      case AV_PIX_FMT_NV12:
      case AV_PIX_FMT_NV21:
        break;
      default:
        return false;
    }
    if (f->data[0] == nullptr || f->linesize[0] < f->width) return false;
    const cv::Mat luma(f->height, f->width, CV_8UC1, f->data[0],
                       static_cast<size_t>(f->linesize[0]));
    const cv::Mat reduced = size.empty() ? luma : AreaReduced(luma, size);
    if (full_range) {
      // The decoder reuses its picture: copied when not reduced.
      *out = reduced.data == luma.data ? luma.clone() : reduced;
    } else {
      if (video_to_full_.empty()) {
        // Video range: black at 16, white at 235 (as swscale expands it).
        video_to_full_.create(1, 256, CV_8U);
        for (int v = 0; v < 256; ++v)
          video_to_full_.at<uint8_t>(0, v) =
              cv::saturate_cast<uint8_t>(std::lround((v - 16) * 255.0 / 219.0));
      }
      cv::LUT(reduced, video_to_full_, *out);
    }
    return true;
  }

  // The same from a 10- or 12-bit planar YUV picture (ProRes, DNxHR,
  // 10-bit H.265), whose luma swscale would convert whole at full size (a
  // 4K ProRes frame: more than its decoding's share): reduced in 16 bits,
  // then brought to 8 bits and to full range in one step.
  bool ToGrayFromDeepLuma(cv::Mat* out, cv::Size size) {
    const AVFrame* f = frame_;
    const bool full_range = f->color_range == AVCOL_RANGE_JPEG;
    int bits = 0;
    switch (static_cast<AVPixelFormat>(f->format)) {
      case AV_PIX_FMT_YUV420P10LE:
      case AV_PIX_FMT_YUV422P10LE:
      case AV_PIX_FMT_YUV444P10LE:
      case AV_PIX_FMT_YUVA422P10LE:
      case AV_PIX_FMT_YUVA444P10LE:
        bits = 10;
        break;
      case AV_PIX_FMT_YUV420P12LE:
      case AV_PIX_FMT_YUV422P12LE:
      case AV_PIX_FMT_YUV444P12LE:
      case AV_PIX_FMT_YUVA422P12LE:
      case AV_PIX_FMT_YUVA444P12LE:
        bits = 12;
        break;
      default:
        return false;
    }
    if (f->data[0] == nullptr || f->linesize[0] < 2 * f->width) return false;
    const cv::Mat luma(f->height, f->width, CV_16UC1, f->data[0],
                       static_cast<size_t>(f->linesize[0]));
    const cv::Mat reduced = size.empty() ? luma : AreaReduced(luma, size);
    const double unit = 1 << (bits - 8);  // one 8-bit level
    if (full_range) {
      reduced.convertTo(*out, CV_8U, 255.0 / ((1 << bits) - 1));
    } else {
      // Video range: black at 16, white at 235, in 8-bit levels.
      reduced.convertTo(*out, CV_8U, 255.0 / (219.0 * unit),
                        -16.0 * 255.0 / 219.0);
    }
    return true;
  }

  // Gray from a 16-bit packed RGB picture (TIFF stills from a raw
  // converter): reduced in colour first (an area average commutes with the
  // luma's weights), then weighed as cv::COLOR_RGB2GRAY does and brought to
  // 8 bits, instead of swscale's conversion of the whole picture.
  bool ToGrayFromDeepRgb(cv::Mat* out, cv::Size size) {
    const AVFrame* f = frame_;
    int type = 0, code = 0;
    switch (static_cast<AVPixelFormat>(f->format)) {
      case AV_PIX_FMT_RGB48LE:
        type = CV_16UC3, code = cv::COLOR_RGB2GRAY;
        break;
      case AV_PIX_FMT_BGR48LE:
        type = CV_16UC3, code = cv::COLOR_BGR2GRAY;
        break;
      case AV_PIX_FMT_RGBA64LE:
        type = CV_16UC4, code = cv::COLOR_RGBA2GRAY;
        break;
      case AV_PIX_FMT_BGRA64LE:
        type = CV_16UC4, code = cv::COLOR_BGRA2GRAY;
        break;
      default:
        return false;
    }
    const int channels = CV_MAT_CN(type);
    if (f->data[0] == nullptr || f->linesize[0] < 2 * channels * f->width)
      return false;
    const cv::Mat rgb(f->height, f->width, type, f->data[0],
                      static_cast<size_t>(f->linesize[0]));
    cv::Mat gray16;
    cv::cvtColor(size.empty() ? rgb : AreaReduced(rgb, size), gray16, code);
    gray16.convertTo(*out, CV_8U, 255.0 / 65535.0);
    return true;
  }

  cv::Mat video_to_full_;  // video-range luma -> 0-255

  AVFormatContext* format_ = nullptr;
  AVCodecContext* codec_ = nullptr;
  AVPacket* packet_ = nullptr;
  AVFrame* frame_ = nullptr;
  SwsContext* sws_ = nullptr;
  int stream_ = -1;
  bool flushed_ = false;
};

// The first frame of one image file as BGR at the image's own size and/or
// gray reduced to gray_size (empty: its own size), and the size it has;
// the message says why not.
std::string DecodeImage(const std::string& path, cv::Mat* bgr,
                        cv::Mat* gray = nullptr, cv::Size gray_size = {},
                        cv::Size* decoded = nullptr) {
  Decoder d;
  std::string error = d.Open(path, /*single_image=*/true);
  if (error.empty()) {
    const int err = d.Next();
    if (err == 0) {
      if (decoded) *decoded = cv::Size(d.frame()->width, d.frame()->height);
      if (gray) d.ToImage(gray, true, gray_size);
      if (bgr) d.ToImage(bgr, false);
      return (gray && gray->empty()) || (bgr && bgr->empty())
                 ? "unsupported pixel format"
                 : "";
    }
    error = err == AVERROR_EOF ? "no image in the file" : AvError(err);
  }
  if (bgr) bgr->release();
  if (gray) gray->release();
  return error;
}

// Whether `path`'s extension, in lower case, is one of `extensions`.
bool HasExtension(const std::string& path,
                  std::initializer_list<const char*> extensions) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return std::any_of(extensions.begin(), extensions.end(),
                     [&](const char* e) { return ext == e; });
}

// Names FFmpeg's image reader takes for a JPEG or a TIFF (it goes by the
// name too).
bool HasJpegName(const std::string& path) {
  return HasExtension(path, {".jpg", ".jpeg", ".jpe", ".jfif"});
}
bool HasTiffName(const std::string& path) {
  return HasExtension(path, {".tif", ".tiff"});
}

}  // namespace

struct VideoReader::Movie {
  Decoder decoder;
  int64_t first_pts = 0;  // of frame 0, in the stream's time base
  bool pending =
      false;  // decoder.frame() is frame `position_`, not yet returned
  // The decoder was drained after one key frame (SeekNear): the frames
  // after it need a seek first.
  bool drained = false;
  double frame_seconds = 0.0;

  // The stream time stamp of 0-based frame `index` (in double, clamped: a
  // corrupt time base or rate must not overflow); first_pts when there is
  // none.
  int64_t TimestampOf(int index) const {
    const double ticks =
        static_cast<double>(first_pts) +
        index * frame_seconds / av_q2d(decoder.stream()->time_base);
    return std::isfinite(ticks) && std::fabs(ticks) < 9e18 ? std::llround(ticks)
                                                           : first_pts;
  }

  // 0-based frame index of decoder.frame(), from its time stamp.
  int64_t IndexOfFrame() const {
    const int64_t pts = decoder.frame()->best_effort_timestamp;
    if (pts == AV_NOPTS_VALUE || frame_seconds <= 0.0) return -1;
    // In double: corrupt time stamps may be far apart enough to overflow.
    const double seconds = (static_cast<double>(pts) - first_pts) *
                           av_q2d(decoder.stream()->time_base);
    const double index = seconds / frame_seconds;
    return std::isfinite(index) && std::fabs(index) < 1e15 ? std::llround(index)
                                                           : -1;
  }
};

VideoReader::VideoReader(const std::string& path, bool gray_only)
    : path_(path), gray_only_(gray_only) {
  if (!fs::exists(path)) {
    throw std::invalid_argument("path: no such file: " + path);
  }
  if (std::optional<ImageSequence> sequence = FindImageSequence(path)) {
    is_sequence_ = true;
    sequence_ = *sequence;
    num_frames_ = sequence_.num_frames();
    num_frames_exact_ = true;
    fps_ = 0.0;
    // A JPEG's size from decoding it at an eighth (every decoding thread of
    // a stream opens the clip, and a 24 MP still decoded whole in colour
    // costs a quarter of a second); else, or when TurboJPEG refuses it,
    // FFmpeg's.
    cv::Mat first;
    if (HasJpegName(path)) {
      jpeg_ = std::make_unique<ScaledJpeg>();
      if (jpeg_->Open(path, kMaxFramePixels).empty() &&
          jpeg_->Gray(8) != nullptr) {
        width_ = jpeg_->width();
        height_ = jpeg_->height();
        return;
      }
    }
    if (HasTiffName(path)) {
      // An uncompressed TIFF's size from its header (each decoding thread
      // opens the clip, and FFmpeg decodes a 50 MB still whole).
      PlainTiff tiff;
      if (tiff.Open(path, kMaxFramePixels).empty()) {
        width_ = tiff.width();
        height_ = tiff.height();
        return;
      }
    }
    const std::string error = DecodeImage(path, &first);
    if (!error.empty()) {
      throw std::invalid_argument("path: cannot decode image " + path + " (" +
                                  error + ")");
    }
    width_ = first.cols;
    height_ = first.rows;
    return;
  }
  movie_ = std::make_unique<Movie>();
  const std::string error =
      movie_->decoder.Open(path, /*single_image=*/false, gray_only);
  if (!error.empty()) {
    throw std::invalid_argument("path: cannot open video " + path + " (" +
                                error + ")");
  }
  AVStream* stream = movie_->decoder.stream();
  const AVRational rate =
      av_guess_frame_rate(movie_->decoder.format(), stream, nullptr);
  fps_ = rate.num > 0 && rate.den > 0 ? av_q2d(rate) : 0.0;
  movie_->frame_seconds = fps_ > 0.0 ? 1.0 / fps_ : 0.0;
  if (stream->nb_frames > 0 && stream->nb_frames <= 1000000000) {
    num_frames_ = static_cast<int>(stream->nb_frames);
    num_frames_exact_ = true;
  } else if (fps_ > 0.0) {
    double seconds = 0.0;
    if (stream->duration != AV_NOPTS_VALUE) {
      seconds = stream->duration * av_q2d(stream->time_base);
    } else if (movie_->decoder.format()->duration != AV_NOPTS_VALUE) {
      seconds = movie_->decoder.format()->duration /
                static_cast<double>(AV_TIME_BASE);
    }
    // A corrupt header can claim any duration: keep the estimate an int.
    const double frames = seconds * fps_;
    num_frames_ = std::isfinite(frames) && frames > 0.0
                      ? static_cast<int>(std::min(frames, 1e9) + 0.5)
                      : 0;
  }
  // The first decoded frame fixes the size every frame must have.
  int err, refused = 0;
  while ((err = movie_->decoder.Next()) < 0 && err != AVERROR_EOF) {
    refused = err;
  }
  if (err == AVERROR_EOF) {
    // Frames larger than kMaxFramePixels end here too (the decoder refuses
    // them before their size is known to us).
    throw std::invalid_argument(
        "path: video has no frames: " + path +
        (refused ? " (none could be decoded: " + AvError(refused) +
                       "; frames larger than 8192x8192 pixels are refused)"
                 : ""));
  }
  width_ = movie_->decoder.frame()->width;
  height_ = movie_->decoder.frame()->height;
  const int64_t pts = movie_->decoder.frame()->best_effort_timestamp;
  movie_->first_pts = pts == AV_NOPTS_VALUE ? 0 : pts;
  movie_->pending = true;
}

VideoReader::~VideoReader() = default;

int VideoReader::CountFrames() {
  if (is_sequence_ || num_frames_exact_) return num_frames_;
  // A second demuxer, so the reading position is untouched.
  AVFormatContext* format = nullptr;
  if (avformat_open_input(&format, path_.c_str(), nullptr, nullptr) < 0)
    return num_frames_;
  int count = 0;
  if (avformat_find_stream_info(format, nullptr) >= 0) {
    const int stream =
        av_find_best_stream(format, AVMEDIA_TYPE_VIDEO, -1, -1, nullptr, 0);
    AVPacket* packet = av_packet_alloc();
    while (stream >= 0 && av_read_frame(format, packet) >= 0) {
      count += packet->stream_index == stream;
      av_packet_unref(packet);
    }
    av_packet_free(&packet);
    num_frames_ = count;
    num_frames_exact_ = true;
  }
  avformat_close_input(&format);
  return num_frames_;
}

void VideoReader::Wanted::Release() const {
  if (gray) gray->release();
  if (bgr) bgr->release();
}

bool VideoReader::Read(cv::Mat* bgr) {
  if (gray_only_) throw std::logic_error("VideoReader: opened for gray only");
  Wanted want;
  want.bgr = bgr;
  return is_sequence_ ? ReadSequence(want) : ReadMovie(want);
}

bool VideoReader::ReadGray(cv::Mat* gray, cv::Size size) {
  Wanted want;
  want.gray = gray;
  want.gray_size = size;
  return is_sequence_ ? ReadSequence(want) : ReadMovie(want);
}

bool VideoReader::ReadGrayAndBgr(cv::Mat* gray, cv::Size gray_size,
                                 cv::Mat* bgr, cv::Size bgr_size) {
  if (gray_only_ && bgr != nullptr)
    throw std::logic_error("VideoReader: opened for gray only");
  const Wanted want{gray, gray_size, bgr, bgr_size};
  return is_sequence_ ? ReadSequence(want) : ReadMovie(want);
}

bool VideoReader::ReadSequence(const Wanted& want) {
  if (position_ >= num_frames_) return false;
  last_ = FrameReport{};
  last_.index = position_;
  const std::string file = sequence_.Path(position_++);
  if (!fs::exists(file)) {
    want.Release();
    last_.status = FrameStatus::kMissingFile;
    last_.message = "no file " + file;
    return true;
  }
  if (ReadScaledJpeg(file, want) || ReadPlainTiff(file, want)) return true;
  // Gray at its size from the decoder (reduced before any conversion);
  // colour whole, then reduced as always.
  cv::Size decoded;
  const std::string error =
      DecodeImage(file, want.bgr, want.gray, want.gray_size, &decoded);
  if (!error.empty()) {
    last_.status = FrameStatus::kUndecodable;
    last_.message = "cannot decode " + file + " (" + error + ")";
    return true;
  }
  last_.width = decoded.width;
  last_.height = decoded.height;
  if (decoded.width != width_ || decoded.height != height_) {
    // A frame of another size is as unusable as a corrupt one.
    want.Release();
    last_.status = FrameStatus::kSizeChanged;
    last_.message = file + " is " + std::to_string(last_.width) + "x" +
                    std::to_string(last_.height) + ", the clip " +
                    std::to_string(width_) + "x" + std::to_string(height_);
    return true;
  }
  if (want.bgr) *want.bgr = AreaReduced(*want.bgr, want.bgr_size);
  return true;
}

bool VideoReader::ReadScaledJpeg(const std::string& file, const Wanted& want) {
  // Only reads that reduce every output: the whole picture keeps FFmpeg's
  // (colour at its own size: tracks read through OpenCV match it).
  const cv::Size full(width_, height_);
  auto reduces = [&](const cv::Mat* out, cv::Size size) {
    return out == nullptr || (!size.empty() && size != full);
  };
  if (!reduces(want.gray, want.gray_size) ||
      !reduces(want.bgr, want.bgr_size) || !HasJpegName(file))
    return false;
  if (!jpeg_) jpeg_ = std::make_unique<ScaledJpeg>();
  // Another size than the clip's: FFmpeg's read reports it as always.
  if (!jpeg_->Open(file, kMaxFramePixels).empty() || jpeg_->width() != width_ ||
      jpeg_->height() != height_)
    return false;
  // At the largest scaling that keeps the reduction's geometry; even
  // whole, TurboJPEG's luma alone costs two thirds of FFmpeg's decode.
  // JPEG's Y is BT.601's full-range luma: what FFmpeg's decoder gave as
  // gray (ToGrayFromLuma) and what cv::COLOR_BGR2GRAY weighs.
  const int gray_shrink = JpegShrinkFor(full, want.gray_size);
  // The decoder's buffer is reused: an output of its very size is copied.
  auto reduced = [](const cv::Mat& plane, cv::Size size) {
    cv::Mat out = AreaReduced(plane, size);
    return out.data == plane.data ? out.clone() : out;
  };
  if (want.bgr) {
    // Gray and colour from one decode of the planes, at the gray's scaling.
    // The colour is the unmodelled-shadow note's background, compared with
    // a frame's point samples a pixel of shake apart: where a colour
    // pixel's border cuts a block it may take the block's mean, as long as
    // its pixels are no smaller than the blocks.
    int shrink = want.gray ? gray_shrink : 8;
    while (shrink > 1 && (width_ < want.bgr_size.width * shrink ||
                          height_ < want.bgr_size.height * shrink))
      shrink /= 2;
    cv::Mat y, cb, cr;
    if (!jpeg_->Planes(shrink, &y, &cb, &cr)) return false;
    if (want.gray) *want.gray = reduced(y, want.gray_size);
    *want.bgr = BgrFromPlanes(y, cb, cr, want.bgr_size);
  } else {
    const cv::Mat* y = jpeg_->Gray(gray_shrink);
    if (y == nullptr) return false;
    *want.gray = reduced(*y, want.gray_size);
  }
  last_.width = width_;
  last_.height = height_;
  return true;
}

bool VideoReader::ReadPlainTiff(const std::string& file, const Wanted& want) {
  if (!HasTiffName(file)) return false;
  if (!tiff_) tiff_ = std::make_unique<PlainTiff>();
  cv::Mat rgb;
  // Another size than the clip's: FFmpeg's read reports it as always.
  if (!tiff_->Open(file, kMaxFramePixels).empty() || tiff_->width() != width_ ||
      tiff_->height() != height_ || !tiff_->Read(&rgb))
    return false;
  // As FFmpeg's 16-bit RGB is made gray (Decoder::ToGrayFromDeepRgb):
  // reduced in colour, then weighed, then 8 bits.
  const bool alpha = rgb.channels() == 4;
  if (want.gray) {
    cv::Mat gray16;
    cv::cvtColor(
        want.gray_size.empty() ? rgb : AreaReduced(rgb, want.gray_size), gray16,
        alpha ? cv::COLOR_RGBA2GRAY : cv::COLOR_RGB2GRAY);
    gray16.convertTo(*want.gray, CV_8U, 255.0 / 65535.0);
  }
  if (want.bgr) {
    // Reduced before the 8-bit conversion (a background's colour: within
    // a level of converting first).
    cv::Mat bgr16;
    cv::cvtColor(want.bgr_size.empty() ? rgb : AreaReduced(rgb, want.bgr_size),
                 bgr16, alpha ? cv::COLOR_RGBA2BGR : cv::COLOR_RGB2BGR);
    bgr16.convertTo(*want.bgr, CV_8U, 255.0 / 65535.0);
  }
  last_.width = width_;
  last_.height = height_;
  return true;
}

bool VideoReader::ReadMovie(const Wanted& want) {
  Movie& mv = *movie_;
  if (!mv.pending && mv.drained && !SeekFar(position_)) return false;
  last_ = FrameReport{};
  last_.index = position_;
  if (!mv.pending) {
    mv.decoder.SkipDeblocking(gray_only_ && want.gray != nullptr &&
                              !want.gray_size.empty() &&
                              2 * want.gray_size.width <= width_ &&
                              2 * want.gray_size.height <= height_);
    const int err = mv.decoder.Next();
    if (err == AVERROR_EOF) {
      // Containers often over-report their length; the end is where reading
      // stops.
      last_.index = -1;
      return false;
    }
    if (err < 0) {
      want.Release();
      ++position_;
      last_.status = FrameStatus::kUndecodable;
      last_.message = "frame " + std::to_string(last_.index) +
                      " cannot be decoded (" + AvError(err) + ")";
      return true;
    }
  }
  mv.pending = false;
  ++position_;
  const AVFrame* f = mv.decoder.frame();
  last_.width = f->width;
  last_.height = f->height;
  if (f->width != width_ || f->height != height_) {
    // Converting at the first frame's size would garble it: report, skip.
    want.Release();
    last_.status = FrameStatus::kSizeChanged;
    last_.message = "frame " + std::to_string(last_.index) + " is " +
                    std::to_string(f->width) + "x" + std::to_string(f->height) +
                    ", the clip " + std::to_string(width_) + "x" +
                    std::to_string(height_);
    return true;
  }
  if (want.gray) mv.decoder.ToImage(want.gray, true, want.gray_size);
  if (want.bgr) mv.decoder.ToImage(want.bgr, false, want.bgr_size);
  if ((want.gray && want.gray->empty()) || (want.bgr && want.bgr->empty())) {
    want.Release();
    last_.status = FrameStatus::kUndecodable;
    last_.message = "frame " + std::to_string(last_.index) +
                    " has an unsupported pixel format";
  }
  return true;
}

bool VideoReader::Seek(int index) {
  if (index < 0 || (num_frames_ > 0 && index >= num_frames_)) return false;
  if (is_sequence_) {
    position_ = index;
    return true;
  }
  Movie& mv = *movie_;
  if (index == position_ && (mv.pending || !mv.drained)) return true;
  // Close ahead: decoding forward is exact and cheaper than a seek, unless
  // a key frame lies between: decoding from it is shorter.
  if (!mv.drained && index > position_ && index <= position_ + 50 &&
      KeyFrameAtOrBefore(index) <= position_) {
    while (position_ < index) {
      if (!mv.pending) {
        const int err = mv.decoder.Next();
        if (err == AVERROR_EOF) return false;
      }
      mv.pending = false;
      ++position_;
    }
    return true;
  }
  return SeekFar(index);
}

bool VideoReader::SeekFar(int index) {
  Movie& mv = *movie_;
  mv.drained = false;
  // To the key frame at or before the target, then decode up to it; the
  // frames' time stamps say where we are.
  const int64_t target = mv.TimestampOf(index);
  mv.pending = false;
  if (mv.decoder.SeekTo(target)) {
    int64_t at = -1;
    while (true) {
      const int err = mv.decoder.Next();
      if (err == AVERROR_EOF) break;
      if (err < 0) continue;
      at = mv.IndexOfFrame();
      if (at < 0 || at >= index) break;
    }
    if (at == index) {
      mv.pending = true;
      position_ = index;
      return true;
    }
  }
  // The seek landed past the target, or the frames carry no time stamps:
  // from the very beginning, counting frames as Read() does.
  if (!mv.decoder.SeekTo(mv.first_pts)) return false;
  int err;
  while ((err = mv.decoder.Next()) < 0 && err != AVERROR_EOF) {
  }
  if (err == AVERROR_EOF) return false;
  mv.pending = true;
  position_ = 0;
  while (position_ < index) {
    if (!mv.pending && mv.decoder.Next() == AVERROR_EOF) return false;
    mv.pending = false;
    ++position_;
  }
  return true;
}

int VideoReader::KeyFrameAtOrBefore(int index) const {
  if (index < 0 || (num_frames_ > 0 && index >= num_frames_)) return -1;
  if (is_sequence_) return index;
  const Movie& mv = *movie_;
  if (mv.frame_seconds <= 0.0) return -1;
  AVStream* st = mv.decoder.stream();
  const int64_t ticks = mv.TimestampOf(index);
  // The index holds decoding time stamps: with B-frames they run ahead of
  // the presentation ones by the first entry's lag behind frame 0.
  const AVIndexEntry* first = avformat_index_get_entry(st, 0);
  if (first == nullptr) return -1;
  const int64_t lag = mv.first_pts - first->timestamp;
  const AVIndexEntry* e = avformat_index_get_entry_from_timestamp(
      st, ticks - lag, AVSEEK_FLAG_BACKWARD);
  if (e == nullptr || !(e->flags & AVINDEX_KEYFRAME)) return -1;
  const double at = (static_cast<double>(e->timestamp) + lag - mv.first_pts) *
                    av_q2d(st->time_base) / mv.frame_seconds;
  if (!std::isfinite(at)) return -1;
  const int64_t key = std::llround(at);
  return key >= 0 && key <= index ? static_cast<int>(key) : -1;
}

bool VideoReader::frames_independent() const {
  return is_sequence_ || movie_->decoder.intra_only();
}

int VideoReader::SeekNear(int index) {
  if (index < 0 || (num_frames_ > 0 && index >= num_frames_)) return -1;
  if (is_sequence_ || index == position_ || index == position_ + 1) {
    return Seek(index) ? index : -1;
  }
  // The key frame at or before the target costs one decode; frames after it
  // would cost one each.
  Movie& mv = *movie_;
  const int64_t target = mv.TimestampOf(index);
  mv.pending = false;
  if (mv.decoder.SeekTo(target)) {
    mv.drained = false;
    int err = mv.decoder.NextKeyFrameAlone();
    if (err == 0) {
      mv.drained = true;
    } else if (mv.decoder.SeekTo(target)) {
      while ((err = mv.decoder.Next()) < 0 && err != AVERROR_EOF) {
      }
    }
    const int64_t at = err == 0 ? mv.IndexOfFrame() : -1;
    if (at >= 0 && at <= index) {
      mv.pending = true;
      position_ = static_cast<int>(at);
      return position_;
    }
  }
  return SeekFar(index) ? index : -1;
}

cv::Mat AreaReduced(const cv::Mat& image, cv::Size size) {
  if (image.empty() || size.empty() || image.size() == size) return image;
  int halvings = 0;
  while ((size.width << (halvings + 1)) <= image.cols &&
         (size.height << (halvings + 1)) <= image.rows)
    ++halvings;
  cv::Mat out;
  if (halvings > 0 && (size.width << halvings) == image.cols &&
      (size.height << halvings) == image.rows) {
    out = image;
    for (int i = 0; i < halvings; ++i) {
      cv::Mat half;
      cv::resize(out, half, cv::Size(out.cols / 2, out.rows / 2), 0, 0,
                 cv::INTER_AREA);
      out = half;
    }
    return out;
  }
  cv::resize(image, out, size, 0, 0, cv::INTER_AREA);
  return out;
}

cv::Mat CentredBlockMeans(const cv::Mat& image, int stride,
                          const cv::Mat& table) {
  Require(image.depth() == CV_8U && image.channels() >= 1 &&
              image.channels() <= 4 && !image.empty(),
          "image: expected a non-empty 8-bit image of 1-4 channels");
  Require(stride >= 1, "stride must be >= 1");
  Require(table.type() == CV_32FC1 && table.total() == 256,
          "table: expected 256 float32 values");
  cv::Mat out;
  if (stride == 1) {
    cv::LUT(image, table, out);
    return out;
  }
  const int h = image.rows, w = image.cols;
  const int out_h = (h + stride - 1) / stride,
            out_w = (w + stride - 1) / stride;
  const int half = stride / 2;
  // Columns [-half, out_w * stride - half) of the image, the border repeated.
  const int right = out_w * stride - half - w;
  const cv::Mat cols = right >= 0 ? image : image.colRange(0, w + right);
  out.create(out_h, out_w, CV_32FC(image.channels()));
  constexpr int kBandRows = 32;
  const int bands = (out_h + kBandRows - 1) / kBandRows;
  tbb::parallel_for(0, bands, [&](int b) {
    const int r0 = b * kBandRows, r1 = std::min(out_h, r0 + kBandRows);
    const int y0 = r0 * stride - half, y1 = r1 * stride - half;
    const int top = std::max(0, -y0), bottom = std::max(0, y1 - h);
    cv::Mat padded, linear, reduced;
    cv::copyMakeBorder(cols.rowRange(std::max(0, y0), std::min(h, y1)), padded,
                       top, bottom, half, std::max(0, right),
                       cv::BORDER_REPLICATE);
    cv::LUT(padded, table, linear);
    // An exact integer factor: INTER_AREA's value is each block's mean.
    cv::resize(linear, reduced, cv::Size(out_w, r1 - r0), 0, 0, cv::INTER_AREA);
    reduced.copyTo(out.rowRange(r0, r1));
  });
  return out;
}

cv::Mat LinearGrayTable(double gamma) {
  cv::Mat table(1, 256, CV_32F);
  for (int v = 0; v < 256; ++v)
    table.at<float>(0, v) = static_cast<float>(std::pow(v / 255.0, gamma));
  return table;
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
  if (gray.depth() == CV_8U) {
    cv::LUT(gray, LinearGrayTable(gamma), out);
    return out;
  }
  const double scale = gray.depth() == CV_16U ? 1.0 / 65535.0 : 1.0;
  gray.convertTo(out, CV_32F, scale);
  if (gamma != 1.0) cv::pow(out, gamma, out);
  return out;
}

}  // namespace sunlapse
