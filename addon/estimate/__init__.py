"""The estimate: frames of a clip in, a track out (bpy-free, over _native).

run.run validates a run and dispatches it: the whole-clip controller
(whole_clip.py, ours) or the thesis's baseline (thesis.py); finish.py
smooths each segment; notes.py looks for shadows the model does not cast.
"""
