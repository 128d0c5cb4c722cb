#include "tiff_plain.h"

#include <algorithm>
#include <fstream>
#include <map>

namespace sunlapse {
namespace {

// Baseline TIFF tags (TIFF 6.0, section 8) this reader looks at.
enum Tag : uint16_t {
  kWidth = 256,
  kHeight = 257,
  kBitsPerSample = 258,
  kCompression = 259,
  kPhotometric = 262,
  kStripOffsets = 273,
  kOrientation = 274,
  kSamplesPerPixel = 277,
  kRowsPerStrip = 278,
  kStripByteCounts = 279,
  kPlanarConfiguration = 284,
  kTileWidth = 322,
  kSampleFormat = 339,
};

bool HostIsLittleEndian() {
  const uint16_t probe = 1;
  return *reinterpret_cast<const uint8_t*>(&probe) == 1;
}

// Reads a TIFF's numbers in its byte order, never past the file's end.
class Numbers {
 public:
  Numbers(std::ifstream* in, bool big, uint64_t size)
      : in_(in), big_(big), size_(size) {}

  bool Bytes(uint64_t at, size_t n, uint8_t* out) {
    if (at > size_ || n > size_ - at) return false;
    in_->seekg(static_cast<std::streamoff>(at));
    return static_cast<bool>(in_->read(reinterpret_cast<char*>(out),
                                       static_cast<std::streamsize>(n)));
  }
  uint64_t From(const uint8_t* p, int n) const {
    uint64_t v = 0;
    for (int i = 0; i < n; ++i)
      v |= uint64_t{p[big_ ? n - 1 - i : i]} << (8 * i);
    return v;
  }
  bool Read(uint64_t at, int n, uint64_t* v) {
    uint8_t b[8];
    if (!Bytes(at, static_cast<size_t>(n), b)) return false;
    *v = From(b, n);
    return true;
  }

