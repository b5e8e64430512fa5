#!/usr/bin/env python3
"""An unbiased path tracer with portal sampling, for scenes lit through a gap (references/gap_room).

usage: python3 references/portal_tracer.py SCENE_DIR SPP SEED OUT.exr [--pass-spp 8]
                                            [--portal X0,X1,Y0,Y1,Z] [--q 0.5]

Why: in gap_room every light path the camera sees passes a 0.5 x 2 m door gap. Mitsuba's `path`
integrator finds the gap only by chance (BSDF sampling), and its `ptracer` wastes most particles in
the lit room; both reach a per-pixel relMSE of about 2.4 (path) and 3.2 (ptracer) per CPU-second of
a 256^2 image, so 0.0002 would take some 12,000 CPU-s. Here each vertex on the dark side of the gap
samples its next direction from a one-sample mixture (Veach's balance heuristic):
    p(w) = q p_portal(w) + (1 - q) p_bsdf(w),   q = 0.5,
    p_portal(w) = t^2 / (A |cos theta_p|)  if the ray crosses the portal rectangle (area A) at distance t,
so directions through the gap are sampled every other bounce, and the estimator stays unbiased over
the whole hemisphere (p > 0 wherever the cosine-weighted diffuse BSDF is). Emitted light is counted by
next-event estimation only (Mitsuba's `sample_emitter_direction`, with its visibility test), except on
the camera ray, so nothing is counted twice. Russian roulette after depth 5 as Mitsuba's `path`.

The scene, camera, materials and film conventions are references/mitsuba_scene.py's (box filter:
each pixel is the mean radiance over its area; an emitter's pixel equals its Ke). Diffuse surfaces
only (the BSDFs are Mitsuba's); the portal is an axis-aligned rectangle facing -z:
x in [X0, X1], y in [Y0, Y1] on the plane z = Z, and the dark side is z < Z.
Default portal: gap_room's door gap at the dark room's wall face (x 2.8..3.3, y 0..2, z 4.0).
Prints one JSON line with render_s and cpu_s (user + system of this process).
"""
import time

T0 = time.perf_counter()
import argparse
import json
import os
import resource
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import numpy as np

import mitsuba_scene as ms


