"""Scripted sunlapse run: estimate the Sun on every frame of a clip.

Contract (the accuracy benchmarks call it exactly so; extend, never break):

  blender -b SCENE.blend --python-exit-code 1 --python examples/run_estimate.py -- \
      --out TRACK.json [--collection NAME] [--ground NAME ...] [--frames A:B] \
      [--smoothing online|two_pass|physical] [--method thesis|default] \
      [--apply-lamp] [--save OUT.blend] [--render-ar DIR] \
      [--times CSV] [--latitude DEG] [--longitude DEG] [--date YYYY-MM-DD] \
      [--start-time HH:MM[:SS]] [--utc-offset HOURS] [--frame-seconds S] \
      [--fit-latitude | --fixed-latitude] [--initial-sun ZENITH AZIMUTH]
      [--uncalibrated-confidence] [--refine-model | --no-refine-model]
      [--apply-model-corrections]

Flags:
  --out TRACK.json      the track file to write (*.sun.json; docs/track-format.md)
  --collection NAME     the collection holding the model (default: every visible mesh)
  --ground NAME ...     the object(s) the shadows fall on (default: the panel's
                        Ground, else the one the add-on finds)
  --frames A:B          scene frames to estimate, inclusive (default: the clip's)
  --smoothing MODE      two_pass (default), online, or physical (the Sun's true
                        path: needs the place and the frames' times)
  --method METHOD       default (the whole clip at once) or thesis (the baseline)
  --apply-lamp          keyframe a Sun lamp from the track
  --save OUT.blend      save the .blend here afterwards
  --render-ar DIR       render the AR composite into DIR
  --times CSV           each frame's capture time (columns frame,local_time or
                        utc_time; core/frametimes.py): frames are tracked in
                        capture order and smoothed over real time
  --latitude DEG        place, north positive      } physical smoothing; default:
  --longitude DEG       place, east positive       } the frames' GPS, the panel's
  --date YYYY-MM-DD     the first frame's local date  } values, else Blender's
  --start-time HH:MM    the first frame's local time  } Sun Position add-on's
  --utc-offset HOURS    the local times' offset from UTC (e.g. 2 for CEST)
  --frame-seconds S     seconds between frames
  --fit-latitude        fit the latitude too, near the given one (default: the
                        panel's Fit Latitude, off unless set: the latitude is
                        used as given)
  --fixed-latitude      use the given latitude as given: the default since
                        issue 25, kept so that scripts that pass it still run
                        With the frames' times (--times, a times file or EXIF
                        times), the place (--latitude and --longitude, else the
                        GPS, else the panel's when not 0, 0) also says which
                        frames are night, whatever the smoothing: those get no
                        direct sunlight and the Sun the ephemeris puts there
  --initial-sun Z A     start from this Sun on the first frame (degrees, azimuth
                        as in the track file) instead of estimating it: measures
                        the tracker alone
  --uncalibrated-confidence
                        write each frame's support as the estimator computes
                        it, not the probability (0-1) that its Sun is within
                        2 deg, which is the default; for refitting that
                        calibration (bench/calibrate.py). The track's
                        method.confidence says which one a file holds
  --refine-model        refine the hand-made model by the clip first (the
                        default, unless the scene's Refine Model is off;
                        static cameras and the default method only): each
                        object in view moved, turned and scaled, the camera
                        turned and zoomed, so that the model's edges fall on
                        the edges that stay put in the footage; used only
                        where the model is clearly off and the fit clearly
                        puts it back. The estimate then uses the refined
                        model, keeps every frame's confidence below 0.5 (a
                        hand-made model's remaining error biases every frame)
                        unless the refined model's shadows then fit the
                        footage closely, and says so; the track's extra.model_refinement lists
                        each correction (object_id indexes
                        method.options.model_objects). The .blend is not
                        changed
  --no-refine-model     use the model as it is, without the refinement
  --apply-model-corrections
                        apply the corrections the estimate used to the open
                        .blend's objects and camera (kept with --save, used
                        by --render-ar); objects moved by keys, drivers or
                        constraints are left as they are and named; a note
                        says when the clip left the model as it was

Clip, camera and model come from the .blend (active clip, scene camera) unless
given. On failure it prints one line "sunlapse: error: <reason>" on stderr and
exits non-zero (2 a bad flag or file, 3 the scene or clip lacks something, 4 an
internal error or an incomplete install: no native core, or a Blender Python
without numpy; 130 interrupted); the track file is written only when the run
succeeds. The work is done by the add-on (addon/cli.py), which Blender 4.2+
also offers as `blender -c sunlapse SCENE.blend --out ...`.
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
    sunlapse = load_sunlapse()
    if sunlapse.BROKEN:  # a Blender Python that cannot run the add-on (no numpy)
        sunlapse.broken.reason = sunlapse.BROKEN
        sys.exit(sunlapse.broken.command(argv))
    from sunlapse import cli
    sys.exit(cli.main(argv))
