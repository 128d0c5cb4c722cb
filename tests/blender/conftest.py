"""Fixtures for tests that run inside Blender (see run_pytest.py)."""
import os
import sys

import bpy
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "examples"))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import run_estimate  # noqa: E402

sunlapse = run_estimate.load_sunlapse()


@pytest.fixture
def empty_scene():
    """A fresh empty file, with the add-on registered."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    if not hasattr(bpy.types.Scene, "sunlapse"):
        sunlapse.register()
    yield bpy.context.scene
    bpy.ops.wm.read_factory_settings(use_empty=True)


@pytest.fixture(scope="session")
def native():
    from sunlapse.estimate import native_loader
    return native_loader.require()


_generated = {}


def generate_preset(preset, tmp_path_factory, *extra):
    """Renders a tiny preset once per test session; returns (folder, truth)."""
    import subprocess
    from sunlapse.core import trackfile
    key = (preset,) + extra
    if key not in _generated:
        out = str(tmp_path_factory.mktemp(preset))
        cmd = [bpy.app.binary_path, "-b", "--factory-startup", "--python-exit-code", "1",
               "--python", os.path.join(ROOT, "examples", "generate_scene.py"), "--",
               "--preset", preset, "--out", out, "--tiny", *extra]
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
        assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
        _generated[key] = out
    out = _generated[key]
    return out, trackfile.read_track(os.path.join(out, "truth.sun.json"))


@pytest.fixture(scope="session")
def tiny_plaza(tmp_path_factory):
    return generate_preset("plaza", tmp_path_factory)


@pytest.fixture(scope="session")
def long_plaza(tmp_path_factory):
    # Five small frames 40 minutes apart: the shadows move between them, so
    # their median is the ground without shadows.
    return generate_preset("plaza", tmp_path_factory, "--frames", "5", "--minutes-per-frame", "40",
                           "--resolution", "256x192")
