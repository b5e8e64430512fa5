#!/usr/bin/env python3
"""Baseline of a radray binary on the test rooms (scenes/rooms/*.toml) against their references.

usage: python3 references/baseline_rooms.py [--radray PATH] [--rooms a,b,...] [--qualities default,high]
                                            [--out DIR] [--renders-only | --compare-only]

For each room and quality preset it runs, one process at a time (never two scenes at once):
  radray render ROOM.toml -o OUT/ROOM.QUALITY.final.exr  --direct pixel --quality QUALITY   (final image)
  radray render ROOM.toml -o OUT/ROOM.QUALITY.radiosity.exr --mode radiosity --quality QUALITY
under /usr/bin/time (user + system CPU seconds, wall seconds, peak RSS), then
  radray compare OUT/... references/ROOM/reference.exr --json
and prints a Markdown table of relMSE, CPU seconds and wall seconds, plus OUT/baseline.json.
relMSE against a reference includes the reference's own noise: subtract `relMSE_ref` of
references/ROOM/reference_noise.json for an estimate against the converged image.
Images are 256x256 as the scene files say. CPU seconds are the honest figure on a shared machine;
wall seconds depend on the load (recorded as the 1-minute load average).
"""
import argparse
import json
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)
from timed import timed  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--radray", default=os.path.join(ROOT, "target", "release", "radray"))
    ap.add_argument("--rooms", default="l_room,gap_room,alcove_hall,textured_box,rotunda")
    ap.add_argument("--qualities", default="default,high")
    ap.add_argument("--out", default="/tmp/radray_baseline")
    ap.add_argument("--renders-only", action="store_true")
    ap.add_argument("--compare-only", action="store_true")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    results_path = os.path.join(a.out, "baseline.json")
    results = json.load(open(results_path)) if os.path.exists(results_path) else {}
    modes = {"final": ["--direct", "pixel"], "radiosity": ["--mode", "radiosity"]}
    for room in a.rooms.split(","):
        toml = os.path.join(ROOT, "scenes", "rooms", room + ".toml")
        ref = os.path.join(HERE, room, "reference.exr")
        for q in a.qualities.split(","):
            for mode, flags in modes.items():
                key = "%s/%s/%s" % (room, q, mode)
                img = os.path.join(a.out, "%s.%s.%s.exr" % (room, q, mode))
                rec = results.get(key, {})
                if not a.compare_only:
                    try:
                        cpu, wall, rss, _ = timed([a.radray, "--quiet", "render", toml, "-o", img, "--quality", q] + flags)
                    except RuntimeError as e:  # e.g. a scene this binary refuses: record the message
                        rec = {"error": str(e)}
                        results[key] = rec
                        json.dump(results, open(results_path, "w"), indent=1)
                        print("%-28s %s" % (key, e), file=sys.stderr, flush=True)
                        continue
                    rec = {"cpu_s": cpu, "wall_s": wall, "peak_rss_mib": rss, "load1": os.getloadavg()[0]}
                    print("%-28s %7.1f CPU-s %6.1f s" % (key, cpu, wall), file=sys.stderr, flush=True)
                if not a.renders_only and os.path.exists(ref) and os.path.exists(img) and "error" not in rec:
                    r = subprocess.run([a.radray, "compare", img, ref, "--json"], capture_output=True, text=True)
                    if r.returncode != 0:
                        raise SystemExit(r.stderr)
                    m = json.loads(r.stdout)
                    rec["relMSE"] = m.get("rel_mse", m.get("relMSE"))
                    rec["compare"] = m
                results[key] = rec
                json.dump(results, open(results_path, "w"), indent=1)
    print("| room | quality | final relMSE | final CPU-s (wall) | radiosity relMSE | radiosity CPU-s (wall) |")
    print("|---|---|---|---|---|---|")
    for room in a.rooms.split(","):
        for q in a.qualities.split(","):
            f, r = results.get("%s/%s/final" % (room, q), {}), results.get("%s/%s/radiosity" % (room, q), {})
            fmt = lambda d: ("%.5f" % d["relMSE"]) if d.get("relMSE") is not None else (
                "refused" if "error" in d else "–")
            tm = lambda d: ("%.1f (%.1f)" % (d["cpu_s"], d["wall_s"])) if "cpu_s" in d else "–"
            print("| %s | %s | %s | %s | %s | %s |" % (room, q, fmt(f), tm(f), fmt(r), tm(r)))


if __name__ == "__main__":
    main()
