#!/usr/bin/env python3
"""An unbiased particle (light) tracer with portal sampling, for scenes lit through a gap (gap_room).

usage: python3 references/portal_ptracer.py SCENE_DIR SPP SEED OUT.exr [--pass-spp 16]
                                             [--portal X0,X1,Y0,Y1,Z] [--q 0.5]

SPP is particles per pixel (W*H*SPP particles in all). Each particle leaves an emitter
(Mitsuba's `sample_emitter_ray`, weight = flux / pdf) and at every surface it hits it is connected to
the camera (Mitsuba's `sensor.sample_direction`, a shadow ray, the BSDF in importance mode), as
Mitsuba's `ptracer` does. The difference: at a vertex on the lit side of the gap its next direction is
drawn from a one-sample mixture (Veach's balance heuristic)
    p(w) = q p_portal(w) + (1 - q) p_bsdf(w),   p_portal(w) = t^2 / (A |cos theta_p|)
for directions that cross the portal rectangle (area A) at distance t, zero otherwise, so about
half the particles the lit room's surfaces reflect go through the gap instead of a few per cent.
The estimator stays unbiased (p > 0 wherever the BSDF is). Russian roulette after depth 5.

The portal is an axis-aligned rectangle facing +z: x in [X0, X1], y in [Y0, Y1] on the plane z = Z,
the lit side is z > Z. Default: gap_room's door gap at the lit room's wall face (x 2.8..3.3,
y 0..2, z 4.2). Emitters seen directly by the camera are not drawn (none is, in gap_room).
The scene, camera, film and materials are references/mitsuba_scene.py's (box filter: each pixel is
the mean radiance over its area). Prints one JSON line with render_s and cpu_s.
"""
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import numpy as np

from portal_tracer import accumulate, run_cli, weigh_and_roulette


def portal_pdf(mi, dr, p, d, portal):
    """Solid-angle density of direction d from p when a uniform point on the portal rectangle
    (facing +z, seen from z > Z) is aimed at: t^2 / (A |cos theta_p|), zero if d misses it."""
    x0, x1, y0, y1, zp = portal
    dz = -d.z
    t = (p.z - zp) / dr.select(dz > 1e-7, dz, 1.0)
    hx = p.x + t * d.x
    hy = p.y + t * d.y
    inside = (p.z > zp) & (dz > 1e-7) & (hx >= x0) & (hx <= x1) & (hy >= y0) & (hy <= y1)
    return dr.select(inside, t * t / ((x1 - x0) * (y1 - y0) * dz), 0.0)


