"""Blender's APIs that changed between the versions sunlapse runs in, in one
place: the glue calls these instead of checking versions itself."""

import os

import bpy


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


def clip_overlay_panel():
    """The Movie Clip Editor's popover for what is drawn over the clip: its
    Overlays popover where there is one (4.2+), else Display."""
    return getattr(bpy.types, "CLIP_PT_overlay", None) or bpy.types.CLIP_PT_display


def uniform_color_shader():
    """The built-in flat-colour shader: 'UNIFORM_COLOR' where it exists
    (4.0 removed the '2D_' name), '2D_UNIFORM_COLOR' before."""
    import gpu
    try:
        return gpu.shader.from_builtin("UNIFORM_COLOR")
    except ValueError:
        return gpu.shader.from_builtin("2D_UNIFORM_COLOR")


def font_size(size):
    """Sets the UI font's size for blf drawing: 4.0 dropped the dpi argument."""
    import blf
    if bpy.app.version >= (4, 0, 0):
        blf.size(0, size)
    else:
        blf.size(0, size, 72)


def label_points(context):
    """The UI font's size for labels, in points: the style's widget_label
    before 5.0, widget from 5.0 (which merged the two)."""
    style = context.preferences.ui_styles[0]
    return (getattr(style, "widget_label", None) or style.widget).points


def compositor_tree(scene, create=True):
    """The scene's compositor node tree, made when `create` and missing.
    Before 5.0 it is scene.node_tree (with use_nodes on); 5.0 made it a node
    group data-block of its own, scene.compositing_node_group."""
    if hasattr(scene, "compositing_node_group"):
        tree = scene.compositing_node_group
        if create:
            if tree is None:
                tree = bpy.data.node_groups.new(f"{scene.name} Compositing",
                                                "CompositorNodeTree")
                scene.compositing_node_group = tree
            # A 3.x/4.x file saved with use_nodes off opens in 5.x with
            # compositing off: the tree would be skipped.
            scene.render.use_compositing = True
        return tree
    if create:
        scene.use_nodes = True
        scene.render.use_compositing = True
    return scene.node_tree


def composite_input(tree):
    """The socket the final image goes into: the Composite node's (before
    5.0), or the tree's Group Output 'Image' (from 5.0, which removed the
    Composite node). The node is made when missing."""
    if hasattr(bpy.types, "CompositorNodeComposite"):
        node = next((n for n in tree.nodes if n.bl_idname == "CompositorNodeComposite"), None) \
            or tree.nodes.new("CompositorNodeComposite")
        return node, node.inputs["Image"]
    if not any(item.item_type == "SOCKET" and item.in_out == "OUTPUT" and item.name == "Image"
               for item in tree.interface.items_tree):
        tree.interface.new_socket("Image", in_out="OUTPUT", socket_type="NodeSocketColor")
    node = next((n for n in tree.nodes if n.bl_idname == "NodeGroupOutput"), None) \
        or tree.nodes.new("NodeGroupOutput")
    return node, node.inputs["Image"]


def multiply_node(tree):
    """A colour Multiply node: (node, input A, input B, output). Mix RGB
    before 5.0; 5.0 dropped it from the compositor for the shared Mix node,
    whose sockets of each data type share names (so: by identifier)."""
    if hasattr(bpy.types, "CompositorNodeMixRGB"):
        node = tree.nodes.new("CompositorNodeMixRGB")
        node.blend_type = "MULTIPLY"
        node.inputs[0].default_value = 1.0
        return node, node.inputs[1], node.inputs[2], node.outputs[0]
    node = tree.nodes.new("ShaderNodeMix")
    node.data_type = "RGBA"
    node.blend_type = "MULTIPLY"
    sockets = {s.identifier: s for s in node.inputs}
    sockets["Factor_Float"].default_value = 1.0
    result = next(s for s in node.outputs if s.identifier == "Result_Color")
    return node, sockets["A_Color"], sockets["B_Color"], result


def alpha_over_inputs(node):
    """(background, foreground) of an Alpha Over node: named from 5.0,
    both 'Image' (after the factor) before."""
    if "Background" in node.inputs:
        return node.inputs["Background"], node.inputs["Foreground"]
    return node.inputs[1], node.inputs[2]


def file_output(tree, folder, name):
    """A File Output node writing one 32-bit EXR input called `name` into
    `folder`: (node, its input, the path of frame f as a function). 5.0
    renamed base_path/file_slots to directory/file_name/file_output_items."""
    node = tree.nodes.new("CompositorNodeOutputFile")
    if hasattr(node, "file_output_items"):
        node.directory = folder
        node.file_name = ""
        node.format.media_type = "IMAGE"  # the default is a multilayer EXR
        node.format.file_format = "OPEN_EXR"
        node.format.color_depth = "32"
        node.file_output_items.clear()
        node.file_output_items.new("RGBA", name)
    else:
        node.base_path = folder
        node.format.file_format = "OPEN_EXR"
        node.format.color_depth = "32"
        node.file_slots.clear()
        node.file_slots.new(name)
    return node, node.inputs[name], lambda frame: _output_file(folder, name, frame)


def _output_file(folder, name, frame):
    """The file the File Output node wrote for frame `frame`: NAME0012.exr
    before 5.0, NAME.exr for a still from 5.0 (looked up, not assumed)."""
    numbered = os.path.join(folder, f"{name}{frame:04d}.exr")
    still = os.path.join(folder, f"{name}.exr")
    return still if os.path.exists(still) and not os.path.exists(numbered) else numbered
