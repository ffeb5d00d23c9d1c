#include "errors.h"

namespace py = pybind11;

namespace far::python {

// The classes are looked up at each raise, not cached in statics: a py::object destroyed after
// the interpreter has finalized would crash at exit, and errors are rare.
void ThrowNamed(const char* class_name, const std::string& message) {
  py::object cls = py::module_::import("far._errors").attr(class_name);
  PyErr_SetString(cls.ptr(), message.c_str());
  throw py::error_already_set();
}

void Throw(const Error& error) {
  py::object by_code = py::module_::import("far._errors").attr("BY_CODE");
  py::object cls =
      by_code.attr("get")(ToString(error.code), py::module_::import("far._errors").attr("Error"));
  PyErr_SetString(cls.ptr(), error.message.c_str());
  throw py::error_already_set();
}

void ThrowArgument(const char* argument, const std::string& what) {
  ThrowNamed("InvalidArgumentError", std::string(argument) + ": " + what);
}

}  // namespace far::python
