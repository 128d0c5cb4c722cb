// Numbered image sequences (frame_0001.png, frame_0002.png, ...): the one
// parser of their names, for the reader and, through the bindings, for the
// add-on (EXIF times per frame, missing files).
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace sunlapse {

// A sequence named by one of its files: the folder and name before the
// number, the number's width as written, and the extension with its dot.
struct ImageSequence {
  std::string prefix;    // folder and stem, e.g. "shots/IMG_"
  int digits = 0;        // width of the first file's number
  bool padded = false;   // the first number is written with leading zeros
  int first_number = 0;  // the number of the file named
  int last_number = 0;   // the highest number present (a gap: missing frames)
  std::string suffix;    // e.g. ".JPG"

  int num_frames() const { return last_number - first_number + 1; }
  // The file of frame `index`, counted from the file named (0-based).
  std::string Path(int index) const;
};

// The sequence that `path` starts, when it is a numbered image (an image
// extension, a number of at most 9 digits right before it); its last number
// is the highest of the folder's files of the same name: zero-padded names
// keep their width, unpadded ones may grow. std::nullopt otherwise.
std::optional<ImageSequence> FindImageSequence(const std::string& path);

// Whether the extension (with its dot, any case) is an image the reader
// decodes as a still.
bool IsImageExtension(std::string extension);

}  // namespace sunlapse