def cpu_seconds():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def render_pass(mi, dr, scene, spp, seed, portal, max_depth=64, rr_depth=5, q=0.5):
    """Mean radiance per pixel of `spp` paths per pixel, as float64 H x W x 3."""
    sensor = scene.sensors()[0]
    W, H = sensor.film().crop_size()
    n = W * H * spp
    idx = dr.arange(mi.UInt32, n)
    pix = idx // spp
    rng = mi.PCG32(size=n, initstate=mi.UInt64(seed) * 0x9E3779B97F4A7C15 + 12345, initseq=mi.UInt64(idx))
    px = mi.Float(pix % W)
    py = mi.Float(pix // W)
    pos = mi.Point2f((px + rng.next_float32()) / W, (py + rng.next_float32()) / H)
    ray, _ = sensor.sample_ray(0.0, 0.5, pos, mi.Point2f(0.5, 0.5))
    ray = mi.Ray3f(ray)
    x0, x1, y0, y1, zp = portal
    area = (x1 - x0) * (y1 - y0)
    ctx = mi.BSDFContext()
    L = mi.Color3f(0.0)
    beta = mi.Color3f(1.0)
    active = mi.Bool(True)
    for depth in range(max_depth):
        si = scene.ray_intersect(ray, active)
        active &= si.is_valid()
        if depth == 0:
            L += dr.select(active, si.emitter(scene).eval(si, active), 0.0)
        bsdf = si.bsdf(ray)
        # next-event estimation: the only place emitted light enters after the camera ray
        ds, em = scene.sample_emitter_direction(si, mi.Point2f(rng.next_float32(), rng.next_float32()), True, active)
        wo_em = si.to_local(ds.d)
        f_em = bsdf.eval(ctx, si, wo_em, active)
        L += dr.select(active, beta * f_em * em, 0.0)
        # next direction: mixture of the BSDF and the portal on the dark side, the BSDF elsewhere
        dark = active & (si.p.z < zp - 1e-4)
        use_portal = dark & (rng.next_float32() < q)
        bs, _ = bsdf.sample(ctx, si, rng.next_float32(), mi.Point2f(rng.next_float32(), rng.next_float32()), active)
        pp = mi.Point3f(x0 + (x1 - x0) * rng.next_float32(), y0 + (y1 - y0) * rng.next_float32(), zp)
        d_portal = dr.normalize(pp - si.p)
        wo_world = dr.select(use_portal, d_portal, si.to_world(bs.wo))
        wo = si.to_local(wo_world)
        f, pdf_bsdf = bsdf.eval_pdf(ctx, si, wo, active)
        # portal density of this direction (solid angle), zero if it misses the rectangle
        dz = wo_world.z
        t = (zp - si.p.z) / dr.select(dz > 1e-7, dz, 1.0)
        hx = si.p.x + t * wo_world.x
        hy = si.p.y + t * wo_world.y
        inside = dark & (dz > 1e-7) & (hx >= x0) & (hx <= x1) & (hy >= y0) & (hy <= y1)
        pdf_portal = dr.select(inside, t * t / (area * dz), 0.0)
        pdf = dr.select(dark, q * pdf_portal + (1.0 - q) * pdf_bsdf, pdf_bsdf)
        beta, active = weigh_and_roulette(dr, rng, beta, active, f, pdf, depth >= rr_depth)
        ray = si.spawn_ray(wo_world)
        dr.eval(L, beta, active, ray, rng)
        if not dr.any(active):
            break
    rad = np.stack([np.array(L.x), np.array(L.y), np.array(L.z)], axis=1).astype(np.float64)
    img = rad.reshape(H, W, spp, 3).mean(axis=2)
    return img


def weigh_and_roulette(dr, rng, beta, active, f, pdf, roulette):
    """beta · f/pdf for the sampled direction (f the BSDF times the cosine), then Russian roulette
    with survival min(max(beta), 0.95) when `roulette`, as Mitsuba's `path`."""
    ok = active & (pdf > 0) & (dr.max(f) > 0)
    beta = dr.select(ok, beta * f / dr.select(pdf > 0, pdf, 1.0), 0.0)
    active &= ok
    if roulette:
        surv = dr.minimum(dr.max(beta), 0.95)
        alive = rng.next_float32() < surv
        beta = dr.select(alive, beta / surv, 0.0)
        active &= alive
    return beta, active


def accumulate(render_pass, spp, seed, pass_spp):
    """Mean of passes of at most `pass_spp` samples, `render_pass(spp, seed)` with seeds seed·1000003 + k."""
    acc, done, k = None, 0, 0
    while done < spp:
        m = min(pass_spp, spp - done)
        img = render_pass(m, seed * 1000003 + k)
        acc = img * m if acc is None else acc + img * m
        done += m
        k += 1
    return acc / spp


def render(mi, dr, scene, spp, seed, portal, pass_spp=8, q=0.5):
    return accumulate(lambda m, s: render_pass(mi, dr, scene, m, s, portal, q=q), spp, seed, pass_spp)


def run_cli(doc, render_fn, default_portal, default_pass_spp, one_emitter=False):
    """The command line both portal tracers share: SCENE_DIR SPP SEED OUT [--pass-spp] [--portal] [--q]."""
    ap = argparse.ArgumentParser(description=doc, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene")
    ap.add_argument("spp", type=int)
    ap.add_argument("seed", type=int)
    ap.add_argument("out")
    ap.add_argument("--pass-spp", type=int, default=default_pass_spp)
    ap.add_argument("--portal", default=default_portal)
    ap.add_argument("--q", type=float, default=0.5)
    a = ap.parse_args()
    portal = [float(v) for v in a.portal.split(",")]
    mi, variant = ms.init_mitsuba("llvm_ad_rgb")
    import drjit as dr
    scene = mi.load_dict(ms.scene_dict(mi, a.scene, spp=a.spp, seed=a.seed))
    if one_emitter and len(scene.emitters()) != 1:
        raise SystemExit("%s: this tracer handles one area emitter, found %d" % (a.scene, len(scene.emitters())))
    c0, t0 = cpu_seconds(), time.perf_counter()
    img = render_fn(mi, dr, scene, a.spp, a.seed, portal, a.pass_spp, a.q)
    tr, cr = time.perf_counter() - t0, cpu_seconds() - c0
    if a.out.endswith(".npy"):
        np.save(a.out, img)
    else:
        mi.Bitmap(img.astype(np.float32)).write(a.out)
    print(json.dumps({"scene": a.scene, "spp": a.spp, "seed": a.seed, "variant": variant, "render_s": tr,
                      "cpu_s": cr, "total_s": time.perf_counter() - T0, "out": a.out}))


if __name__ == "__main__":
    run_cli(__doc__, render, "2.8,3.3,0.0,2.0,4.0", 8)
