"""Blender's APIs that changed between the versions sunlapse runs in, in one
place: the glue calls these instead of checking versions itself."""


def fcurves(id_data):
    """The F-curve collection animating `id_data` (it has .remove), or None
    when nothing animates it. Blender 3.x-4.5 keep them on the action
    (Action.fcurves); 5.0 removed that for layered actions, whose F-curves
    sit in the channel bag of the datablock's slot."""
    ad = getattr(id_data, "animation_data", None)
    action = ad.action if ad is not None else None
    if action is None:
        return None
    if hasattr(action, "fcurves"):
        return action.fcurves
    from bpy_extras import anim_utils
    bag = anim_utils.action_get_channelbag_for_slot(action, ad.action_slot)
    return None if bag is None else bag.fcurves
