"""The add-on's layers as docs/design.md describes them: no import circle in
addon/, nothing bpy-free at the add-on's root, no policy decided by matching
message text, and no Python constant that copies a native default."""
import ast
import os
import re

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
ADDON = os.path.join(ROOT, "addon")
# The bpy-free packages: the Blender glue never lives in them.
BPY_FREE = ("core", "estimate")


def addon_modules():
    """{module name relative to the add-on ("estimate.run"): path}."""
    out = {}
    for folder, _, files in os.walk(ADDON):
        for f in files:
            if f.endswith(".py"):
                rel = os.path.relpath(os.path.join(folder, f), ADDON)[:-3].replace(os.sep, ".")
                if rel == "__init__" or rel.endswith(".__init__"):
                    rel = rel[:-len("__init__")].rstrip(".")
                out[rel] = os.path.join(folder, f)
    return out


def imports_of(name, path, known):
    """The add-on's modules that `name` imports, anywhere in it (an import
    inside a function ties the modules as much as one at the top)."""
    package = name if path.endswith("__init__.py") else name.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(open(path).read(), path)):
        if isinstance(node, ast.ImportFrom) and node.level > 0:
            base = package.split(".") if package else []
            base = base[:len(base) - (node.level - 1)] if node.level > 1 else base
            target = ".".join(base + ([node.module] if node.module else []))
            for alias in node.names:
                sub = f"{target}.{alias.name}" if target else alias.name
                if sub in known:
                    found.add(sub)
                elif target in known:
                    found.add(target)
    found.discard(name)
    return found


def test_no_import_circle_in_the_addon():
    modules = addon_modules()
    graph = {m: imports_of(m, p, modules) for m, p in modules.items()}
    # A module that takes a name from its own package's __init__ (the
    # add-on's register) is no circle: the package holds the module.
    circles = []
    state = {}

    def visit(m, stack):
        state[m] = "open"
        for n in sorted(graph[m]):
            if n == "" or m.startswith(n + "."):
                continue
            if state.get(n) == "open":
                circles.append(stack[stack.index(n):] + [n])
            elif n not in state:
                visit(n, stack + [n])
        state[m] = "done"
    for m in sorted(graph):
        if m not in state:
            visit(m, [m])
    assert not circles, "import circles: " + "; ".join(" -> ".join(c) for c in circles)


def test_the_bpy_free_packages_do_not_import_blender():
    for name, path in addon_modules().items():
        if name.split(".")[0] not in BPY_FREE:
            continue
        for node in ast.walk(ast.parse(open(path).read(), path)):
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0:
                names = [node.module or ""]
            else:
                continue
            # native_loader may ask a running Blender its version, guarded.
            if name == "estimate.native_loader":
                continue
            assert not any(n.split(".")[0] in ("bpy", "mathutils", "bpy_extras", "gpu", "blf")
                           for n in names), (name, names)


def test_nothing_bpy_free_at_the_addon_root():
    """Every module at the root imports bpy (it is glue); the bpy-free code
    lives in the packages."""
    for f in os.listdir(ADDON):
        if not f.endswith(".py"):
            continue
        text = open(os.path.join(ADDON, f)).read()
        assert re.search(r"^\s*import bpy\b|^\s*from bpy\b", text, re.M), \
            f"addon/{f} does not import bpy: a bpy-free module belongs in a package"


# Comparing a stage's message (or an exception's text) with a literal is
# deciding a policy by what a sentence says: statuses are types.
MESSAGE_MATCH = re.compile(
    r"""((\b(message|reason|msg)|str\([\w.]+\))\s*(==|!=)\s*["'])"""
    r"""|(["'][^"'\n]*["']\s+(not\s+)?in\s+(str\([\w.]+\)|[\w.]*(message|reason)\b))""")


def test_no_policy_is_decided_by_matching_message_text():
    hits = []
    for name, path in addon_modules().items():
        for n, line in enumerate(open(path), start=1):
            if MESSAGE_MATCH.search(line.split("#")[0]):
                hits.append(f"addon/{name.replace('.', '/')}.py:{n}: {line.strip()}")
    assert not hits, "\n".join(hits)


