"""The one Estimate Sun run of this Blender session (a second would race the
first for the stored track): its state, read by the panels and the status
bar, and written by the modal operator and its worker thread."""

import threading
import time

import bpy

RUN = {"running": False, "fraction": 0.0, "cancel": False, "outcome": None, "drawn": 0}
# A run whose modal handler has not ticked for this long is taken as ended.
STALE_RUN_S = 10.0


def running() -> bool:
    """Whether a run goes on (one whose handler stopped ticking, after an
    error, is taken as ended)."""
    if RUN["running"] and RUN.get("thread") is not None and \
            time.monotonic() - RUN.get("tick", 0.0) > STALE_RUN_S:
        RUN["running"] = False
    return RUN["running"]


def redraw_all():
    wm = bpy.context.window_manager
    for win in wm.windows:
        for area in win.screen.areas:
            if area.type in ("CLIP_EDITOR", "VIEW_3D", "STATUSBAR"):
                area.tag_redraw()


# What the user is told when the file a run belonged to was closed under it.
CLOSED_NOTICE = ("Estimate Sun stopped: its file was closed before it finished; "
                 "nothing was written")


class Worker:
    """Runs `work(progress)` on a thread, keeping its result or exception
    here, in plain Python: the operator that started it is freed with its
    file, and a thread that wrote to it then would raise ReferenceError."""

    def __init__(self, work):
        self.result = None
        self.error = None

        def progress(fraction):
            RUN["fraction"] = fraction
            return not RUN["cancel"]

        def body():
            try:
                self.result = work(progress)
            except Exception as e:  # noqa: BLE001 -- reported on the main thread
                self.error = e

        self.thread = threading.Thread(target=body, name="sunlapse-estimate", daemon=True)
        self.thread.start()
        RUN["thread"] = self.thread

    def alive(self) -> bool:
        return self.thread.is_alive()


def file_closed():
    """The file of a running estimate closes (Blender cancels the modal
    operator): the worker is told to stop, and the next file loaded says
    why the run vanished (tell_after_load)."""
    RUN["cancel"] = True
    RUN["outcome"] = "cancelled: the file was closed"
    RUN["notice"] = CLOSED_NOTICE
    print(f"sunlapse: {CLOSED_NOTICE}", flush=True)


@bpy.app.handlers.persistent
def tell_after_load(*_):
    """After a file loads, shows a pending notice in the status bar (through
    the internal report operator: only operators can report)."""
    notice = RUN.pop("notice", None)
    if notice is None or bpy.app.background:
        return

    def report():
        try:
            bpy.ops.clip.sunlapse_notice(message=notice)
        except RuntimeError:  # no window to report in
            pass
        return None

    bpy.app.timers.register(report, first_interval=0.2)
