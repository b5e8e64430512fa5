#!/usr/bin/env python3
"""Join a new, independent reference render of a scene to the one already in references/NAME/.

usage: python3 references/merge_reference.py NAME NEW_NAME

NAME/reference.exr (estimate 1, its per-pixel noise relMSE_ref from NAME/reference_noise.json) and the
two halves A, B that make_reference.py left in references/.cache/NEW_NAME.npz (estimate 2 = (A + B)/2,
its noise measured from A - B) are independent unbiased estimates of the same image (same renderer,
settings and scene; different seeds). This writes into references/NAME/:
  reference_1.exr, reference_2.exr   the two estimates (kept: `compare.py --halves` needs them)
  reference.exr                      w1 * estimate 1 + (1 - w1) * estimate 2, with one global weight from
                                     their noise, w1 = n2 / (n1 + n2) (a weight that does not depend on
                                     the pixels' values keeps the mean unbiased)
  reference.png                      clamped sRGB preview
  reference_noise.json               relMSE_ref of the joined image, w1^2 n1 + (1 - w1)^2 n2 (the
                                     estimates are independent), and each part's figures
and deletes references/NEW_NAME/ (make_reference.py's copy of the scene and its own mean).
Against the joined reference radray's relMSE still carries the floor relMSE_ref; `compare.py TEST
NAME/reference.exr --halves NAME/reference_1.exr NAME/reference_2.exr` estimates it against the
converged image without that floor.
"""
import json
import os
import shutil
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import numpy as np

from compare import EPS, read_image, write_png_srgb


def write_exr(img, path):
    import mitsuba_scene as ms
    mi, _ = ms.init_mitsuba()
    mi.Bitmap(img.astype(np.float32)).write(path)


def main():
    if len(sys.argv) != 3:
        raise SystemExit(__doc__)
    name, new = sys.argv[1], sys.argv[2]
    folder = os.path.join(HERE, name)
    old_noise = json.load(open(os.path.join(folder, "reference_noise.json")))
    one_path = os.path.join(folder, "reference_1.exr")
    if os.path.exists(one_path):
        raise SystemExit("%s exists: %s was merged already" % (one_path, name))
    e1 = read_image(os.path.join(folder, "reference.exr"))
    c = np.load(os.path.join(HERE, ".cache", new + ".npz"))
    half = int(c["half"])
    a, b = c["accA"] / half, c["accB"] / half
    e2 = 0.5 * (a + b)
    n1 = float(old_noise["relMSE_ref"])
    n2 = float(np.mean((a - b) ** 2 / (e2 ** 2 + EPS)) / 4)
    w1 = n2 / (n1 + n2)
    ref = w1 * e1 + (1 - w1) * e2
    write_exr(e1, one_path)
    write_exr(e2, os.path.join(folder, "reference_2.exr"))
    write_exr(ref, os.path.join(folder, "reference.exr"))
    write_png_srgb(ref, os.path.join(folder, "reference.png"))
    noise = {
        "scene": name,
        "relMSE_ref": w1 * w1 * n1 + (1 - w1) ** 2 * n2,
        "weight_reference_1": w1,
        "mean_rgb": ref.reshape(-1, 3).mean(0).tolist(),
        "relMSE_1_vs_2": float(np.mean((e1 - e2) ** 2 / (ref ** 2 + EPS))),
        "relMSE_1_vs_2_expected": n1 + n2,
        "reference_1": old_noise,
        "reference_2": {
            "spp": 2 * half, "half_spp": half, "render_s_halves": c["times"].tolist(), "relMSE_ref": n2,
            "relMSE_ref_64x64": float(np.mean((box(a) - box(b)) ** 2 / (box(e2) ** 2 + EPS)) / 4),
            "load_avg_1min_at_end": os.getloadavg()[0],
        },
    }
    noise["rel_rmse_ref"] = float(np.sqrt(noise["relMSE_ref"]))
    with open(os.path.join(folder, "reference_noise.json"), "w") as f:
        json.dump(noise, f, indent=1)
    shutil.rmtree(os.path.join(HERE, new), ignore_errors=True)
    print(json.dumps(noise, indent=1))


def box(img, n=4):
    h, w = img.shape[:2]
    return img.reshape(h // n, n, w // n, n, -1).mean(axis=(1, 3))


if __name__ == "__main__":
    main()
