// Bindings of the ephemeris stage.
#include <pybind11/pybind11.h>

#include "options.h"
#include "sunlapse/ephemeris/sun_position.h"

namespace py = pybind11;

namespace sunlapse::python {

void BindEphemeris(py::module_& m) {
  OptionsClass<SunPositionOptions>(m, "SunPositionOptions",
                                   "Options of sun_position.")
      .field("elevation_m", &SunPositionOptions::elevation_m,
             "Observer's height above the ellipsoid, metres.")
      .field("pressure_hpa", &SunPositionOptions::pressure_hpa,
             "Air pressure, hPa; 0 turns refraction off.")
      .field("temperature_c", &SunPositionOptions::temperature_c,
             "Air temperature, degrees Celsius.")
      .field("relative_humidity", &SunPositionOptions::relative_humidity,
             "Relative humidity, 0..1.")
      .field("dut1_s", &SunPositionOptions::dut1_s, "UT1 - UTC, seconds.");
  m.def(
      "sun_position",
      [](int year, int month, int day, int hour, int minute, double second,
         double latitude_deg, double longitude_deg, const py::object& options,
         const py::kwargs& kwargs) {
        const SunPositionOptions o =
            OptionsFrom<SunPositionOptions>(options, kwargs);
        const SunPosition s =
            SunPositionAt({year, month, day, hour, minute, second},
                          latitude_deg, longitude_deg, o);
        return py::make_tuple(s.zenith_deg, s.azimuth_deg);
      },
      py::arg("year"), py::arg("month"), py::arg("day"), py::arg("hour"),
      py::arg("minute"), py::arg("second"), py::arg("latitude_deg"),
      py::arg("longitude_deg"), py::kw_only(), py::arg("options") = py::none(),
      "Options: options=SunPositionOptions and/or its fields as keyword "
      "arguments (elevation_m, pressure_hpa, ...). Apparent topocentric Sun at "
      "a UTC instant: (zenith_deg, azimuth_deg), "
      "azimuth clockwise from north. pressure_hpa=0 turns refraction off.");
}

}  // namespace sunlapse::python
