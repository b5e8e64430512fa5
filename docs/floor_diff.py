#!/usr/bin/env python3
"""The contact-shadow figure of docs/accuracy.md: the Cornell box floor, radray against the reference.

usage: python3 docs/floor_diff.py [--radray PATH] [--out docs/images/gather_cornell_floor_diff.png]

Renders scenes/cornell_box.toml (256², the default preset as `radray render` uses it) three ways, one
process at a time under /usr/bin/time:
  old default      --direct radiosity --final-gather off   (meshed direct light)
  no gather        --direct pixel --final-gather off
  default          no flags
writes `radray compare --diff` false-colour maps against references/cornell_original/reference.exr
(0 black, relative error 1 or more pale yellow) and tiles their lower 38% (the floor and the blocks'
feet) left to right, 4 px apart, into OUT. Prints, per render, the relMSE of the whole image and of the
floor strip (references/compare.py's metric) and the render's CPU seconds (user + system).
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

import numpy as np
from PIL import Image

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "references"))
from compare import basic, read_exr  # noqa: E402
from timed import timed  # noqa: E402

FLOOR_FRACTION = 0.38
GAP_PX = 4
RENDERS = [
    ("old default", ["--direct", "radiosity", "--final-gather", "off"]),
    ("no gather", ["--direct", "pixel", "--final-gather", "off"]),
    ("default", []),
]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--radray", default=os.path.join(ROOT, "target", "release", "radray"))
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "images", "gather_cornell_floor_diff.png"))
    a = ap.parse_args()
    scene = os.path.join(ROOT, "scenes", "cornell_box.toml")
    ref_path = os.path.join(ROOT, "references", "cornell_original", "reference.exr")
    ref = read_exr(ref_path)
    top = int(round(ref.shape[0] * (1.0 - FLOOR_FRACTION)))
    floor = np.zeros(ref.shape[:2], bool)
    floor[top:] = True
    strips = []
    with tempfile.TemporaryDirectory(prefix="floor_diff_") as tmp:
        for name, flags in RENDERS:
            img = os.path.join(tmp, "render.exr")
            diff = os.path.join(tmp, "diff.png")
            cpu, wall, _, _ = timed([a.radray, "--quiet", "render", scene, "-o", img] + flags)
            r = subprocess.run([a.radray, "compare", img, ref_path, "--json", "--diff", diff],
                               capture_output=True, text=True, check=True)
            whole = json.loads(r.stdout)
            strip = basic(read_exr(img), ref, floor)
            print(json.dumps({"render": name, "flags": " ".join(flags), "cpu_s": cpu, "wall_s": wall,
                              "relMSE": whole.get("rel_mse", whole.get("relMSE")),
                              "floor_relMSE": strip["relMSE"]}), flush=True)
            strips.append(np.asarray(Image.open(diff).convert("RGB"))[top:])
    h, w = strips[0].shape[:2]
    sheet = np.zeros((h, len(strips) * w + (len(strips) - 1) * GAP_PX, 3), np.uint8)
    sheet[:] = 255
    for i, s in enumerate(strips):
        sheet[:, i * (w + GAP_PX):i * (w + GAP_PX) + w] = s
    Image.fromarray(sheet).save(a.out)
    print("wrote %s" % os.path.relpath(a.out, ROOT))


if __name__ == "__main__":
    main()
