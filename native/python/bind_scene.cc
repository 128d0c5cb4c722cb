// Bindings of the scene stage: Camera and Scene.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <limits>
#include <string>

#include "arrays.h"
#include "options.h"
#include "sunlapse/scene/camera.h"
#include "sunlapse/scene/scene.h"

namespace sunlapse::python {
namespace {

SensorFit ParseSensorFit(const std::string& s) {
  if (s == "AUTO") return SensorFit::kAuto;
  if (s == "HORIZONTAL") return SensorFit::kHorizontal;
  if (s == "VERTICAL") return SensorFit::kVertical;
  throw std::invalid_argument(
      "sensor_fit: expected AUTO, HORIZONTAL or "
      "VERTICAL, got '" +
      s + "'");
}

const char* SensorFitName(SensorFit f) {
  switch (f) {
    case SensorFit::kHorizontal:
      return "HORIZONTAL";
    case SensorFit::kVertical:
      return "VERTICAL";
    default:
      return "AUTO";
  }
}

// Fields without a sensible default (a camera made without them would be
// silently wrong): required unless a whole params struct is given.
void RequireKeywords(const py::kwargs& kwargs,
                     std::initializer_list<const char*> names,
                     const char* function) {
  for (const char* name : names) {
    if (!kwargs.contains(name)) {
      throw py::type_error(std::string(function) +
                           ": missing required argument '" + name + "'");
    }
  }
}

// Allocates the numpy outputs of a first-hit query and the buffers into them.
struct HitArrays {
  explicit HitArrays(py::ssize_t n)
      : point({n, py::ssize_t{3}}),
        normal({n, py::ssize_t{3}}),
        distance(n),
        object_id(n),
        triangle_id(n) {}
  HitBuffers buffers() {
    return {point.mutable_data(), normal.mutable_data(),
            distance.mutable_data(), object_id.mutable_data(),
            triangle_id.mutable_data()};
  }
  py::dict ToDict() {
    py::dict d;
    d["point"] = point;
    d["normal"] = normal;
    d["distance"] = distance;
    d["object_id"] = object_id;
    d["triangle_id"] = triangle_id;
    py::array_t<bool> hit(object_id.size());
    auto h = hit.mutable_unchecked<1>();
    auto ids = object_id.unchecked<1>();
    for (py::ssize_t i = 0; i < object_id.size(); ++i) h(i) = ids(i) >= 0;
    d["hit"] = hit;
    return d;
  }
  py::array_t<float> point, normal, distance;
  py::array_t<int32_t> object_id, triangle_id;
};

constexpr const char* kHitDoc =
    "Returns a dict of arrays: point (N,3), normal (N,3, unit, facing the ray "
    "origin), distance (N,), object_id (N,), triangle_id (N,), hit (N, bool). "
    "Misses have NaN point/normal, inf distance and id -1.";

}  // namespace

void BindScene(py::module_& m) {
  OptionsClass<BlenderCameraParams>(
      m, "BlenderCameraParams",
      "A camera as Blender describes it (Camera data, render settings).")
      .field("lens_mm", &BlenderCameraParams::lens_mm,
             "Focal length, millimetres (Camera.lens).")
      .field("sensor_width_mm", &BlenderCameraParams::sensor_width_mm,
             "Camera.sensor_width, millimetres.")
      .field("sensor_height_mm", &BlenderCameraParams::sensor_height_mm,
             "Camera.sensor_height, millimetres.")
      .field_property(
          "sensor_fit",
          [](const BlenderCameraParams& p) {
            return std::string(SensorFitName(p.sensor_fit));
          },
          [](BlenderCameraParams& p, const std::string& name) {
            p.sensor_fit = ParseSensorFit(name);
          },
          "Camera.sensor_fit: 'AUTO', 'HORIZONTAL' or 'VERTICAL'.")
      .field("shift_x", &BlenderCameraParams::shift_x,
             "Camera.shift_x, in units of the fitted sensor side.")
      .field("shift_y", &BlenderCameraParams::shift_y, "Camera.shift_y.")
      .field("width", &BlenderCameraParams::width, "Image width, pixels.")
      .field("height", &BlenderCameraParams::height, "Image height, pixels.")
      .field("pixel_aspect_x", &BlenderCameraParams::pixel_aspect_x,
             "Render pixel aspect x.")
      .field("pixel_aspect_y", &BlenderCameraParams::pixel_aspect_y,
             "Render pixel aspect y.")
      .field("matrix_world", &BlenderCameraParams::world_from_camera_local,
             "The camera object's matrix_world (4x4, world from camera "
             "local).");
  OptionsClass<PolynomialDistortion>(
      m, "PolynomialDistortion",
      "Blender's polynomial lens distortion (OpenCV pixels).")
      .field("focal_x_px", &PolynomialDistortion::focal_x_px,
             "Focal length, pixels.")
      .field("focal_y_px", &PolynomialDistortion::focal_y_px,
             "Vertical focal length (focal * pixel aspect), pixels.")
      .field("principal_x_px", &PolynomialDistortion::principal_x_px,
             "Principal point x, OpenCV pixels.")
      .field("principal_y_px", &PolynomialDistortion::principal_y_px,
             "Principal point y, OpenCV pixels.")
      .field("k1", &PolynomialDistortion::k1, "r^2 coefficient.")
      .field("k2", &PolynomialDistortion::k2, "r^4 coefficient.")
      .field("k3", &PolynomialDistortion::k3, "r^6 coefficient.");

  py::class_<Camera>(m, "Camera",
                     "Pinhole camera in OpenCV pixels (0,0 = centre of the "
                     "top-left pixel), world frame = Blender's.")
      .def_static(
          "from_blender",
          [](const py::object& params, const py::kwargs& kwargs) {
            if (params.is_none()) {
              RequireKeywords(kwargs,
                              {"lens_mm", "sensor_width_mm", "sensor_height_mm",
                               "width", "height", "matrix_world"},
                              "from_blender");
            }
            return Camera::FromBlender(
                OptionsFrom<BlenderCameraParams>(params, kwargs));
          },
          py::kw_only(), py::arg("params") = py::none(),
          "Builds the camera from Blender's camera data, the image size in "
          "pixels and the camera object's matrix_world (4x4): "
          "params=BlenderCameraParams and/or its fields as keyword arguments "
          "(lens_mm, sensor_width_mm, sensor_height_mm, width, height and "
          "matrix_world required without params).")
      .def(
          "set_distortion",
          [](Camera& c, const py::object& distortion,
             const py::kwargs& kwargs) {
            if (distortion.is_none()) {
              RequireKeywords(kwargs,
                              {"focal_x_px", "focal_y_px", "principal_x_px",
                               "principal_y_px"},
                              "set_distortion");
            }
            c.SetDistortion(
                OptionsFrom<PolynomialDistortion>(distortion, kwargs));
          },
          py::kw_only(), py::arg("distortion") = py::none(),
          "Blender's polynomial lens distortion; principal point in OpenCV "
          "pixels: distortion=PolynomialDistortion and/or its fields as "
          "keyword arguments (focal and principal point required without "
          "it).")
      .def("resized", &Camera::Resized, py::arg("width"), py::arg("height"),
           "The same camera for its image resized to width x height.")
      .def_property_readonly(
          "has_distortion",
          [](const Camera& c) { return c.distortion().has_value(); })
      .def_property_readonly("K", &Camera::K)
      .def_property_readonly(
          "cam_from_world",
          [](const Camera& c) {
            return Eigen::Matrix4d(c.cam_from_world().matrix());
          })
      .def_property_readonly("center_in_world", &Camera::center_in_world)
      .def_property_readonly("width", &Camera::width)
      .def_property_readonly("height", &Camera::height)
      .def(
          "project",
          [](const Camera& c, const py::array& points) {
            const double* p = CheckArray<double>(points, "points", {-1, 3});
            const py::ssize_t n = points.shape(0);
            py::array_t<double> pixels({n, py::ssize_t{2}});
            py::array_t<bool> in_front(n);
            double* out = pixels.mutable_data();
            bool* front = in_front.mutable_data();
            for (py::ssize_t i = 0; i < n; ++i) {
              Eigen::Vector2d px;
              front[i] = c.WorldToPixel(Eigen::Vector3d(p + 3 * i), &px);
              if (!front[i])
                px.setConstant(std::numeric_limits<double>::quiet_NaN());
              out[2 * i] = px.x();
              out[2 * i + 1] = px.y();
            }
            return py::make_tuple(pixels, in_front);
          },
          py::arg("points").noconvert(),
          "World points (N,3) float64 -> (pixels (N,2), in_front (N,) bool).")
      .def(
          "pixel_rays",
          [](const Camera& c, const py::array& pixels) {
            const double* p = CheckArray<double>(pixels, "pixels", {-1, 2});
            const py::ssize_t n = pixels.shape(0);
            py::array_t<double> rays({n, py::ssize_t{3}});
            double* out = rays.mutable_data();
            for (py::ssize_t i = 0; i < n; ++i) {
              const Eigen::Vector3d r =
                  c.PixelToRayInWorld(Eigen::Vector2d(p[2 * i], p[2 * i + 1]));
              for (int k = 0; k < 3; ++k) out[3 * i + k] = r[k];
            }
            return rays;
          },
          py::arg("pixels").noconvert(),
          "Pixels (N,2) float64 -> unit viewing directions (N,3) in world.");

  py::class_<Scene>(m, "Scene",
                    "Embree BVH of world-space triangles with batched, "
                    "multi-threaded ray queries.")
      .def(py::init([](const py::array& vertices, const py::array& triangles,
                       const py::array& object_ids) {
             const float* v = CheckArray<float>(vertices, "vertices", {-1, 3});
             const int32_t* t =
                 CheckArray<int32_t>(triangles, "triangles", {-1, 3});
             const int32_t* ids = CheckArray<int32_t>(object_ids, "object_ids",
                                                      {triangles.shape(0)});
             py::gil_scoped_release release;
             return Scene(v, vertices.shape(0), t, triangles.shape(0), ids);
           }),
           py::arg("vertices").noconvert(), py::arg("triangles").noconvert(),
           py::arg("object_ids").noconvert(),
           "vertices (V,3) float32, triangles (T,3) int32, object_ids (T,) "
           "int32; the data is copied.")
      .def_property_readonly("num_triangles", &Scene::num_triangles)
      .def_property_readonly("num_vertices", &Scene::num_vertices)
      .def_property_readonly("bounds",
                             [](const Scene& s) {
                               const auto b = s.bounds();
                               return py::make_tuple(
                                   Eigen::Vector3d(b.min().cast<double>()),
                                   Eigen::Vector3d(b.max().cast<double>()));
                             })
      .def(
          "intersect",
          [](const Scene& s, const py::array& origins,
             const py::array& directions, float t_near, float t_far) {
            const float* o = CheckArray<float>(origins, "origins", {-1, 3});
            const float* d = CheckArray<float>(directions, "directions",
                                               {origins.shape(0), 3});
            HitArrays out(origins.shape(0));
            HitBuffers buffers = out.buffers();
            {
              py::gil_scoped_release release;
              s.Intersect(origins.shape(0), o, d, t_near, t_far, buffers);
            }
            return out.ToDict();
          },
          py::arg("origins").noconvert(), py::arg("directions").noconvert(),
          py::arg("t_near") = 0.0f,
          py::arg("t_far") = std::numeric_limits<float>::infinity(),
          (std::string("First hits of rays (N,3) float32. ") + kHitDoc).c_str())
      .def(
          "intersect_pixels",
          [](const Scene& s, const Camera& camera, const py::array& pixels) {
            const double* p = CheckArray<double>(pixels, "pixels", {-1, 2});
            HitArrays out(pixels.shape(0));
            HitBuffers buffers = out.buffers();
            {
              py::gil_scoped_release release;
              s.IntersectPixels(camera, pixels.shape(0), p, buffers);
            }
            return out.ToDict();
          },
          py::arg("camera"), py::arg("pixels").noconvert(),
          (std::string("First hits of the camera rays through pixels (N,2) "
                       "float64. ") +
           kHitDoc)
              .c_str())
      .def(
          "occluded",
          [](const Scene& s, const py::array& origins,
             const py::array& directions, float t_near, float t_far) {
            const float* o = CheckArray<float>(origins, "origins", {-1, 3});
            const float* d = CheckArray<float>(directions, "directions",
                                               {origins.shape(0), 3});
            py::array_t<uint8_t> occluded(origins.shape(0));
            uint8_t* out = occluded.mutable_data();
            {
              py::gil_scoped_release release;
              s.Occluded(origins.shape(0), o, d, t_near, t_far, out);
            }
            return occluded.attr("astype")("bool");
          },
          py::arg("origins").noconvert(), py::arg("directions").noconvert(),
          py::arg("t_near") = 1e-4f,
          py::arg("t_far") = std::numeric_limits<float>::infinity(),
          "True where anything lies on the ray between t_near and t_far.");
}

}  // namespace sunlapse::python
