#!/usr/bin/env python3
"""Noise per CPU-second of a reference integrator on one scene: two independent renders, their difference.

usage: python3 references/integrator_noise.py SCENE_DIR INTEGRATOR SPP [--seeds 11,12]

INTEGRATOR: `path` (Mitsuba's, as every reference here), `ptracer` (Mitsuba's particle tracer),
`portal` (references/portal_tracer.py) or `portal_ptracer` (references/portal_ptracer.py); the last two
take the gap_room portal defaults. Renders SPP twice with two seeds, A and B, and prints JSON:
  noise_per_image    relMSE of one image against its own mean = mean (A-B)^2/(ref^2+0.01)/2, ref the
                     folder's reference.exr (the reference's own noise does not enter)
  noise_x_cpu        noise_per_image times the CPU-seconds of one render: the relMSE the integrator
                     reaches in one CPU-second (it falls as 1/time), lower is better
  noise_64           the same for the images box-averaged to 64^2 (4 x 4 pixels)
  relMSE_64_vs_ref   (A+B)/2 against the reference at 64^2, and its expectation if both are unbiased
                     (noise_64/2 + the reference's 64^2 noise when reference_noise.json has it): a bias
                     check
CPU-seconds: user + system of this process during the render call (all of Dr.Jit's threads).
"""
import argparse
import json
import os
import resource
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import numpy as np

import mitsuba_scene as ms
from compare import EPS, box_average, read_image


def cpu_seconds():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene")
    ap.add_argument("integrator", choices=["path", "ptracer", "portal", "portal_ptracer"])
    ap.add_argument("spp", type=int)
    ap.add_argument("--seeds", default="11,12")
    a = ap.parse_args()
    mi, _ = ms.init_mitsuba("llvm_ad_rgb")
    import drjit as dr
    d = ms.scene_dict(mi, a.scene, spp=a.spp, seed=0, max_depth=64)
    if a.integrator == "ptracer":
        d["integrator"] = {"type": "ptracer", "max_depth": 64, "rr_depth": 5}
    scene = mi.load_dict(d)
    imgs, cpus = [], []
    for s in (int(x) for x in a.seeds.split(",")):
        c0 = cpu_seconds()
        if a.integrator in ("path", "ptracer"):
            img = np.array(mi.render(scene, spp=a.spp, seed=s), dtype=np.float64)
        elif a.integrator == "portal":
            import portal_tracer as pt
            img = pt.render(mi, dr, scene, a.spp, s, [2.8, 3.3, 0.0, 2.0, 4.0])
        else:
            import portal_ptracer as pp
            img = pp.render(mi, dr, scene, a.spp, s, [2.8, 3.3, 0.0, 2.0, 4.2])
        cpus.append(cpu_seconds() - c0)
        imgs.append(img)
    A, B = imgs
    ref = read_image(os.path.join(a.scene, "reference.exr"))
    noise = float(np.mean((A - B) ** 2 / (ref ** 2 + EPS)) / 2)
    rb, ab, bb = box_average(ref, 4), box_average(A, 4), box_average(B, 4)
    noise64 = float(np.mean((ab - bb) ** 2 / (rb ** 2 + EPS)) / 2)
    nf = os.path.join(a.scene, "reference_noise.json")
    ref64 = json.load(open(nf)).get("relMSE_ref_64x64") if os.path.exists(nf) else None
    m = 0.5 * (ab + bb)
    print(json.dumps({
        "scene": a.scene, "integrator": a.integrator, "spp": a.spp, "cpu_s": cpus,
        "noise_per_image": noise, "noise_x_cpu": noise * float(np.mean(cpus)), "noise_64": noise64,
        "mean_rgb": (0.5 * (A + B)).reshape(-1, 3).mean(0).tolist(), "ref_mean_rgb": ref.reshape(-1, 3).mean(0).tolist(),
        "relMSE_64_vs_ref": float(np.mean((m - rb) ** 2 / (rb ** 2 + EPS))),
        "relMSE_64_vs_ref_expected": noise64 / 2 + (ref64 or 0.0),
    }))


if __name__ == "__main__":
    main()
