#include "sunlapse/video/image_sequence.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <regex>
#include <system_error>

namespace fs = std::filesystem;

namespace sunlapse {

bool IsImageExtension(std::string ext) {
  for (auto& c : ext) c = static_cast<char>(std::tolower(c));
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".tif" ||
         ext == ".tiff" || ext == ".exr" || ext == ".bmp" || ext == ".webp";
}

std::string ImageSequence::Path(int index) const {
  char number[32];
  std::snprintf(number, sizeof(number), "%0*d", digits, first_number + index);
  return prefix + number + suffix;
}

std::optional<ImageSequence> FindImageSequence(const std::string& path) {
  const fs::path p(path);
  const std::string name = p.filename().string();
  // At most 9 digits: the number must fit an int.
  static const std::regex kNumbered(R"((.*?)(\d{1,9})(\.[A-Za-z]+)$)");
  std::smatch m;
  if (!IsImageExtension(p.extension().string()) ||
      !std::regex_match(name, m, kNumbered)) {
    return std::nullopt;
  }
  ImageSequence s;
  const std::string stem = m[1].str();
  s.prefix = (p.parent_path() / stem).string();
  s.digits = static_cast<int>(m[2].str().size());
  s.padded = s.digits > 1 && m[2].str()[0] == '0';
  s.first_number = std::stoi(m[2].str());
  s.last_number = s.first_number;
  s.suffix = m[3].str();
  const fs::path dir =
      p.parent_path().empty() ? fs::path(".") : p.parent_path();
  std::error_code error;
  for (const auto& entry : fs::directory_iterator(dir, error)) {
    const std::string other = entry.path().filename().string();
    if (other.size() <= stem.size() + s.suffix.size() ||
        other.compare(0, stem.size(), stem) ||
        other.compare(other.size() - s.suffix.size(), s.suffix.size(),
                      s.suffix)) {
      continue;
    }
    const std::string digits =
        other.substr(stem.size(), other.size() - stem.size() - s.suffix.size());
    if (digits.empty() || digits.size() > 9 ||
        digits.find_first_not_of("0123456789") != std::string::npos) {
      continue;
    }
    // Zero-padded names keep their width; unpadded ones may grow.
    if (s.padded && static_cast<int>(digits.size()) != s.digits) continue;
    s.last_number = std::max(s.last_number, std::stoi(digits));
  }
  return s;
}

}  // namespace sunlapse
