"""Fills the footage cache for the AMOS webcam clips from a clone of the
public repository Mizzade/diplomarbeit (its data/webcam/ holds frames of the
"Webcam" dataset of Verdie et al., CVPR 2015, taken from the AMOS archive of
Jacobs et al., CVPR 2007; academic use only, so they are not copied here).

  git clone --depth 1 https://github.com/Mizzade/diplomarbeit /tmp/diplomarbeit
  /usr/bin/python3 examples/real/amos_fetch.py /tmp/diplomarbeit [--out ../shared/real/amos]

(A bare clone works too: the files are read with `git show HEAD:path`.)
Each folder's frames are written in capture order as <clip>/0001.png,
0002.png, ... (a Blender image sequence) with <clip>.times.csv beside them:
frame,utc_time from the file names (YYYYMMDD_HHMMSS, UTC). Clips:

  amos-mulhouse   data/webcam/courbevoie (Place de la Reunion, Mulhouse;
                  the folder's name is not the place), 640x471
  amos-stlouis    data/webcam/stlouis (Kiener Plaza, St. Louis), 800x450
"""
import argparse
import os
import re
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CLIPS = {"amos-mulhouse": "data/webcam/courbevoie", "amos-stlouis": "data/webcam/stlouis"}
STAMP = re.compile(r"(\d{4})(\d{2})(\d{2})_(\d{2})(\d{2})(\d{2})\.png$")


def git(repo, *args):
    return subprocess.run(["git", "-C", repo, *args], check=True, capture_output=True).stdout


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("repo", help="a clone (plain or bare) of Mizzade/diplomarbeit")
    p.add_argument("--out", default=os.path.join(os.path.dirname(ROOT), "shared", "real", "amos"))
    args = p.parse_args(argv)
    for clip, folder in CLIPS.items():
        names = git(args.repo, "ls-tree", "--name-only", "HEAD", folder + "/").decode().split()
        shots = sorted((STAMP.search(n).groups(), n) for n in names if STAMP.search(n))
        if not shots:
            sys.exit(f"amos_fetch: no frames under {folder} in {args.repo}")
        out_dir = os.path.join(args.out, clip)
        os.makedirs(out_dir, exist_ok=True)
        rows = ["frame,utc_time,source"]
        for i, ((y, mo, d, h, mi, s), name) in enumerate(shots, start=1):
            with open(os.path.join(out_dir, f"{i:04d}.png"), "wb") as f:
                f.write(git(args.repo, "show", f"HEAD:{name}"))
            rows.append(f"{i},{y}-{mo}-{d} {h}:{mi}:{s},{os.path.basename(name)}")
        with open(os.path.join(args.out, f"{clip}.times.csv"), "w") as f:
            f.write("\n".join(rows) + "\n")
        print(f"amos_fetch: {clip}: {len(shots)} frames into {out_dir}")


if __name__ == "__main__":
    main()
