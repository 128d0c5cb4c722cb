"""The add-on in a real Blender window (Xvfb): the modal Estimate Sun with its
worker thread, Esc to cancel, and the overlay drawn over the clip."""
import os
import shutil
import subprocess

import numpy as np
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))


def blender_ui(*args, timeout=180):
    if shutil.which("xvfb-run") is None:
        pytest.fail("xvfb-run is missing: tools/install.sh installs xvfb")
    cmd = ["xvfb-run", "-a", "-s", "-screen 0 1280x800x24", "blender", "--factory-startup", *args]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    out = str(tmp_path_factory.mktemp("ui"))
    proc = subprocess.run(["blender", "-b", "--factory-startup", "--python-exit-code", "1",
                           "--python", os.path.join(ROOT, "examples", "generate_scene.py"), "--",
                           "--preset", "plaza", "--out", out, "--tiny"],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return out


def results(proc):
    return {l.split()[1]: l.split(None, 2)[2] for l in proc.stdout.splitlines()
            if l.startswith("RESULT ")}


def fresh_copy(scene, tmp_path):
    dst = str(tmp_path / "scene")
    shutil.copytree(scene, dst)
    return os.path.join(dst, "scene.blend")


def test_modal_estimate_runs_in_the_background_and_the_overlay_draws(scene, tmp_path):
    shot = str(tmp_path / "shot.png")
    proc = blender_ui(fresh_copy(scene, tmp_path), "--python", os.path.join(HERE, "ui_script.py"),
                      "--", "modal", shot)
    r = results(proc)
    assert r.get("invoke") == "{'RUNNING_MODAL'}", proc.stdout[-2000:] + proc.stderr[-2000:]
    assert r.get("stored") == "True" and r.get("apply") == "{'FINISHED'}"
    assert r.get("screenshot") == "True"
    import matplotlib.image as mpimg
    img = mpimg.imread(shot)[..., :3]
    # The overlay's shadow segment is drawn in yellow (1.0, 0.9, 0.1).
    yellow = (img[..., 0] > 0.9) & (img[..., 1] > 0.8) & (img[..., 2] < 0.3)
    assert yellow.sum() > 10


def test_esc_cancels_and_changes_nothing(scene, tmp_path):
    proc = blender_ui("--enable-event-simulate", fresh_copy(scene, tmp_path), "--python",
                      os.path.join(HERE, "ui_script.py"), "--", "esc", str(tmp_path / "x.png"))
    r = results(proc)
    assert r.get("invoke") == "{'RUNNING_MODAL'}", proc.stdout[-2000:] + proc.stderr[-2000:]
    assert r.get("stored") == "False"
