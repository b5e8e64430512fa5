#!/usr/bin/env python3
"""The path tracer's time to a given error on the test rooms, and radray's figures, in one run.

usage: python3 references/time_to_error.py [--rooms a,b] [--spp 64,128,256,512] [--target 0.0007]
                                           [--radray PATH] [--variants NAME=FLAGS;...] [--out DIR]

For each room it renders the reference scene with Mitsuba (references/render_one.py, the reference's
renderer and settings, seed 7, independent of the reference's seeds) at each spp, one process at a
time under /usr/bin/time, and compares with references/ROOM/reference.exr (`radray compare`). The
time to the target relMSE is interpolated log-log between the two spp that bracket it (relMSE of an
unbiased estimator falls as 1/spp). Then it runs each radray variant (`radray render
scenes/rooms/ROOM.toml` plus FLAGS) the same way. CPU seconds are user + system of the whole process
(Mitsuba's include its LLVM kernel compilation; `render_s` is the path tracer's own timer). Prints a
Markdown table and writes OUT/time_to_error.json.
"""
import argparse
import json
import math
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)
from timed import timed  # noqa: E402


def rel_mse(radray, img, ref):
    r = subprocess.run([radray, "compare", img, ref, "--json"], capture_output=True, text=True, check=True)
    m = json.loads(r.stdout)
    return m.get("rel_mse", m.get("relMSE"))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rooms", default="l_room,alcove_hall,textured_box,gap_room")
    ap.add_argument("--spp", default="64,128,256,512")
    ap.add_argument("--target", type=float, default=0.0007)
    ap.add_argument("--radray", default=os.path.join(ROOT, "target", "release", "radray"))
    ap.add_argument("--variants", default="")
    ap.add_argument("--skip-path-tracer", action="store_true")
    ap.add_argument("--out", default="/tmp/radray_tte")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    path = os.path.join(a.out, "time_to_error.json")
    results = json.load(open(path)) if os.path.exists(path) else {}
    for room in a.rooms.split(","):
        ref = os.path.join(HERE, room, "reference.exr")
        rec = results.setdefault(room, {"path_tracer": {}, "radray": {}})
        if not a.skip_path_tracer:
            for spp in [int(s) for s in a.spp.split(",")]:
                img = os.path.join(a.out, "%s.mitsuba.%d.exr" % (room, spp))
                cpu, wall, _, out = timed([sys.executable, os.path.join(HERE, "render_one.py"), room, str(spp), "7", img])
                info = json.loads(out.strip().splitlines()[-1])
                rec["path_tracer"][str(spp)] = {"cpu_s": cpu, "wall_s": wall, "render_s": info["render_s"],
                                                "relMSE": rel_mse(a.radray, img, ref), "load1": os.getloadavg()[0]}
                print("%-13s path tracer %5d spp: relMSE %.5f, %.1f CPU-s" % (room, spp, rec["path_tracer"][str(spp)]["relMSE"], cpu),
                      file=sys.stderr, flush=True)
                json.dump(results, open(path, "w"), indent=1)
        pts = sorted(((int(k), v) for k, v in rec["path_tracer"].items()), key=lambda kv: kv[0])
        rec["path_tracer_cpu_s_to_target"] = None
        for (s0, v0), (s1, v1) in zip(pts, pts[1:]):
            if v0["relMSE"] > a.target >= v1["relMSE"]:
                f = math.log(v0["relMSE"] / a.target) / math.log(v0["relMSE"] / v1["relMSE"])
                rec["path_tracer_cpu_s_to_target"] = math.exp(math.log(v0["cpu_s"]) + f * math.log(v1["cpu_s"] / v0["cpu_s"]))
        for variant in filter(None, a.variants.split(";")):
            name, _, flags = variant.partition("=")
            img = os.path.join(a.out, "%s.radray.%s.exr" % (room, name))
            toml = os.path.join(ROOT, "scenes", "rooms", room + ".toml")
            cpu, wall, _, _ = timed([a.radray, "--quiet", "render", toml, "-o", img] + flags.split())
            rec["radray"][name] = {"cpu_s": cpu, "wall_s": wall, "relMSE": rel_mse(a.radray, img, ref), "flags": flags}
            print("%-13s radray %-12s relMSE %.5f, %.1f CPU-s" % (room, name, rec["radray"][name]["relMSE"], cpu),
                  file=sys.stderr, flush=True)
        json.dump(results, open(path, "w"), indent=1)
    print("| room | path tracer CPU-s to %g | radray variant | relMSE | CPU-s |" % a.target)
    print("|---|---|---|---|---|")
    for room, rec in results.items():
        t = rec.get("path_tracer_cpu_s_to_target")
        for name, v in rec["radray"].items():
            print("| %s | %s | %s | %.5f | %.1f |" % (room, "%.0f" % t if t else "not reached", name, v["relMSE"], v["cpu_s"]))


if __name__ == "__main__":
    main()
