"""One source for the version: blender_manifest.toml. Blender 3.x reads
bl_info by parsing addon/__init__.py and literal-evaluating it (addon_utils),
so bl_info must stay a literal; these tests hold it and the native module to
the manifest."""
import ast
import os
import tomllib

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def manifest_version():
    with open(os.path.join(ROOT, "blender_manifest.toml"), "rb") as fh:
        return tuple(int(part) for part in tomllib.load(fh)["version"].split("."))


def bl_info_as_blender_reads_it():
    path = os.path.join(ROOT, "addon", "__init__.py")
    with open(path, encoding="utf-8") as fh:
        tree = ast.parse(fh.read(), filename=path)
    for node in tree.body:
        if (isinstance(node, ast.Assign) and len(node.targets) == 1
                and getattr(node.targets[0], "id", "") == "bl_info"):
            return ast.literal_eval(node.value)
    raise AssertionError("addon/__init__.py has no top-level bl_info = {...}")


def test_bl_info_version_is_the_manifests():
    assert tuple(bl_info_as_blender_reads_it()["version"]) == manifest_version()


def test_native_module_version_is_the_manifests():
    native = pytest.importorskip("_native")
    assert tuple(int(p) for p in native.__version__.split(".")) == manifest_version()
