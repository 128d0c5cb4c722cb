"""Scripted sunlapse run: estimate the Sun on every frame of a clip.

Contract (the accuracy benchmarks call it exactly so; extend, never break):

  blender -b SCENE.blend --python-exit-code 1 --python examples/run_estimate.py -- \
      --out TRACK.json [--collection NAME] [--ground NAME ...] [--frames A:B] \
      [--smoothing online|two_pass|physical] [--method thesis|default] \
      [--apply-lamp] [--save OUT.blend] [--render-ar DIR]

Clip, camera and model come from the .blend (active clip, scene camera) unless
given. On failure it prints one line "sunlapse: error: <reason>" on stderr and
exits non-zero; the track file is written only when the run succeeds.
"""

import argparse
import importlib.util
import os
import sys
import time

EXIT_USAGE = 2
EXIT_SCENE = 3
EXIT_INTERNAL = 4


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


def parse_args(argv):
    p = argparse.ArgumentParser(prog="run_estimate.py",
                                description="Estimate the Sun on a clip.")
    p.add_argument("--out", required=True, help="track file to write (*.sun.json)")
    p.add_argument("--collection", help="collection holding the model")
    p.add_argument("--ground", nargs="+", default=[], help="ground object name(s)")
    p.add_argument("--frames", help="frame range A:B (scene frames, inclusive)")
    p.add_argument("--smoothing", choices=["online", "two_pass", "physical"],
                   default="two_pass")
    p.add_argument("--method", choices=["thesis", "default"], default="default")
    p.add_argument("--apply-lamp", action="store_true",
                   help="keyframe a Sun lamp from the track")
    p.add_argument("--save", help="save the .blend here afterwards")
    p.add_argument("--render-ar", metavar="DIR", help="render the AR composite here")
    return p.parse_args(argv)


def parse_frames(text, clip):
    if not text:
        return clip.frame_start, clip.frame_end
    try:
        a, b = (int(v) for v in text.split(":"))
    except ValueError:
        raise ValueError(f"--frames must be A:B with integers, got '{text}'")
    if a > b:
        raise ValueError(f"--frames {text}: start after end")
    if a < clip.frame_start or b > clip.frame_end:
        raise ValueError(f"--frames {text} outside the clip's frames "
                         f"{clip.frame_start}:{clip.frame_end}")
    return a, b


def fail(code, message):
    sys.stderr.write(f"sunlapse: error: {message}\n")
    sys.stderr.flush()
    sys.exit(code)


def main(argv):
    import bpy
    sunlapse = load_sunlapse()
    from sunlapse import bridge, native_loader
    from sunlapse.core import trackfile

    args = parse_args(argv)
    try:
        native_loader.require()
    except RuntimeError as e:
        fail(EXIT_INTERNAL, str(e))
    context = bpy.context
    collection = None
    if args.collection:
        collection = bpy.data.collections.get(args.collection)
        if collection is None:
            fail(EXIT_USAGE, f"no collection named '{args.collection}'")
    try:
        clip = bridge.gather_clip(context)
        frames = parse_frames(args.frames, clip)
        movieclip = bridge.active_movieclip(context)
        cam = bridge.gather_camera(context, None, clip, movieclip)
        model = bridge.gather_model(context, collection)
        missing = [g for g in args.ground if g not in model.names]
        if missing:
            raise bridge.SceneError(f"ground object(s) not in the model: {', '.join(missing)}")
        ground = args.ground or bridge.guess_ground(model)
        t0 = time.perf_counter()
        native_scene = bridge.build_scene(model)
        native_camera = bridge.build_camera(cam)
        t_bvh = time.perf_counter() - t0
    except bridge.SceneError as e:
        fail(EXIT_SCENE, str(e))
    except ValueError as e:
        fail(EXIT_USAGE, str(e))
    for w in cam.warnings:
        print(f"sunlapse: warning: {w}")

    print(f"sunlapse: model {model.num_triangles} triangles, {len(model.names)} "
          f"objects, BVH {t_bvh:.3f} s; camera '{cam.name}'; clip '{clip.name}' "
          f"{clip.width}x{clip.height} frames {frames[0]}:{frames[1]}; ground: "
          f"{', '.join(ground) or 'none found'}")

    from sunlapse import pipeline
    if args.smoothing == "physical":
        fail(EXIT_USAGE, "--smoothing physical is not implemented yet; use online or two_pass")
    options = pipeline.RunOptions(method=args.method, smoothing=args.smoothing,
                                  north_offset_deg=bridge.scene_north_offset_deg(context),
                                  ground_object_ids=model.ids_of(ground))
    frame_numbers = list(range(frames[0], frames[1] + 1))
    try:
        track = pipeline.run(native_scene, native_camera, clip.filepath, clip.frame_start,
                             frame_numbers, options)
    except pipeline.PipelineError as e:
        fail(EXIT_SCENE, str(e))
    track.clip = clip.filepath
    track.method["options"].update({"method": args.method, "frames": list(frames),
                                    "ground": ground})
    trackfile.write_track(args.out, track)
    init = track.initial
    if init:
        print(f"sunlapse: initial Sun zenith {init['zenith_deg']:.2f} azimuth "
              f"{init['azimuth_deg']:.2f} deg (confidence {init['confidence']:.2f}, "
              f"{init['seconds']:.2f} s){' - ' + init['message'] if init.get('message') else ''}")
    else:
        print(f"sunlapse: warning: {track.frames[0].reason}")
    done = sum(1 for f in track.frames if f.has_estimate)
    print(f"sunlapse: {done}/{len(track.frames)} frames estimated; wrote {args.out}")
    for flag, value in (("--apply-lamp", args.apply_lamp), ("--render-ar", args.render_ar)):
        if value:
            print(f"sunlapse: warning: {flag} is not implemented yet; ignored")
    if args.save:
        bpy.ops.wm.save_as_mainfile(filepath=os.path.abspath(args.save), copy=True)
        print(f"sunlapse: saved {args.save}")


if __name__ == "__main__":
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    try:
        main(argv)
    except SystemExit:
        raise
    except Exception as e:  # an internal bug: still one line, non-zero exit
        import traceback
        traceback.print_exc()
        fail(EXIT_INTERNAL, f"internal error: {type(e).__name__}: {e}")