 private:
  std::ifstream* in_;
  bool big_;
  uint64_t size_;
};

}  // namespace

std::string PlainTiff::Open(const std::string& path, int64_t max_pixels) {
  width_ = height_ = channels_ = rows_per_strip_ = 0;
  strip_offsets_.clear();
  strip_bytes_.clear();
  // Kept open for Read: a still is opened once.
  in_.close();
  in_.clear();
  in_.open(path, std::ios::binary | std::ios::ate);
  std::ifstream& in = in_;
  if (!in) return "cannot open the file";
  const uint64_t size = static_cast<uint64_t>(in.tellg());
  uint8_t head[8];
  in.seekg(0);
  if (size < 8 || !in.read(reinterpret_cast<char*>(head), 8))
    return "no TIFF header";
  if (head[0] == 'I' && head[1] == 'I') {
    big_endian_ = false;
  } else if (head[0] == 'M' && head[1] == 'M') {
    big_endian_ = true;
  } else {
    return "no TIFF header";
  }
  Numbers num(&in, big_endian_, size);
  if (num.From(head + 2, 2) != 42) return "not a classic TIFF (BigTIFF?)";
  const uint64_t ifd = num.From(head + 4, 4);
  uint64_t count = 0;
  if (!num.Read(ifd, 2, &count) || count == 0 || count > 4096)
    return "no image directory";
  // Each tag's values (SHORT or LONG), read where they are: in the entry
  // when they fit in its 4 bytes, else at its offset.
  std::map<uint16_t, std::vector<uint64_t>> tags;
  for (uint64_t i = 0; i < count; ++i) {
    uint8_t e[12];
    if (!num.Bytes(ifd + 2 + 12 * i, 12, e)) return "truncated directory";
    const uint16_t tag = static_cast<uint16_t>(num.From(e, 2));
    const uint64_t type = num.From(e + 2, 2), n = num.From(e + 4, 4);
    const int bytes = type == 3 ? 2 : type == 4 ? 4 : 0;
    // Only the tags read here, and no more values than an image can have
    // (a strip per row at most): a hostile directory's counts allocate
    // nothing.
    const bool strips = tag == kStripOffsets || tag == kStripByteCounts;
    const bool known = strips || tag == kWidth || tag == kHeight ||
                       tag == kBitsPerSample || tag == kCompression ||
                       tag == kPhotometric || tag == kOrientation ||
                       tag == kSamplesPerPixel || tag == kRowsPerStrip ||
                       tag == kPlanarConfiguration || tag == kTileWidth ||
                       tag == kSampleFormat;
    if (!known) continue;
    if (bytes == 0 || n == 0 || n > (strips ? (1u << 16) : 16u))
      return "a tag this reader does not read";
    std::vector<uint64_t> v(n);
    if (n * bytes <= 4) {
      for (uint64_t k = 0; k < n; ++k)
        v[k] = num.From(e + 8 + k * bytes, bytes);
    } else {
      std::vector<uint8_t> raw(n * bytes);
      if (!num.Bytes(num.From(e + 8, 4), raw.size(), raw.data()))
        return "truncated tag values";
      for (uint64_t k = 0; k < n; ++k)
        v[k] = num.From(raw.data() + k * bytes, bytes);
    }
    tags[tag] = std::move(v);
  }
  auto one = [&](Tag t, uint64_t fallback) {
    auto it = tags.find(t);
    return it == tags.end() ? fallback : it->second[0];
  };
  auto all_equal = [&](Tag t, uint64_t value) {
    auto it = tags.find(t);
    return it == tags.end() ||
           std::all_of(it->second.begin(), it->second.end(),
                       [&](uint64_t x) { return x == value; });
  };
  const uint64_t w = one(kWidth, 0), h = one(kHeight, 0);
  const uint64_t spp = one(kSamplesPerPixel, 1);
  if (w == 0 || h == 0 || w > (1u << 16) || h > (1u << 16) ||
      static_cast<int64_t>(w * h) > max_pixels)
    return "no size, or too large";
  if (spp != 3 && spp != 4) return "not RGB(A)";
  if (!tags.count(kBitsPerSample) || !all_equal(kBitsPerSample, 16))
    return "not 16 bits a sample";
  if (one(kCompression, 1) != 1) return "compressed";
  if (one(kPhotometric, 0) != 2) return "not RGB";
  if (one(kPlanarConfiguration, 1) != 1) return "planar";
  if (!all_equal(kSampleFormat, 1)) return "not unsigned integers";
  if (one(kOrientation, 1) != 1) return "not top-left";
  if (tags.count(kTileWidth)) return "tiled";
  const uint64_t rps = std::min<uint64_t>(one(kRowsPerStrip, h), h);
  if (rps == 0) return "no rows per strip";
  const uint64_t strips = (h + rps - 1) / rps;
  const auto offsets = tags.find(kStripOffsets);
  const auto bytes = tags.find(kStripByteCounts);
  if (offsets == tags.end() || bytes == tags.end() ||
      offsets->second.size() != strips || bytes->second.size() != strips)
    return "strips not as the size says";
  const uint64_t row_bytes = w * spp * 2;
  for (uint64_t s = 0; s < strips; ++s) {
    const uint64_t rows = std::min(rps, h - s * rps);
    const uint64_t need = rows * row_bytes;
    if (bytes->second[s] < need || offsets->second[s] > size ||
        need > size - offsets->second[s])
      return "a strip beyond the file";
  }
  width_ = static_cast<int>(w);
  height_ = static_cast<int>(h);
  channels_ = static_cast<int>(spp);
  rows_per_strip_ = static_cast<int>(rps);
  strip_offsets_ = offsets->second;
  strip_bytes_ = bytes->second;
  return {};
}

bool PlainTiff::Read(cv::Mat* rgb) {
  if (width_ <= 0) return false;
  std::ifstream& in = in_;
  in.clear();
  const size_t row_values = static_cast<size_t>(width_) * channels_;
  buffer_.resize(row_values * height_);
  for (size_t s = 0; s < strip_offsets_.size(); ++s) {
    const size_t row = s * rows_per_strip_;
    const size_t rows = std::min<size_t>(rows_per_strip_, height_ - row);
    in.seekg(static_cast<std::streamoff>(strip_offsets_[s]));
    if (!in.read(reinterpret_cast<char*>(buffer_.data() + row * row_values),
                 static_cast<std::streamsize>(rows * row_values * 2)))
      return false;
  }
  if (big_endian_ == HostIsLittleEndian()) {
    for (uint16_t& v : buffer_) v = static_cast<uint16_t>((v >> 8) | (v << 8));
  }
  *rgb = cv::Mat(height_, width_, CV_16UC(channels_), buffer_.data());
  return true;
}

}  // namespace sunlapse
