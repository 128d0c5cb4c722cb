"""The Blender glue library (bpy): the scene gathered into a run job, place
and time, the track stored in the .blend, the lamp and sky keyed, exports,
the AR render and the background job. The operators, panels, overlay and
CLI are thin leaves over it; the estimate itself is bpy-free (estimate/)."""
