"""Scripted sunlapse run: estimate the Sun on every frame of a clip.

Contract (the accuracy benchmarks call it exactly so; extend, never break):

  blender -b SCENE.blend --python-exit-code 1 --python examples/run_estimate.py -- \
      --out TRACK.json [--collection NAME] [--ground NAME ...] [--frames A:B] \
      [--smoothing online|two_pass|physical] [--method thesis|default] \
      [--apply-lamp] [--save OUT.blend] [--render-ar DIR]

Clip, camera and model come from the .blend (active clip, scene camera) unless
given. On failure it prints one line "sunlapse: error: <reason>" on stderr and
exits non-zero; the track file is written only when the run succeeds. The
work is done by the add-on (addon/cli.py), which Blender 4.2+ also offers as
`blender -c sunlapse SCENE.blend --out ...`.
"""

import importlib.util
import os
import sys


def load_sunlapse():
    """The add-on package beside this script (../addon) as module 'sunlapse'."""
    if "sunlapse" in sys.modules:
        return sys.modules["sunlapse"]
    here = os.path.dirname(os.path.abspath(__file__))
    addon_dir = os.path.join(os.path.dirname(here), "addon")
    spec = importlib.util.spec_from_file_location(
        "sunlapse", os.path.join(addon_dir, "__init__.py"),
        submodule_search_locations=[addon_dir])
    module = importlib.util.module_from_spec(spec)
    sys.modules["sunlapse"] = module
    spec.loader.exec_module(module)
    return module


if __name__ == "__main__":
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    load_sunlapse()
    from sunlapse import cli
    sys.exit(cli.main(argv))