def render_pass(mi, dr, scene, spp, seed, portal, q=0.5, max_depth=64, rr_depth=5):
    """Sum over pixels of the particle contributions of W*H*spp particles, divided by spp: H x W x 3."""
    sensor = scene.sensors()[0]
    W, H = sensor.film().crop_size()
    n = W * H * spp
    idx = dr.arange(mi.UInt32, n)
    rng = mi.PCG32(size=n, initstate=mi.UInt64(seed) * 0x9E3779B97F4A7C15 + 777, initseq=mi.UInt64(idx))
    x0, x1, y0, y1, zp = portal
    area = (x1 - x0) * (y1 - y0)
    # emission: a uniform point on the (single) area emitter, its direction from the same mixture of the
    # cosine lobe and the portal as at the surfaces: beta = Le cos / (pdf_area p(w))
    emitter = scene.emitters()[0]
    ps, _ = emitter.sample_position(0.0, mi.Point2f(rng.next_float32(), rng.next_float32()))
    si_e = mi.SurfaceInteraction3f(ps, mi.Color0f())
    si_e.wi = mi.Vector3f(0.0, 0.0, 1.0)
    le = emitter.eval(si_e)
    frame = mi.Frame3f(ps.n)
    d_cos = frame.to_world(mi.warp.square_to_cosine_hemisphere(mi.Point2f(rng.next_float32(), rng.next_float32())))
    pe = mi.Point3f(x0 + (x1 - x0) * rng.next_float32(), y0 + (y1 - y0) * rng.next_float32(), zp)
    use_pe = (ps.p.z > zp + 1e-4) & (rng.next_float32() < q)
    d0 = dr.select(use_pe, dr.normalize(pe - ps.p), d_cos)
    cos_e = dr.dot(d0, ps.n)
    pdf0 = dr.select(ps.p.z > zp + 1e-4, q * portal_pdf(mi, dr, ps.p, d0, portal) + (1.0 - q) * cos_e / dr.pi,
                     cos_e / dr.pi)
    ok0 = (cos_e > 0) & (pdf0 > 0)
    beta = dr.select(ok0, le * cos_e / (ps.pdf * dr.select(ok0, pdf0, 1.0)), 0.0)
    ray = mi.Ray3f(ps.p + 1e-4 * ps.n, d0)
    ctx = mi.BSDFContext(mi.TransportMode.Importance)
    img = np.zeros((H * W, 3))
    active = mi.Bool(True)
    for depth in range(max_depth):
        si = scene.ray_intersect(ray, active)
        active &= si.is_valid()
        bsdf = si.bsdf(ray)
        # connect to the camera
        sds, sw = sensor.sample_direction(si, mi.Point2f(rng.next_float32(), rng.next_float32()), active)
        c_ok = active & (sds.pdf > 0) & (dr.max(sw) > 0)
        c_ok &= ~scene.ray_test(si.spawn_ray_to(sds.p), c_ok)
        fc = bsdf.eval(ctx, si, si.to_local(sds.d), c_ok)
        val = dr.select(c_ok, beta * fc * sw, 0.0)
        px = mi.Int32(dr.floor(sds.uv.x))
        py = mi.Int32(dr.floor(sds.uv.y))
        c_ok &= (px >= 0) & (px < W) & (py >= 0) & (py < H)
        pix = dr.select(c_ok, py * W + px, 0)
        dr.eval(val, pix, c_ok)
        m = np.array(c_ok, dtype=bool)
        if m.any():
            p = np.array(pix)[m]
            v = np.stack([np.array(val.x)[m], np.array(val.y)[m], np.array(val.z)[m]], axis=1).astype(np.float64)
            for ch in range(3):
                img[:, ch] += np.bincount(p, weights=v[:, ch], minlength=H * W)
        # next direction: mixture of the BSDF and the portal on the lit side, the BSDF elsewhere
        lit = active & (si.p.z > zp + 1e-4)
        use_portal = lit & (rng.next_float32() < q)
        bs, _ = bsdf.sample(ctx, si, rng.next_float32(), mi.Point2f(rng.next_float32(), rng.next_float32()), active)
        pp = mi.Point3f(x0 + (x1 - x0) * rng.next_float32(), y0 + (y1 - y0) * rng.next_float32(), zp)
        wo_world = dr.select(use_portal, dr.normalize(pp - si.p), si.to_world(bs.wo))
        f, pdf_bsdf = bsdf.eval_pdf(ctx, si, si.to_local(wo_world), active)
        pdf = dr.select(lit, q * portal_pdf(mi, dr, si.p, wo_world, portal) + (1.0 - q) * pdf_bsdf, pdf_bsdf)
        beta, active = weigh_and_roulette(dr, rng, beta, active, f, pdf, depth >= rr_depth)
        ray = si.spawn_ray(wo_world)
        dr.eval(beta, active, ray, rng)
        if not dr.any(active):
            break
    return img.reshape(H, W, 3) / spp


def render(mi, dr, scene, spp, seed, portal, pass_spp=16, q=0.5):
    return accumulate(lambda m, s: render_pass(mi, dr, scene, m, s, portal, q), spp, seed, pass_spp)


if __name__ == "__main__":
    run_cli(__doc__, render, "2.8,3.3,0.0,2.0,4.2", 16, one_emitter=True)