def test_the_message_pattern_catches_what_it_is_for():
    # The check above must be able to fail.
    assert MESSAGE_MATCH.search('if init.message == "cancelled":')
    assert MESSAGE_MATCH.search('stopped = str(self._error) == "cancelled"')
    assert MESSAGE_MATCH.search('if "cancelled" in result.message:')
    assert not MESSAGE_MATCH.search('if status == native.InitialSunStatus.CANCELLED:')


def native_defaults(native):
    """{(class, field): value} of every numeric default of a bound options
    struct."""
    out = {}
    for cls_name in dir(native):
        if not cls_name.endswith("Options"):
            continue
        cls = getattr(native, cls_name)
        o = cls()
        for field in dir(cls):
            if field.startswith("_") or not isinstance(getattr(cls, field, None), property):
                continue
            value = getattr(o, field)
            if isinstance(value, (int, float)) and not isinstance(value, bool):
                out[(cls_name, field)] = float(value)
    return out


# Python constants equal to a native default by coincidence, not copies of
# it (a different quantity with the same number): name -> why.
NOT_COPIES = {
    "estimate.whole_clip.SUNLIT_EXPLAINED_SHARE": "a share of a frame explained, not of the "
                                                  "Suns a circle holds",
    "estimate.finish.PREDICT_PAST_SPAN_SHARE": "a share of a segment's span, not of the Suns a "
                                               "circle holds",
    "estimate.whole_clip.SEGMENT_MIN_MARGIN": "a jumped-to segment's lead in log-likelihood, "
                                              "not the frames a stream reads near a key frame",
    "estimate.untimed.LOOP_GROUP_MAX": "frames in a loop check's group, not the path's "
                                       "largest step in degrees",
    "estimate.whole_clip.PACE_SWITCH_FRAMES": "Suns far off a circle, not the frames a "
                                              "stream queues",
    "estimate.whole_clip.EXCURSION_SIDE_FRAMES": "sunlit frames either side of a jumped-to "
                                                 "segment, not a stream's queue or a "
                                                 "sample's sides",
    "estimate.finish.CLOCK_NORTH_FRAMES": "measured frames that agree on a north, not the "
                                          "frames a stream queues",
    "estimate.finish.CLOCK_NORTH_SHARE": "a share of the measured Suns the ephemeris keeps, "
                                         "not of the Suns a circle holds",
    "estimate.finish.CLOCK_SHIFT_MAX_HOURS": "hours a clock may be off by, not pixels or a "
                                             "path's step in degrees",
}


def python_constants():
    """{module.NAME: value} of the bpy-free packages' numeric module constants."""
    out = {}
    for name, path in addon_modules().items():
        if name.split(".")[0] not in BPY_FREE:
            continue
        for node in ast.parse(open(path).read(), path).body:
            if isinstance(node, ast.Assign) and len(node.targets) == 1 and \
                    isinstance(node.targets[0], ast.Name) and node.targets[0].id.isupper():
                try:
                    value = ast.literal_eval(node.value)
                except ValueError:
                    continue
                if isinstance(value, (int, float)) and not isinstance(value, bool):
                    out[f"{name}.{node.targets[0].id}"] = float(value)
    return out


def words(name):
    return {w for w in re.split(r"[_.]", name.lower()) if w not in ("", "deg", "s", "px")}


def test_no_python_constant_copies_a_native_default():
    """A Python constant with a native field's value and a word of its name
    in common is taken for a copy: read it from the bound options."""
    native = pytest.importorskip("_native")
    defaults = native_defaults(native)
    assert defaults[("SunPathOptions", "max_speed_deg_per_hour")] == 15.5  # the check sees them
    copies = []
    for const, value in python_constants().items():
        if const in NOT_COPIES:
            continue
        for (cls, field), default in defaults.items():
            if value == default and value not in (0.0, 1.0) and \
                    words(const.rpartition(".")[2]) & words(field):
                copies.append(f"{const} = {value:g} copies {cls}.{field}")
    assert not copies, "\n".join(copies)


def test_the_copy_check_finds_a_copy():
    native = pytest.importorskip("_native")
    defaults = native_defaults(native)
    value = defaults[("SunPathOptions", "max_step_deg")]
    assert any(value == d and words("UNTIMED_STEP_DEG") & words(f)
               for (c, f), d in defaults.items())
