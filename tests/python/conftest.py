import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
# bpy-free modules of the add-on, importable without Blender.
sys.path.insert(0, os.path.join(ROOT, "addon"))
# The add-on's package without its bpy registration (addon/__init__.py), so
# that its bpy-free packages (estimate/, core/) import each other relatively.
if "sunlapse" not in sys.modules:
    import types

    _package = types.ModuleType("sunlapse")
    _package.__path__ = [os.path.join(ROOT, "addon")]
    sys.modules["sunlapse"] = _package
    # One copy of the compiled module: tests import it as `_native` (addon/
    # is on the path); loading it again under a second name would register
    # its types twice.
    try:
        import _native
    except ImportError:  # not built: the tests that need it skip
        pass
    else:
        sys.modules.setdefault("sunlapse._native", _native)
