"""Guarded import of the compiled core, so the add-on registers without it."""

try:
    from . import _native  # noqa: F401
    IMPORT_ERROR = None
except ImportError as exc:  # the module is missing or built for another Python
    _native = None
    IMPORT_ERROR = str(exc)

BUILD_HINT = ("The native core (_native) is not built. From the sunlapse source "
              "folder run: bash tools/install.sh")


def require():
    """Returns the native module or raises RuntimeError with how to build it."""
    if _native is None:
        raise RuntimeError(f"{BUILD_HINT} ({IMPORT_ERROR})")
    return _native
