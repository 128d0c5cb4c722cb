// Bindings of the video stage's names: numbered image sequences (the one
// parser of their names, also for the add-on's EXIF times and its check for
// missing files).
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "sunlapse/video/image_sequence.h"

namespace py = pybind11;

namespace sunlapse::python {

void BindVideo(py::module_& m) {
  py::class_<ImageSequence>(m, "ImageSequence",
                            "A numbered image sequence named by one of its "
                            "files (video/image_sequence.h).")
      .def_readonly("prefix", &ImageSequence::prefix, "folder and stem")
      .def_readonly("digits", &ImageSequence::digits,
                    "width of the named file's number")
      .def_readonly("padded", &ImageSequence::padded)
      .def_readonly("first_number", &ImageSequence::first_number)
      .def_readonly("last_number", &ImageSequence::last_number,
                    "highest number present (a gap: missing frames)")
      .def_readonly("suffix", &ImageSequence::suffix)
      .def_property_readonly("num_frames", &ImageSequence::num_frames)
      .def("path", &ImageSequence::Path, py::arg("index"),
           "The file of frame `index` (0-based from the named file).");
  m.def("find_image_sequence", &FindImageSequence, py::arg("path"),
        "The numbered image sequence `path` starts (an ImageSequence), or "
        "None when it is not a numbered image.");
}

}  // namespace sunlapse::python
