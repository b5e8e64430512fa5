#!/usr/bin/env python3
"""Pass one and a final render of Crytek Sponza, measured with /usr/bin/time -v (issue 10's targets:
pass one <= 10 min and <= 8 GB peak RSS; a 640x360 final image, whole process, <= 15 min).

Sponza stays out of the repository: give its folder (scene.obj, scene.mtl) as the first argument.
The script writes, into WORK_DIR, the copy the issue asks for (the OBJ linked, the MTL without its map_
lines and with Kd capped at 0.8: pass one on its own), a scene TOML (two-sided, the README's camera,
the default preset, method = "auto"), then runs `radray solve` and `radray render` and writes
WORK_DIR/sponza_bench.json and a Markdown table on stdout.

--textured renders the scene as it is instead: the OBJ, the MTL and the textures folder linked
unchanged (textured pass one: every element or hierarchy leaf reflects its texture mean). The
warnings radray prints (missing textures, clamped albedos) are saved in WORK_DIR/*.stderr.

usage: docs/sponza_bench.py SPONZA_DIR WORK_DIR [--radray target/release/radray] [--timeout-s 1800]
       [--method auto|hierarchical|matrix] [--quality preview|default|high] [--skip-render] [--textured]
       [--skip-solve]
"""

import argparse
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from timed_run import run_timed  # noqa: E402

KD_CAP = 0.8


def capped_mtl(text: str) -> str:
    """The MTL without map_ statements, every Kd channel capped at KD_CAP."""
    out = []
    for line in text.splitlines():
        stripped = line.strip()
        if stripped.lower().startswith("map_"):
            continue
        if stripped.startswith("Kd "):
            values = [min(float(x), KD_CAP) for x in stripped.split()[1:4]]
            line = "Kd " + " ".join(f"{v:g}" for v in values)
        out.append(line)
    return "\n".join(out) + "\n"


SCENE_TOML = """# Crytek Sponza (Frank Meinl, Crytek; CC BY 3.0), the GPU-Raytracer arrangement (roof plane, two
# icosphere lights). Made by docs/sponza_bench.py: {materials}.
quality = "{quality}"

[camera]
eye = [-110.0, 15.0, -5.0]
look_at = [100.0, 35.0, 0.0]
up = [0.0, 1.0, 0.0]
vfov_deg = 50.0

[image]
width = 640
height = 360

[radiosity]
method = "{method}"

[[mesh]]
obj = "scene.obj"
two_sided = true
"""


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("sponza_dir", type=Path)
    ap.add_argument("work_dir", type=Path)
    ap.add_argument("--radray", default="target/release/radray")
    ap.add_argument("--timeout-s", type=float, default=1800)
    ap.add_argument("--method", default="auto")
    ap.add_argument("--quality", default="default")
    ap.add_argument("--skip-render", action="store_true")
    ap.add_argument("--textured", action="store_true", help="the MTL and textures as they are")
    ap.add_argument("--skip-solve", action="store_true", help="only the whole-process render")
    args = ap.parse_args()

    obj = args.sponza_dir / "scene.obj"
    mtl = args.sponza_dir / "scene.mtl"
    if not obj.is_file() or not mtl.is_file():
        sys.exit(f"{args.sponza_dir}: expected scene.obj and scene.mtl")
    work = args.work_dir
    work.mkdir(parents=True, exist_ok=True)
    linked = [("scene.obj", obj)]
    if args.textured:
        linked += [("scene.mtl", mtl), ("textures", args.sponza_dir / "textures")]
        materials = "the MTL and textures unchanged (textured)"
    else:
        (work / "scene.mtl").write_text(capped_mtl(mtl.read_text(errors="replace")))
        materials = f"MTL without map_ lines, Kd capped at {KD_CAP}"
    for name, target in linked:
        link = work / name
        if link.exists() or link.is_symlink():
            link.unlink()
        link.symlink_to(target.resolve())
    scene = work / "sponza.toml"
    scene.write_text(SCENE_TOML.format(materials=materials, quality=args.quality, method=args.method))
    radray = str(Path(args.radray).resolve())

    results = {"scene": str(scene), "method": args.method, "quality": args.quality, "textured": args.textured}
    if not args.skip_solve:
        results["solve"] = run_timed(
            [radray, "-v", "solve", str(scene), "-o", str(work / "sponza.radsol"), "--stats", str(work / "solve.json")],
            args.timeout_s,
            work / "solve.stderr",
        )
    if (work / "solve.json").is_file() and not args.skip_solve:
        results["solve_stats"] = json.loads((work / "solve.json").read_text())
    if not args.skip_render:
        results["render"] = run_timed(
            [radray, "-v", "render", str(scene), "-o", str(work / "sponza.png"), "-o", str(work / "sponza.exr"),
             "--width", "640", "--height", "360", "--stats", str(work / "render.json")],
            args.timeout_s,
            work / "render.stderr",
        )
        if (work / "render.json").is_file():
            results["render_stats"] = json.loads((work / "render.json").read_text())
    (work / "sponza_bench.json").write_text(json.dumps(results, indent=2))

    print("| run | exit | wall s | CPU s | peak RSS GB |")
    print("|---|---|---|---|---|")
    for key in ("solve", "render"):
        r = results.get(key)
        if not r:
            continue
        cpu = (r["user_s"] or 0) + (r["system_s"] or 0)
        rss = (r["peak_rss_bytes"] or 0) / 1e9
        print(f"| {key} | {r['exit']} | {r['wall_s']} | {cpu:.1f} | {rss:.2f} |")


if __name__ == "__main__":
    main()
