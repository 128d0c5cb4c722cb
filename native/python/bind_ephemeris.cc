// Bindings of the ephemeris stage.
#include <pybind11/pybind11.h>

#include "sunlapse/ephemeris/sun_position.h"

namespace py = pybind11;

namespace sunlapse::python {

void BindEphemeris(py::module_& m) {
  m.def(
      "sun_position",
      [](int year, int month, int day, int hour, int minute, double second,
         double latitude_deg, double longitude_deg, double elevation_m,
         double pressure_hpa, double temperature_c, double relative_humidity,
         double dut1_s) {
        SunPositionOptions o;
        o.elevation_m = elevation_m;
        o.pressure_hpa = pressure_hpa;
        o.temperature_c = temperature_c;
        o.relative_humidity = relative_humidity;
        o.dut1_s = dut1_s;
        const SunPosition s =
            SunPositionAt({year, month, day, hour, minute, second},
                          latitude_deg, longitude_deg, o);
        return py::make_tuple(s.zenith_deg, s.azimuth_deg);
      },
      py::arg("year"), py::arg("month"), py::arg("day"), py::arg("hour"),
      py::arg("minute"), py::arg("second"), py::arg("latitude_deg"),
      py::arg("longitude_deg"), py::arg("elevation_m") = 0.0,
      py::arg("pressure_hpa") = 1013.25, py::arg("temperature_c") = 15.0,
      py::arg("relative_humidity") = 0.0, py::arg("dut1_s") = 0.0,
      "Apparent topocentric Sun at a UTC instant: (zenith_deg, azimuth_deg), "
      "azimuth clockwise from north. pressure_hpa=0 turns refraction off.");
}

}  // namespace sunlapse::python
