"""far's exceptions: one class per far::ErrorCode, all under far.Error.

Why Python classes (not pybind11's register_exception): both extension modules (_client and
_pipeline) raise the same classes, and a class can have a second, built-in base (ValueError,
TimeoutError, ...) so that code that knows nothing of far can still catch them.
"""


class Error(Exception):
    """An error of the far library; `code` is far::ErrorCode's name ("invalid_argument", ...),
    the message is the C++ library's message, unchanged."""

    code = None


class InvalidArgumentError(Error, ValueError):
    """A value is malformed or out of its domain; also a NumPy array of the wrong dtype, shape
    or layout (the message starts with the argument's name)."""

    code = "invalid_argument"


class ParseError(Error, ValueError):
    code = "parse_error"


class IoError(Error, OSError):
    code = "io_error"


class NotFoundError(Error, LookupError):
    code = "not_found"


class LimitExceededError(Error):
    code = "limit_exceeded"


class UnavailableError(Error):
    """No daemon (or it went away), no GL context, a closed session."""

    code = "unavailable"


class BusyError(Error):
    code = "busy"


class PermissionDeniedError(Error, PermissionError):
    code = "permission_denied"


class TimeoutError(Error, TimeoutError):  # noqa: A001 (far.TimeoutError is also the built-in's)
    code = "timeout"


class VersionMismatchError(Error):
    code = "version_mismatch"


class InternalError(Error):
    code = "internal"


class WrongThreadError(Error):
    """A far.Pipeline used from a thread other than the one that made it (its GL context is
    current on that thread only). Not a far::ErrorCode: the binding checks it."""

    code = "wrong_thread"


# The C++ binding looks classes up here by far::ErrorCode's ToString name.
BY_CODE = {
    cls.code: cls
    for cls in (
        InvalidArgumentError,
        ParseError,
        IoError,
        NotFoundError,
        LimitExceededError,
        UnavailableError,
        BusyError,
        PermissionDeniedError,
        TimeoutError,
        VersionMismatchError,
        InternalError,
        WrongThreadError,
    )
}
