#!/usr/bin/env python3
"""Make (or preview) a converged Mitsuba 3 reference for a radray scene whose geometry is one OBJ.

usage: python3 references/make_reference.py SCENE.toml SPP [--name NAME] [--seed S] [--preview OUT.exr]
                                             [--pass-spp 128] [--budget-s SECONDS] [--resume] [--variant llvm_ad_rgb]
                                             [--out-dir DIR]

--out-dir DIR writes the folder below to DIR instead of references/NAME/ (and its resume cache to
DIR/.cache.npz): for scenes that stay outside the repository (Crytek Sponza, 26 MB of OBJ). A
mesh with `two_sided = true` is rendered with two-sided reflection (mitsuba_scene.scene_dict's
two_sided: emitters still emit from their front only).

Without --preview it fills references/NAME/ (NAME defaults to the TOML file's stem):
  scene.obj, scene.mtl (+ textures/)  copied unchanged from the scene's [[mesh]] obj folder
  camera.json                         eye, look_at, up, vfov_deg from [camera]; width, height from [image]
  reference.exr                       linear float RGB, the mean of two independent halves A and B,
                                      rendered as alternating passes of --pass-spp samples (A with seeds
                                      2S*100003+k, B with (2S+1)*100003+k); with --budget-s the passes stop
                                      once that much render time is spent, so SPP is a cap (the noise
                                      file records the samples actually taken). The two running sums are
                                      kept in references/.cache/NAME.npz (not committed); --resume adds
                                      passes to them (with the next seeds) when the scene is unchanged
  reference.png                       clamped, sRGB preview
  reference_noise.json                residual noise, estimated from the two halves A and B (SPP/2 each):
      the full image's error is estimated by (A - B)/2 (its variance is var(A - B)/4), so
      relMSE_ref = mean((A-B)^2 / (ref^2 + 0.01)) / 4 and rel_rmse_ref = sqrt(relMSE_ref), the
      "per-pixel relative RMSE" of references/README.md; mean_abs_rel_err_ref = mean(|A-B|/2 / (|ref|+0.01));
      rmse_ref = sqrt(mean((A-B)^2)/4); *_halfA_vs_halfB are the same sums without the /4;
      rel_rmse_halfA_vs_halfB_pixels_gt_0.05 only over pixels whose mean RGB of ref is > 0.05.
With --preview OUT.exr it renders SPP once to OUT.exr and prints the mean radiance and the time
(for calibrating emitters and spp). Path tracer: max depth 64, box filter, as every reference here.
Run heavy renders under `nice -n 10`.
"""
import time

T0 = time.perf_counter()
import argparse
import json
import os
import shutil
import sys
import tomllib

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import numpy as np

import mitsuba_scene as ms
from compare import write_png_srgb
from render_one import render

EPS = 0.01


def scene_from_toml(path):
    """(obj path, camera dict, two_sided) from a radray scene file with one [[mesh]] and a [camera]."""
    with open(path, "rb") as f:
        t = tomllib.load(f)
    meshes = t.get("mesh", [])
    if len(meshes) != 1 or set(meshes[0]) - {"obj", "two_sided"}:
        raise SystemExit("%s: need exactly one [[mesh]] with only obj (and two_sided)" % path)
    obj = os.path.join(os.path.dirname(os.path.abspath(path)), meshes[0]["obj"])
    c, img = t["camera"], t.get("image", {})
    cam = {"eye": c["eye"], "look_at": c["look_at"], "up": c.get("up", [0.0, 1.0, 0.0]), "vfov_deg": c["vfov_deg"],
           "width": img.get("width", 256), "height": img.get("height", 256)}
    return obj, cam, bool(meshes[0].get("two_sided", False))


def copy_scene(obj, out):
    """Copy the OBJ, its MTL and any texture folder unchanged into `out` as scene.obj/scene.mtl."""
    src = os.path.dirname(obj)
    os.makedirs(out, exist_ok=True)
    shutil.copyfile(obj, os.path.join(out, "scene.obj"))
    mtl = [l.split()[1] for l in open(obj) if l.startswith("mtllib")]
    if mtl != ["scene.mtl"]:
        raise SystemExit("%s: expected 'mtllib scene.mtl'" % obj)
    shutil.copyfile(os.path.join(src, "scene.mtl"), os.path.join(out, "scene.mtl"))
    if os.path.isdir(os.path.join(src, "textures")):
        shutil.rmtree(os.path.join(out, "textures"), ignore_errors=True)
        shutil.copytree(os.path.join(src, "textures"), os.path.join(out, "textures"))


