"""House-habit checks run by tools/test.sh, one junit testcase per check.

    python3 tools/lint.py [--junit FILE] [CHECK ...]

Each check prints the offending lines; the exit status is 1 when any check
found something. Checks:
  clang-format  tracked C++ under native/ and bench/ (.clang-format)
  flake8        the Python under addon/, examples/, bench/, tests/, tools/
  mypy          the bpy-free packages addon/<package>/ (core, estimate; not the
                glue library addon/blender/)
Settings for flake8 and mypy live in setup.cfg.
"""

import argparse
import glob
import os
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def tracked(*patterns):
    """Tracked files matching git pathspecs; a plain glob outside a checkout."""
    try:
        out = subprocess.run(["git", "ls-files", "--", *patterns], cwd=ROOT,
                             check=True, capture_output=True, text=True).stdout
        return sorted(out.split())
    except (OSError, subprocess.CalledProcessError):
        found = set()
        for pattern in patterns:
            found.update(os.path.relpath(p, ROOT) for p in
                         glob.glob(os.path.join(ROOT, pattern), recursive=True))
        return sorted(found)


def run(cmd, env=None):
    """(found_something, output) of a checker that exits non-zero on findings."""
    try:
        proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, env=env)
    except OSError as error:
        return True, f"{cmd[0]}: cannot run ({error}); tools/install.sh installs it"
    return proc.returncode != 0, (proc.stdout + proc.stderr).strip()


def check_clang_format():
    files = tracked("native/*.cc", "native/*.h", "bench/*.cc")
    return run(["clang-format", "--dry-run", "--Werror", *files])


PYTHON_DIRS = ("addon", "examples", "bench", "tests", "tools")


def check_flake8():
    return run([sys.executable, "-m", "flake8", "--show-source", *PYTHON_DIRS])


# The Blender glue library: a package of addon/ that imports bpy.
GLUE_PACKAGES = ("blender",)


def bpy_free_packages():
    """Every package inside addon/ but the glue (addon/blender/, addon/*.py)."""
    addon = os.path.join(ROOT, "addon")
    return sorted(name for name in os.listdir(addon)
                  if os.path.isfile(os.path.join(addon, name, "__init__.py"))
                  and name not in GLUE_PACKAGES)


def check_mypy():
    """mypy on the bpy-free packages as Blender imports them (sunlapse.core,
    sunlapse.estimate: they import each other relatively), through a
    stand-in `sunlapse` package whose __init__ does not register with bpy."""
    with tempfile.TemporaryDirectory() as tmp:
        package = os.path.join(tmp, "sunlapse")
        os.mkdir(package)
        open(os.path.join(package, "__init__.py"), "w").close()
        args = []
        for name in bpy_free_packages():
            os.symlink(os.path.join(ROOT, "addon", name), os.path.join(package, name))
            args += ["-p", f"sunlapse.{name}"]
        return run([sys.executable, "-m", "mypy", "--pretty", "--no-error-summary",
                    "--cache-dir", os.path.join(ROOT, "build", "mypy-cache"), *args],
                   env=dict(os.environ, MYPYPATH=tmp))


CHECKS = {
    "clang-format": check_clang_format,
    "flake8": check_flake8,
    "mypy": check_mypy,
}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--junit", help="write the results as junit XML here")
    parser.add_argument("checks", nargs="*",
                        help=f"checks to run (default: all of {', '.join(CHECKS)})")
    args = parser.parse_args(argv)
    names = args.checks or list(CHECKS)
    unknown = [name for name in names if name not in CHECKS]
    if unknown:
        parser.error(f"unknown check {unknown[0]!r}; valid: {', '.join(CHECKS)}")

    suite = ET.Element("testsuite", name="lint")
    failures = 0
    for name in names:
        start = time.monotonic()
        found, output = CHECKS[name]()
        case = ET.SubElement(suite, "testcase", classname="lint", name=name,
                             time=f"{time.monotonic() - start:.2f}")
        print(f"[lint] {name}: {'FAILED' if found else 'ok'}")
        if found:
            failures += 1
            print(output)
            failure = ET.SubElement(case, "failure",
                                    message=f"{name} found problems")
            failure.text = output
    suite.set("tests", str(len(names)))
    suite.set("failures", str(failures))
    if args.junit:
        ET.ElementTree(suite).write(args.junit, encoding="utf-8",
                                    xml_declaration=True)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
