#pragma once
// far::Error -> the far.Error subclass of its code (far/_errors.py), with the C++ message.
#include <string>
#include <utility>

#include <pybind11/pybind11.h>

#include "far/base/result.h"

namespace far::python {

/// Raises far._errors.BY_CODE[ToString(error.code)] with error.message. Needs the GIL.
[[noreturn]] void Throw(const Error& error);
/// Raises far.<class_name> (a class of far/_errors.py) with `message`. Needs the GIL.
[[noreturn]] void ThrowNamed(const char* class_name, const std::string& message);
/// An invalid argument: far.InvalidArgumentError("<argument>: <what>").
[[noreturn]] void ThrowArgument(const char* argument, const std::string& what);

inline void Check(const Result<void>& result) {
  if (!result.ok()) Throw(result.error());
}
template <typename T>
T Unwrap(Result<T>&& result) {
  if (!result.ok()) Throw(result.error());
  return std::move(result).value();
}

}  // namespace far::python
