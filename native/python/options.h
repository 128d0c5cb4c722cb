// Option structs bound as Python classes: fields by def_readwrite (the
// defaults live in C++), keyword construction, check() and a repr. Functions
// that take options accept the struct (options=...) and/or keyword arguments
// naming its fields, forwarded into a copy (OptionsFrom), so callers written
// against the older keyword signatures keep working.
#pragma once

#include <pybind11/pybind11.h>

#include <algorithm>
#include <string>
#include <vector>

namespace sunlapse::python {

namespace py = pybind11;

// The Python names of an options struct's fields, in binding order.
template <typename O>
std::vector<std::string>& OptionFieldNames() {
  static std::vector<std::string> names;
  return names;
}

template <typename O>
std::string OptionFieldList() {
  std::string out;
  for (const std::string& name : OptionFieldNames<O>()) {
    out += (out.empty() ? "" : ", ") + name;
  }
  return out;
}

// A copy of `base` with every keyword argument set on the field it names.
// An unknown name or a value of the wrong type is a TypeError naming the
// field and what is valid.
template <typename O>
O OptionsFrom(const O& base, const py::kwargs& kwargs) {
  if (kwargs.empty()) return base;
  py::object obj = py::cast(base, py::return_value_policy::copy);
  const std::vector<std::string>& names = OptionFieldNames<O>();
  const std::string type_name =
      py::str(py::type::handle_of(obj).attr("__name__"));
  for (const auto& item : kwargs) {
    const std::string key = py::str(item.first);
    if (std::find(names.begin(), names.end(), key) == names.end()) {
      throw py::type_error("unexpected keyword argument '" + key +
                           "'; valid: " + OptionFieldList<O>() + " (" +
                           type_name + ")");
    }
    try {
      py::setattr(obj, item.first, item.second);
    } catch (py::error_already_set& e) {
      if (!e.matches(PyExc_TypeError)) throw;
      const py::object current = obj.attr(item.first);
      throw py::type_error(
          key + ": expected " +
          std::string(py::str(py::type::handle_of(current).attr("__name__"))) +
          " like its default " + std::string(py::repr(current)) + ", got " +
          std::string(
              py::str(py::type::handle_of(item.second).attr("__name__"))));
    }
  }
  return obj.cast<O>();
}

// `options` (None or an O) with the keyword arguments applied.
template <typename O>
O OptionsFrom(const py::object& options, const py::kwargs& kwargs) {
  return OptionsFrom<O>(options.is_none() ? O() : options.cast<O>(), kwargs);
}

// py::class_ for an options struct; fields are added with field() /
// field_property() so that keyword forwarding knows their names.
template <typename O>
class OptionsClass : public py::class_<O> {
 public:
  OptionsClass(py::handle scope, const char* name, const char* doc)
      : py::class_<O>(scope, name, doc) {
    this->def(py::init([](const py::kwargs& kwargs) {
                return OptionsFrom<O>(O(), kwargs);
              }),
              "Defaults from C++; keyword arguments set fields.");
    this->def(
        "check", [](const O& o) { o.Check(); },
        "Raises ValueError naming the first bad field.");
    this->def("__repr__", [](const py::object& self) {
      std::string out = py::str(py::type::handle_of(self).attr("__name__"));
      out += "(";
      bool first = true;
      for (const std::string& name : OptionFieldNames<O>()) {
        out += (first ? "" : ", ") + name + "=" +
               std::string(py::repr(self.attr(name.c_str())));
        first = false;
      }
      return out + ")";
    });
  }

  template <typename T>
  OptionsClass& field(const char* name, T O::*member, const char* doc) {
    this->def_readwrite(name, member, doc);
    OptionFieldNames<O>().push_back(name);
    return *this;
  }

  // A field converted at the boundary (an enum as its Python string).
  template <typename Get, typename Set>
  OptionsClass& field_property(const char* name, Get get, Set set,
                               const char* doc) {
    this->def_property(name, get, set, doc);
    OptionFieldNames<O>().push_back(name);
    return *this;
  }
};

}  // namespace sunlapse::python