def scene_key(folder, seed):
    """A digest of everything the image depends on, so that --resume never mixes two scenes."""
    import hashlib
    h = hashlib.sha256(str(seed).encode())
    for root, _, files in sorted(os.walk(folder)):
        for f in sorted(files):
            if f.startswith("reference") or f.startswith(".cache") or ".mitsuba_cache" in root:
                continue
            h.update(f.encode())
            h.update(open(os.path.join(root, f), "rb").read())
    return h.hexdigest()


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("toml")
    ap.add_argument("spp", type=int)
    ap.add_argument("--name")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--preview")
    ap.add_argument("--pass-spp", type=int, default=128)
    ap.add_argument("--budget-s", type=float, default=None)
    ap.add_argument("--resume", action="store_true")
    ap.add_argument("--variant")
    ap.add_argument("--out-dir")
    a = ap.parse_args()
    name = a.name or os.path.splitext(os.path.basename(a.toml))[0]
    obj, cam, two_sided = scene_from_toml(a.toml)
    out = os.path.abspath(a.out_dir) if a.out_dir else os.path.join(HERE, name)
    if a.preview:
        import tempfile
        out = tempfile.mkdtemp(prefix="mkref_")
    copy_scene(obj, out)
    with open(os.path.join(out, "camera.json"), "w") as f:
        json.dump(cam, f, indent=1)
    mi, variant = ms.init_mitsuba(a.variant)
    scene = mi.load_dict(ms.scene_dict(mi, out, spp=a.spp, seed=a.seed, max_depth=64, two_sided=two_sided))
    shutil.rmtree(os.path.join(out, ".mitsuba_cache"), ignore_errors=True)
    if a.preview:
        t = time.perf_counter()
        img = render(mi, scene, a.spp, a.seed * 100003, a.pass_spp)
        dt = time.perf_counter() - t
        mi.Bitmap(img).write(a.preview)
        write_png_srgb(img.astype(np.float64), os.path.splitext(a.preview)[0] + ".png")
        shutil.rmtree(out)
        lum = img.mean(axis=2)
        print(json.dumps({"scene": name, "spp": a.spp, "render_s": dt, "mean_rgb": img.reshape(-1, 3).mean(0).tolist(),
                          "median": float(np.median(lum)), "p90": float(np.percentile(lum, 90))}))
        return
    half_cap = a.spp // 2
    acc, times, half, k = [0.0, 0.0], [0.0, 0.0], 0, 0
    cache = os.path.join(out, ".cache.npz") if a.out_dir else os.path.join(HERE, ".cache", name + ".npz")
    key = scene_key(out, a.seed)
    if a.resume and os.path.exists(cache):
        c = np.load(cache)
        if str(c["key"]) == key:
            acc, times, half, k = [c["accA"], c["accB"]], list(c["times"]), int(c["half"]), int(c["k"])
            print("resuming at %d spp per half" % half, file=sys.stderr, flush=True)
    t_start = time.perf_counter()
    while half < half_cap:
        n = min(a.pass_spp, half_cap - half)
        for h in range(2):
            t = time.perf_counter()
            acc[h] = acc[h] + n * np.array(mi.render(scene, spp=n, seed=(2 * a.seed + h) * 100003 + k), dtype=np.float64)
            times[h] += time.perf_counter() - t
        half += n
        k += 1
        os.makedirs(os.path.dirname(cache), exist_ok=True)
        np.savez(cache + ".tmp.npz", accA=acc[0], accB=acc[1], times=np.array(times), half=half, k=k, key=key)
        os.replace(cache + ".tmp.npz", cache)
        print("%d spp per half, %.0f s" % (half, time.perf_counter() - t_start), file=sys.stderr, flush=True)
        if a.budget_s and time.perf_counter() - t_start > a.budget_s:
            break
    A, B = acc[0] / half, acc[1] / half
    ref = 0.5 * (A + B)
    d2 = (A - B) ** 2
    rel = d2 / (ref ** 2 + EPS)
    bright = ref.mean(axis=2) > 0.05
    mi.Bitmap(ref.astype(np.float32)).write(os.path.join(out, "reference.exr"))
    write_png_srgb(ref, os.path.join(out, "reference.png"))
    noise = {
        "scene": name, "spp": 2 * half, "half_spp": half, "variant": variant, "render_s_halves": times,
        "spp_cap": 2 * half_cap, "budget_s": a.budget_s, "load_avg_1min_at_end": os.getloadavg()[0],
        "mean_rgb": ref.reshape(-1, 3).mean(0).tolist(),
        "relMSE_ref": float(rel.mean() / 4), "rel_rmse_ref": float(np.sqrt(rel.mean() / 4)),
        "mean_abs_rel_err_ref": float(np.mean(np.sqrt(d2) / 2 / (np.abs(ref) + EPS))),
        "rmse_ref": float(np.sqrt(d2.mean() / 4)),
        "relMSE_halfA_vs_halfB": float(rel.mean()), "rel_rmse_halfA_vs_halfB": float(np.sqrt(rel.mean())),
        "rel_rmse_halfA_vs_halfB_pixels_gt_0.05": float(np.sqrt(rel[bright].mean())),
    }
    with open(os.path.join(out, "reference_noise.json"), "w") as f:
        json.dump(noise, f, indent=1)
    print(json.dumps(noise))


if __name__ == "__main__":
    main()
