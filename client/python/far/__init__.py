"""far: Python client of far-daemon (far.Client) and the in-process pipeline (far.Pipeline).

docs/python.md: building, importing from the build tree, the API, thread rules and errors.
far.Pipeline loads OpenGL and EGL; far.Client does not, so it is imported only when first used
(PEP 562 module __getattr__): a simulator that talks to a daemon never loads GL.
"""

from ._errors import (  # noqa: F401
    BusyError,
    Error,
    InternalError,
    InvalidArgumentError,
    IoError,
    LimitExceededError,
    NotFoundError,
    ParseError,
    PermissionDeniedError,
    TimeoutError,
    UnavailableError,
    VersionMismatchError,
    WrongThreadError,
)
from ._result import Penetrations, StepResult  # noqa: F401
from ._client import Client, __version__  # noqa: F401


def __getattr__(name):
    if name == "Pipeline":
        from ._pipeline import Pipeline

        return Pipeline
    raise AttributeError(f"module 'far' has no attribute {name!r}")
