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
    from sunlapse import native_loader
    return native_loader.require()
