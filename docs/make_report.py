#!/usr/bin/env python3
"""Regenerates radray's accuracy and performance report (issue #5).

Builds radray in release mode, runs it on the Cornell box (and on variants of it that this script
writes into a temporary folder), and writes docs/accuracy.md, docs/performance.md and the PNGs under
docs/images/report_*.png.

Needs Python >= 3.11 and matplotlib (`pip install matplotlib`); nothing else is imported directly.
Error metrics come from `radray compare --json` (the metrics of references/compare.py). Times are
whole-process wall-clock seconds with the CPU seconds (user + system) beside them, and peak memory is
the process's peak resident set (ru_maxrss), all from os.wait4.

    python3 docs/make_report.py            # the full report: about 10-15 minutes on a quiet 2-core machine
    python3 docs/make_report.py --quick    # a smoke run in about a minute (fewer, cheaper settings)
    python3 docs/make_report.py --benches  # also run the criterion benches briefly (adds ~10 minutes)
    python3 docs/make_report.py --readme   # also write the measured preset figures into README.md
    python3 docs/make_report.py --presets-only --readme   # only the presets' figures, into README.md

Timings depend on what else the machine is doing: the load average before and after is recorded in
both documents. Run it on a quiet machine before committing its outputs.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"
IMAGES = DOCS / "images"
RADRAY = ROOT / "target" / "release" / "radray"
SCENES = ROOT / "scenes"
REFERENCES = ROOT / "references"

# The path tracer's published error on cornell_original (references/README.md): spp, render seconds,
# whole-process seconds, relMSE.
PATH_TRACER = [(16, 0.26, 0.68, 0.0112), (64, 0.95, 1.38, 0.00276), (256, 3.81, 4.19, 0.00070)]
TARGET_REL_MSE = 0.00070
TARGET_SECONDS = 4.19

# The second view of the two-view study (the batch example's side camera in README.md).
SIDE_CAMERA = {"eye": [500.0, 300.0, -500.0], "look_at": [278.0, 273.0, 280.0], "up": [0.0, 1.0, 0.0]}


# ----------------------------------------------------------------------------------------------------
# Running processes


@dataclass
class Run:
    """One finished process: what it printed and what it cost."""

    cmd: list[str]
    code: int
    wall_s: float
    cpu_s: float
    peak_rss_mib: float
    stdout: str
    stderr: str


TIME = Path("/usr/bin/time")


def run(cmd: list[str], check: bool = True) -> Run:
    """Runs `cmd` to completion and measures it (wall clock, CPU = user + system, peak RSS).

    The peak RSS comes from GNU time when /usr/bin/time exists: the ru_maxrss that os.wait4 reports
    for a child of this process also counts the forked Python (with matplotlib, ~90 MiB) before exec.
    """
    cmd = [str(c) for c in cmd]
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err, tempfile.NamedTemporaryFile() as rss:
        wrapped = [str(TIME), "-f", "%M", "-o", rss.name, *cmd] if TIME.exists() else cmd
        start = time.perf_counter()
        proc = subprocess.Popen(wrapped, stdout=out, stderr=err)
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - start
        proc.returncode = os.waitstatus_to_exitcode(status)
        out.seek(0)
        err.seek(0)
        peak_kib = usage.ru_maxrss  # Linux: KiB
        if TIME.exists():
            found = re.findall(r"^(\d+)$", Path(rss.name).read_text(), re.M)
            peak_kib = int(found[-1]) if found else peak_kib
        result = Run(
            cmd=cmd,
            code=proc.returncode,
            wall_s=wall,
            cpu_s=usage.ru_utime + usage.ru_stime,
            peak_rss_mib=peak_kib / 1024.0,
            stdout=out.read().decode(errors="replace"),
            stderr=err.read().decode(errors="replace"),
        )
    if check and result.code != 0:
        sys.exit(f"failed ({result.code}): {' '.join(result.cmd)}\n{result.stderr}")
    return result


def radray(command: str, *args: object, check: bool = True) -> Run:
    """Runs a radray subcommand; `render` and `solve` with --quiet (no progress bars)."""
    quiet = ["--quiet"] if command in ("render", "solve") else []
    return run([RADRAY, command, *quiet, *args], check=check)


REPEAT_BELOW_S = 5.0


def timed(*args: object, stats_file: Path | None = None) -> tuple[Run, dict | None]:
    """A radray run timed; a run shorter than REPEAT_BELOW_S is run twice and the faster kept (the
    output is deterministic, so only the timing differs), to damp the noise of a shared machine."""
    best: tuple[Run, dict | None] | None = None
    for _ in range(2):
        r = radray(*args)
        stats = json.loads(stats_file.read_text()) if stats_file else None
        if best is None or r.wall_s < best[0].wall_s:
            best = (r, stats)
        if r.wall_s >= REPEAT_BELOW_S:
            break
    assert best is not None
    return best


def compare(test: Path, reference: Path, diff_png: Path | None = None) -> dict:
    """`radray compare --json`: relMSE, mean_abs_rel_err, rmse (references/compare.py's metrics)."""
    extra = ["--diff", diff_png] if diff_png else []
    return json.loads(radray("compare", test, reference, "--json", *extra).stdout)


def load_average() -> str:
    return " ".join(Path("/proc/loadavg").read_text().split()[:3])


def log(msg: str) -> None:
    print(f"[{time.strftime('%H:%M:%S')} load {load_average()}] {msg}", flush=True)


# ----------------------------------------------------------------------------------------------------
# Scene files


def toml_value(v: object) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    raise TypeError(v)


def write_scene(path: Path, base: Path, camera: dict | None = None, **sections: dict) -> Path:
    """Writes a copy of scene `base` to `path` with some keys replaced, e.g.
    `radiosity={"max_element_edge": 48.0}`; mesh paths are made absolute."""
    scene = tomllib.loads(base.read_text())
    if camera:
        scene.setdefault("camera", {}).update(camera)
    for name, values in sections.items():
        scene.setdefault(name, {}).update(values)
    lines = []
    for key, value in scene.items():
        if isinstance(value, dict):
            lines.append(f"[{key}]")
            lines += [f"{k} = {toml_value(v)}" for k, v in value.items()]
        elif isinstance(value, list) and value and isinstance(value[0], dict):
            for table in value:
                lines.append(f"[[{key}]]")
                for k, v in table.items():
                    if k == "obj":
                        v = str((base.parent / v).resolve())
                    lines.append(f"{k} = {toml_value(v)}")
        else:
            lines.insert(0, f"{key} = {toml_value(value)}")
        lines.append("")
    path.write_text("\n".join(lines))
    return path


# ----------------------------------------------------------------------------------------------------
# Settings of the time-to-error study


@dataclass
class Setting:
    """A way to render cornell_original: a preset (`quality`) or explicit values."""

    name: str
    quality: str | None = None
    max_element_edge: float | None = None
    hemicube: int | None = None
    spp: int | None = None
    light_samples: int | None = None

    def scene(self, tmp: Path, camera: dict | None = None, tag: str = "") -> Path:
        base = SCENES / "cornell_box.toml"
        radiosity, image, render = {}, {}, {}
        if self.max_element_edge:
            radiosity["max_element_edge"] = self.max_element_edge
        if self.hemicube:
            radiosity["hemicube_resolution"] = self.hemicube
        if self.spp:
            image["samples_per_pixel"] = self.spp
        if self.light_samples:
            render["light_samples"] = self.light_samples
        path = tmp / f"{self.name}{tag}.toml"
        return write_scene(path, base, camera=camera, radiosity=radiosity, image=image, render=render)

    def args(self) -> list[str]:
        """Command-line flags: the preset, and --spp laid over it (light samples have no flag)."""
        if not self.quality:
            return []
        return ["--quality", self.quality] + (["--spp", str(self.spp)] if self.spp else [])

    def describe(self, info: dict) -> str:
        return (
            f"edge {info['max_element_edge']:.1f} mm ({info['elements']} el.), "
            f"{info['hemicube_resolution_px']}², {info['spp']} spp, light samples {info['light_samples']}"
        )


@dataclass
class Measured:
    setting: Setting
    mode: str
    elements: int
    description: str
    run: Run
    stats: dict
    metrics: dict
    image: Path
    extra: dict = field(default_factory=dict)


def render_and_measure(setting: Setting, mode: str, tmp: Path, reference: Path) -> Measured:
    """Renders cornell_original in `mode` ("final" = two-pass with --direct pixel, or "radiosity")
    from scratch in one process, and compares the EXR with the reference."""
    scene = setting.scene(tmp)
    out = tmp / f"{setting.name}.{mode}.exr"
    stats_file = tmp / f"{setting.name}.{mode}.json"
    mode_args = ["--mode", "final", "--direct", "pixel"] if mode == "final" else ["--mode", "radiosity"]
    r, stats = timed("render", scene, "-o", out, *mode_args, *setting.args(), "--stats", stats_file, stats_file=stats_file)
    info = json.loads(radray("info", scene, "--json", *setting.args()[:2]).stdout)  # info has no --spp
    described = tomllib.loads(scene.read_text())
    spp = setting.spp or described["image"].get("samples_per_pixel", 16)
    ls = setting.light_samples or described.get("render", {}).get("light_samples", 4)
    if setting.quality:
        # Quality::settings in src/scene/mod.rs: (spp, light samples) of each preset.
        spp, ls = {"preview": (4, 1), "default": (16, 4), "high": (64, 16)}[setting.quality]
        spp = setting.spp or spp
    info.update(spp=spp, light_samples=ls)
    m = Measured(setting, mode, stats["elements"], setting.describe(info), r, stats, compare(out, reference), out)
    log(f"{setting.name:>14} {mode:>9}: {r.wall_s:6.2f} s wall, {r.cpu_s:6.2f} CPU-s, relMSE {m.metrics['relMSE']:.5f}")
    return m


# ----------------------------------------------------------------------------------------------------
# Plots


def plot_time_to_error(results: list[Measured], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker

    fig, ax = plt.subplots(figsize=(7, 4.8))
    pt_x = [p[2] for p in PATH_TRACER]
    pt_y = [p[3] for p in PATH_TRACER]
    ax.plot(pt_x, pt_y, "k-o", label="Mitsuba 3 path tracer (whole process)")
    ax.plot([p[1] for p in PATH_TRACER], pt_y, "k:", marker="o", mfc="none", label="path tracer (render only)")
    for x, y, p in zip(pt_x, pt_y, PATH_TRACER):
        ax.annotate(f"{p[0]} spp", (x, y), textcoords="offset points", xytext=(5, 4), fontsize=8)
    for mode, style, label in (("final", "C0s", "radray final (--direct pixel)"), ("radiosity", "C1^", "radray radiosity mode")):
        pts = sorted((m.run.wall_s, m.metrics["relMSE"], m.setting.name) for m in results if m.mode == mode)
        ax.plot([p[0] for p in pts], [p[1] for p in pts], style, ls="none", label=label)
        for x, y, name in pts:
            ax.annotate(name, (x, y), textcoords="offset points", xytext=(5, -10), fontsize=7, color=style[:2])
    ax.axhline(TARGET_REL_MSE, color="grey", lw=0.8, ls="--")
    ax.axvline(TARGET_SECONDS, color="grey", lw=0.8, ls="--")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ticks = [t for t in (0.25, 0.5, 1, 2, 4, 8, 16, 32, 64, 128) if ax.get_xlim()[0] <= t <= ax.get_xlim()[1]]
    ax.set_xticks(ticks, [f"{t:g}" for t in ticks])
    ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    ax.set_xlabel("whole-process wall-clock seconds")
    ax.set_ylabel("relMSE against the reference")
    ax.set_title(f"cornell_original, 256×256, box filter (load {load_average()})", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_panels(panels: list[tuple[str, Path]], path: Path, colorbar_from: int) -> None:
    """One row of PNG panels with titles; a 0..1 magma colour bar for the difference panels."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.image as mpimg
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(panels), figsize=(2.6 * len(panels), 3.2))
    for ax, (title, png) in zip(axes, panels):
        ax.imshow(mpimg.imread(png))
        ax.set_title(title, fontsize=8)
        ax.axis("off")
    if colorbar_from < len(panels):
        mappable = plt.cm.ScalarMappable(cmap="magma", norm=matplotlib.colors.Normalize(0, 1))
        bar = fig.colorbar(mappable, ax=list(axes[colorbar_from:]), fraction=0.04, pad=0.02)
        bar.set_label("max over channels |x − ref| / (|ref| + 0.01)", fontsize=7)
        bar.ax.tick_params(labelsize=7)
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)


def plot_scaling(rows: list[dict], fits: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = [r["elements"] for r in rows]
    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 4))
    a.plot(n, [r["pass_one_s"] for r in rows], "C0o-", label=f"measured (slope {fits['time']:.2f})")
    a.plot(n, [r["predicted_s"] for r in rows], "C0x--", label="radray info's estimate")
    a.set_ylabel("pass one (form factors + solve), wall seconds")
    b.plot(n, [r["peak_rss_mib"] for r in rows], "C1o-", label=f"peak RSS (slope {fits['rss']:.2f})")
    b.plot(n, [r["ff_mib"] for r in rows], "C2s-", label=f"form-factor matrix (slope {fits['ff']:.2f})")
    b.plot(n, [r["predicted_mib"] for r in rows], "C2x--", label="radray info's estimate")
    b.set_ylabel("MiB")
    for ax in (a, b):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("elements")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(f"Cornell box, hemicube {rows[0]['hemicube']}², 2 cores (load {load_average()})", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


# ----------------------------------------------------------------------------------------------------
# Helpers for the documents


def fit_loglog(xs: list[float], ys: list[float]) -> float:
    """Least-squares slope of log y against log x."""
    lx = [math.log(x) for x in xs]
    ly = [math.log(y) for y in ys]
    mx, my = sum(lx) / len(lx), sum(ly) / len(ly)
    sxx = sum((x - mx) ** 2 for x in lx)
    return sum((x - mx) * (y - my) for x, y in zip(lx, ly)) / sxx if sxx > 0 else float("nan")


def table(header: list[str], rows: list[list[object]]) -> str:
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    out += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(out)


def machine_header(load_before: str, started: float) -> str:
    cpu = "unknown CPU"
    for line in Path("/proc/cpuinfo").read_text().splitlines():
        if line.startswith("model name"):
            cpu = line.split(":", 1)[1].strip()
            break
    mem_kib = int(re.search(r"MemTotal:\s+(\d+)", Path("/proc/meminfo").read_text()).group(1))
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True).stdout
    return (
        f"Generated by `python3 docs/make_report.py{' --quick' if ARGS.quick else ''}` on "
        f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime(started))} at commit `{commit.strip() or '?'}`; "
        f"{os.cpu_count()} logical CPUs ({cpu}), {mem_kib / 2**20:.1f} GiB RAM. "
        f"Load average (1, 5, 15 min) before: {load_before}; after: {load_average()}. "
        "A load above the core count means other processes shared the CPUs and wall-clock times are "
        "inflated; CPU seconds are the steadier figure."
    )


def rel(p: Path) -> str:
    return str(p.relative_to(DOCS))


# ----------------------------------------------------------------------------------------------------
# The studies


def time_to_error(tmp: Path) -> tuple[list[Measured], str]:
    reference = REFERENCES / "cornell_original" / "reference.exr"
    if ARGS.quick:
        settings = [
            Setting("preview", quality="preview"),
            Setting("coarse-16spp", max_element_edge=48.0, hemicube=64, spp=16, light_samples=4),
        ]
    else:
        settings = [
            Setting("preview", quality="preview"),
            Setting("coarse-8spp", max_element_edge=48.0, hemicube=64, spp=8, light_samples=2),
            Setting("coarse-16spp", max_element_edge=48.0, hemicube=64, spp=16, light_samples=4),
            Setting("coarse-32spp", max_element_edge=48.0, hemicube=64, spp=32, light_samples=8),
            Setting("preview-16spp", quality="preview", spp=16),
            Setting("mid-16spp", max_element_edge=32.0, hemicube=64, spp=16, light_samples=4),
            Setting("default", quality="default"),
            Setting("shipped", max_element_edge=25.0, hemicube=256, spp=16, light_samples=4),
            Setting("high", quality="high"),
        ]
    results = []
    for s in settings:
        for mode in ("final", "radiosity"):
            results.append(render_and_measure(s, mode, tmp, reference))
    plot_time_to_error(results, IMAGES / "report_time_to_error.png")

    rows = []
    for m in results:
        rows.append(
            [
                f"`{m.setting.name}`",
                m.mode,
                m.description,
                f"{m.run.wall_s:.2f}",
                f"{m.run.cpu_s:.2f}",
                f"{m.stats['form_factor_seconds'] + m.stats['solve_seconds']:.2f} + {m.stats['render_seconds']:.2f}",
                f"{m.run.peak_rss_mib:.0f}",
                f"{m.metrics['relMSE']:.5f}",
                f"{m.metrics['mean_abs_rel_err']:.4f}",
                f"{m.metrics['rmse']:.4f}",
            ]
        )
    for spp, render_s, whole_s, err in PATH_TRACER:
        rows.append([f"path tracer {spp} spp", "—", "Mitsuba 3, LLVM", f"{whole_s:.2f}", "—", f"{render_s:.2f}", "—", f"{err:.5f}", "—", "—"])
    header = ["setting", "mode", "what", "wall s", "CPU s", "pass one + pass two s", "peak RSS MiB", "relMSE", "mean abs. rel.", "RMSE"]
    meeting = [m for m in results if m.mode == "final" and m.metrics["relMSE"] <= TARGET_REL_MSE and m.run.wall_s < TARGET_SECONDS]
    if meeting:
        best = min(meeting, key=lambda m: m.run.wall_s)
        verdict = (
            f"**Target met.** The fastest final image with relMSE ≤ {TARGET_REL_MSE} in this run is `{best.setting.name}` "
            f"({best.description}): relMSE {best.metrics['relMSE']:.5f} in {best.run.wall_s:.2f} s whole process "
            f"({best.run.cpu_s:.2f} CPU-s), against the path tracer's {TARGET_REL_MSE} in {TARGET_SECONDS} s. "
            f"All settings that meet it: {', '.join(f'`{m.setting.name}` ({m.run.wall_s:.2f} s)' for m in meeting)}."
        )
    else:
        best_err = min((m for m in results if m.mode == "final"), key=lambda m: m.metrics["relMSE"])
        verdict = (
            f"**Target not met in this run.** No final image reached relMSE ≤ {TARGET_REL_MSE} in under "
            f"{TARGET_SECONDS} s; the most accurate was `{best_err.setting.name}` ({best_err.metrics['relMSE']:.5f} "
            f"in {best_err.run.wall_s:.2f} s)."
        )
    presets = [m for m in results if m.mode == "final" and m.setting.quality and not m.setting.spp]
    verdict += " Presets as they are: " + "; ".join(
        f"`{m.setting.name}` {m.metrics['relMSE']:.5f} in {m.run.wall_s:.2f} s"
        + (" (meets it)" if m.metrics["relMSE"] <= TARGET_REL_MSE and m.run.wall_s < TARGET_SECONDS else "")
        for m in presets
    ) + "."
    text = table(header, rows) + "\n\n" + verdict
    return results, text


def second_view(tmp: Path) -> str:
    """Pass one once, then another camera from the saved solution, against a full run of that view."""
    s = Setting("second-view", max_element_edge=48.0, hemicube=64, spp=16, light_samples=4)
    if not ARGS.quick:
        s = Setting("second-view", max_element_edge=25.0, hemicube=256, spp=16, light_samples=4)
    front = s.scene(tmp)
    side = s.scene(tmp, camera=SIDE_CAMERA, tag="-side")
    solution = tmp / "view.radsol"
    full, _ = timed("render", side, "-o", tmp / "side_full.exr", "--direct", "pixel")
    solve, _ = timed("solve", front, "-o", solution, "--stats", tmp / "solve.json")
    again, _ = timed("render", side, "--solution", solution, "-o", tmp / "side_reuse.exr", "--direct", "pixel")
    first, _ = timed("render", front, "--solution", solution, "-o", tmp / "front_reuse.exr", "--direct", "pixel")
    radray("render", side, "--solution", solution, "-o", IMAGES / "report_second_view.png", "--direct", "pixel")
    same = compare(tmp / "side_reuse.exr", tmp / "side_full.exr")
    stats = json.loads((tmp / "solve.json").read_text())
    log(f"second view: full {full.wall_s:.2f} s, from solution {again.wall_s:.2f} s")
    rows = [
        ["full run of the side view (`render`, pass one + pass two)", f"{full.wall_s:.2f}", f"{full.cpu_s:.2f}", f"{full.peak_rss_mib:.0f}"],
        ["`solve -o view.radsol` (pass one once)", f"{solve.wall_s:.2f}", f"{solve.cpu_s:.2f}", f"{solve.peak_rss_mib:.0f}"],
        ["front view from the solution (`render --solution`)", f"{first.wall_s:.2f}", f"{first.cpu_s:.2f}", f"{first.peak_rss_mib:.0f}"],
        ["**side view from the solution** (`render --solution`)", f"**{again.wall_s:.2f}**", f"{again.cpu_s:.2f}", f"{again.peak_rss_mib:.0f}"],
    ]
    return (
        f"Setting: {stats['elements']} elements (max_element_edge {s.max_element_edge} mm), hemicube {s.hemicube}², "
        f"{s.spp} spp, {s.light_samples} light samples, `--direct pixel`. The side camera is "
        f"eye {SIDE_CAMERA['eye']}, look_at {SIDE_CAMERA['look_at']}.\n\n"
        + table(["run", "wall s", "CPU s", "peak RSS MiB"], rows)
        + f"\n\nThe side view from the saved solution costs {again.wall_s / full.wall_s:.0%} of the full run "
        f"in wall-clock time ({again.wall_s:.2f} s against {full.wall_s:.2f} s) and {again.cpu_s / full.cpu_s:.0%} "
        f"in CPU time ({again.cpu_s:.2f} against {full.cpu_s:.2f} CPU-s). The two side-view images agree to relMSE "
        f"{same['relMSE']:.2e} (same seed: they should be identical).\n\n"
        "radray has no command-line camera override (`render` has `--width/--height/--spp` but no "
        "`--eye/--look-at`), so the script writes a second scene file with another `[camera]`; the "
        "solution file is keyed by the mesh fingerprint, which the camera does not enter. (`radray batch` "
        "jobs do take a `camera` override, in one process.)\n\n"
        f"![second view]({rel(IMAGES / 'report_second_view.png')})"
    )


def pictures(tmp: Path, ttE: list[Measured]) -> str:
    """Reference, radiosity mode, final mode and the two difference images, one PNG per scene."""
    scenes = [("cornell_original", SCENES / "cornell_box.toml")]
    if not ARGS.quick:
        scenes += [("cornell_empty", SCENES / "cornell_empty.toml"), ("cornell_specular", SCENES / "cornell_specular.toml")]
    parts = []
    rows = []
    for name, scene_file in scenes:
        reference = REFERENCES / name / "reference.exr"
        scene = write_scene(tmp / f"pic_{name}.toml", scene_file, render={"light_samples": 4})
        out = tmp / f"pic_{name}"
        r = radray("render", scene, "-o", f"{out}.exr", "-o", f"{out}.png", "--mode", "both", "--direct", "pixel")
        m = {}
        for mode in ("radiosity", "final"):
            m[mode] = compare(Path(f"{out}.{mode}.exr"), reference, diff_png=Path(f"{out}.{mode}.diff.png"))
        info = json.loads(radray("info", scene, "--json").stdout)
        png = IMAGES / f"report_{name}.png"
        plot_panels(
            [
                ("reference (Mitsuba 3)", REFERENCES / name / "reference.png"),
                (f"radiosity mode\nrelMSE {m['radiosity']['relMSE']:.5f}", Path(f"{out}.radiosity.png")),
                (f"final (--direct pixel)\nrelMSE {m['final']['relMSE']:.5f}", Path(f"{out}.final.png")),
                ("radiosity − reference", Path(f"{out}.radiosity.diff.png")),
                ("final − reference", Path(f"{out}.final.diff.png")),
            ],
            png,
            colorbar_from=3,
        )
        rows.append(
            [
                name,
                f"{info['elements']} el., edge {info['max_element_edge']:.0f} mm, {info['hemicube_resolution_px']}²",
                f"{m['radiosity']['relMSE']:.5f}",
                f"{m['final']['relMSE']:.5f}",
                f"{m['final']['mean_abs_rel_err']:.4f}",
                f"{r.wall_s:.2f} ({r.cpu_s:.2f})",
            ]
        )
        parts.append(f"### {name}\n\n![{name}]({rel(png)})")
        log(f"pictures {name}: radiosity {m['radiosity']['relMSE']:.5f}, final {m['final']['relMSE']:.5f}")
    head = (
        "Each scene as shipped in `scenes/` (256×256, 16 spp, box filter), rendered once with "
        "`--mode both --direct pixel` and 4 light samples. Left to right: the path-traced reference, "
        "radray's pure radiosity output, radray's two-pass final image, and `radray compare --diff` "
        "false-colour maps of the per-pixel relative error (0 black, 1 or more pale yellow). PNGs use "
        "radray's default clamp tone curve; the reference preview is clamped too.\n\n"
        + table(["scene", "mesh", "relMSE radiosity", "relMSE final", "mean abs. rel. final", "wall s (CPU s), both images"], rows)
    )
    return head + "\n\n" + "\n\n".join(parts)


def scaling(tmp: Path) -> tuple[str, dict]:
    hemicube = 128
    edges = [45.0, 28.0, 20.0] if ARGS.quick else [45.0, 28.0, 20.0, 14.0, 10.0, 7.0]
    rows = []
    for edge in edges:
        scene = write_scene(
            tmp / f"scale_{edge}.toml", SCENES / "cornell_box.toml", radiosity={"max_element_edge": edge, "hemicube_resolution": hemicube}
        )
        info = json.loads(radray("info", scene, "--json").stdout)
        stats_file = tmp / f"scale_{edge}.json"
        r = radray("solve", scene, "-o", tmp / "scale.radsol", "--stats", stats_file)
        st = json.loads(stats_file.read_text())
        row = {
            "edge": edge,
            "elements": st["elements"],
            "hemicube": hemicube,
            "ff_s": st["form_factor_seconds"],
            "solve_s": st["solve_seconds"],
            "pass_one_s": st["form_factor_seconds"] + st["solve_seconds"],
            "wall_s": r.wall_s,
            "cpu_s": r.cpu_s,
            "peak_rss_mib": r.peak_rss_mib,
            "ff_mib": st["form_factor_bytes"] / 2**20,
            "nnz": st["form_factor_nonzeros"],
            "predicted_s": info["estimated_form_factor_seconds"],
            "predicted_mib": info["estimated_form_factor_bytes"] / 2**20,
        }
        rows.append(row)
        log(f"scaling: {row['elements']} elements: {row['pass_one_s']:.2f} s, {row['peak_rss_mib']:.0f} MiB")
    n = [r["elements"] for r in rows]
    fits = {
        "time": fit_loglog(n, [r["pass_one_s"] for r in rows]),
        "cpu": fit_loglog(n, [r["cpu_s"] for r in rows]),
        "rss": fit_loglog(n, [r["peak_rss_mib"] for r in rows]),
        "ff": fit_loglog(n, [r["ff_mib"] for r in rows]),
    }
    # The upper half of the ladder shows the asymptotic behaviour better than the whole.
    half = rows[len(rows) // 2 - 1 :] if len(rows) >= 4 else rows
    fits["time_upper"] = fit_loglog([r["elements"] for r in half], [r["pass_one_s"] for r in half])
    plot_scaling(rows, fits, IMAGES / "report_scaling.png")
    text = (
        f"`radray solve` on the Cornell box written with decreasing `max_element_edge` and a fixed hemicube "
        f"of {hemicube}² (256² would put the 40k-element point at several times the minutes this report "
        f"can spend: the hemicube time grows with its pixel count as well as with the elements it draws). "
        "Pass one = the form-factor and solve seconds radray records in `--stats`; wall, CPU and peak RSS "
        "are of the whole process; the estimates are `radray info`'s.\n\n"
        + table(
            ["max edge mm", "elements", "form factors s", "solve s", "wall s", "CPU s", "peak RSS MiB", "matrix MiB", "non-zeros / row", "info: s", "info: MiB"],
            [
                [
                    f"{r['edge']:g}",
                    r["elements"],
                    f"{r['ff_s']:.2f}",
                    f"{r['solve_s']:.3f}",
                    f"{r['wall_s']:.2f}",
                    f"{r['cpu_s']:.2f}",
                    f"{r['peak_rss_mib']:.0f}",
                    f"{r['ff_mib']:.0f}",
                    f"{r['nnz'] / r['elements']:.0f}",
                    f"{r['predicted_s']:.1f}",
                    f"{r['predicted_mib']:.0f}",
                ]
                for r in rows
            ],
        )
        + "\n\nLeast-squares slopes in log-log space (cost ∝ elements^k): "
        f"pass-one time k = **{fits['time']:.2f}** (the upper half of the ladder alone: {fits['time_upper']:.2f}); "
        f"process CPU seconds k = {fits['cpu']:.2f}; peak RSS k = **{fits['rss']:.2f}**; form-factor matrix "
        f"k = {fits['ff']:.2f}. Every element's hemicube draws every other element, so the form-factor "
        "time is quadratic in the element count once the fixed per-hemicube cost stops dominating. A dense "
        f"matrix would give 2 for memory too. A row cannot hold more entries than the hemicube's "
        f"3·{hemicube}² = {3 * hemicube**2} pixels; at {rows[-1]['elements']} elements the rows hold "
        f"{rows[-1]['nnz'] / rows[-1]['elements']:.0f} on average ({rows[-1]['nnz'] / rows[-1]['elements'] / (3 * hemicube**2):.0%} "
        "of that cap), so the matrix is still close to its quadratic regime and would turn linear only "
        "when the rows saturate. Peak RSS follows the matrix once it outweighs the rest of the process. "
        f"`radray info` predicted {rows[-1]['predicted_mib']:.0f} MiB for the measured "
        f"{rows[-1]['ff_mib']:.0f} MiB matrix at {rows[-1]['elements']} elements and {hemicube}² "
        f"({rows[-1]['predicted_mib'] / rows[-1]['ff_mib'] - 1:+.0%}).\n\n"
        f"![scaling]({rel(IMAGES / 'report_scaling.png')})"
    )
    return text, fits


def memory_guard(tmp: Path) -> str:
    """A mesh whose form factors cannot fit: refused before any allocation, with suggestions."""
    edge, hemicube = 2.0, 256
    scene = write_scene(tmp / "guard.toml", SCENES / "cornell_box.toml", radiosity={"max_element_edge": edge, "hemicube_resolution": hemicube})
    info = radray("info", scene)
    info_json = json.loads(radray("info", scene, "--json").stdout)
    n = info_json["elements"]
    bound_gib = n * min(n, 3 * hemicube**2) * 8 / 2 / 2**30
    available_gib = int(re.search(r"MemAvailable:\s+(\d+)", Path("/proc/meminfo").read_text()).group(1)) / 2**20
    summary = "\n".join(line for line in info.stdout.splitlines() if re.match(r"(elements|hemicube|form factors)", line))
    if bound_gib <= available_gib:
        return f"Skipped: this machine has {available_gib:.0f} GiB available, more than the {bound_gib:.0f} GiB the test mesh would need."
    r = radray("solve", scene, "-o", tmp / "guard.radsol", check=False)
    log(f"memory guard: exit {r.code} after {r.wall_s:.2f} s, peak RSS {r.peak_rss_mib:.0f} MiB")
    return (
        f"The Cornell box at `max_element_edge = {edge}` (mm) and a {hemicube}² hemicube. `radray info` "
        f"predicts, before anything is solved:\n\n```\n{summary}\n```\n\n"
        f"`radray solve` refuses it before computing a single form factor (exit code {r.code}, after "
        f"{r.wall_s:.2f} s and {r.peak_rss_mib:.0f} MiB peak RSS: the mesh and nothing more). The guard "
        "(`pipeline::check_memory`) compares half of the upper bound rows × min(elements, 3N²) × 8 bytes "
        f"with `MemAvailable` ({available_gib:.1f} GiB when this ran):\n\n```\n{r.stderr.strip()}\n```"
    )


BENCHES = {
    "hemicube": "one hemicube in a 10k-element Cornell box at N = 128 and 256 (hemicubes/s, pixels/s), and a "
    "whole form-factor matrix of a coarse (100 mm) Cornell box at N = 64",
    "solver": "one Gauss-Seidel (SOR 1.2) sweep, one Jacobi sweep (serial and rayon rows), one progressive "
    "selection and shot, and full solves, on a synthetic 10k-element matrix with ~5k entries per row",
    "trace": "BVH build, closest-hit rays (coherent camera rays and incoherent rays), any-hit shadow rays, "
    "and the Whitted tracer per sample, on a generated ~20k-triangle box with a mirror and a glass sphere",
    "film": "per-sample film overhead (512×512, 16 spp) with each reconstruction filter and a trivial "
    "shader, and the comparison metrics and difference image on 512×512 images",
    "render": "whole pipeline: cornell_box at the preview preset, 128×128, scene file to image; and pass "
    "two alone on cornell_specular at 512×512, 16 spp, from a solved scene, in each mode",
}


def benches() -> str:
    rows = [[f"`{name}`", f"`cargo bench --bench {name}`", what] for name, what in BENCHES.items()]
    text = (
        "Criterion benches in `benches/` (run one briefly with "
        "`cargo bench --bench NAME -- --warm-up-time 1 --measurement-time 3`):\n\n"
        + table(["bench", "command", "what it measures"], rows)
    )
    if not ARGS.benches:
        return text + "\n\nNot run in this report (`python3 docs/make_report.py --benches` runs them and lists the times here)."
    results = []
    for name in BENCHES:
        log(f"bench {name}")
        r = run(["cargo", "bench", "--bench", name, "--", "--warm-up-time", "1", "--measurement-time", "3"], check=False)
        current = None
        for line in r.stdout.splitlines():
            t = re.search(r"time:\s+\[([^\]]+)\]", line)
            if t:
                head = line[: line.find("time:")].strip() or current
                middle = t.group(1).split()
                results.append([f"`{name}`", head, " ".join(middle[2:4]) if len(middle) >= 6 else t.group(1)])
            elif line.strip() and not line.startswith(" "):
                current = line.strip()
    return text + "\n\nMedian estimates of this run:\n\n" + table(["bench", "case", "time"], results)


def preset_cells(results: list[Measured]) -> dict[str, str]:
    cells = {}
    for preset in ("preview", "default", "high"):
        final = next((m for m in results if m.setting.name == preset and m.mode == "final"), None)
        rad = next((m for m in results if m.setting.name == preset and m.mode == "radiosity"), None)
        if final and rad:
            cells[preset] = (
                f"{final.elements:,} elements; final {final.run.wall_s:.1f} s wall ({final.run.cpu_s:.1f} CPU-s), "
                f"{final.run.peak_rss_mib:.0f} MiB peak; relMSE final {final.metrics['relMSE']:.5f}, "
                f"radiosity {rad.metrics['relMSE']:.5f}"
            )
    return cells


def update_readme(cells: dict[str, str]) -> None:
    """Writes the preset figures into README.md's presets table, after each `<!-- PRESET_X -->` mark."""
    readme = ROOT / "README.md"
    text = readme.read_text()
    for preset, cell in cells.items():
        mark = f"<!-- PRESET_{preset.upper()} -->"
        text = re.sub(re.escape(mark) + r"[^|\n]*\|", lambda _: f"{mark} {cell} |", text)
    readme.write_text(text)


# ----------------------------------------------------------------------------------------------------


KEPT_MARKER = "<!-- Hand-written below: docs/make_report.py keeps everything after this line. -->"


def kept_sections(path: Path) -> str:
    """The hand-written tail of a generated page (measurements recorded by people, not by this script):
    everything from KEPT_MARKER on, so that regenerating the page does not drop it."""
    if not path.exists():
        return ""
    text = path.read_text()
    at = text.find(KEPT_MARKER)
    return "\n" + text[at:] if at >= 0 else ""


def main() -> None:
    started = time.time()
    load_before = load_average()
    print(f"{time.strftime('%Y-%m-%d %H:%M:%S UTC', time.gmtime())}; load average {load_before}; {os.cpu_count()} CPUs")
    if not ARGS.no_build:
        log("cargo build --release")
        subprocess.run(["cargo", "build", "--release", "--bin", "radray"], cwd=ROOT, check=True)
    IMAGES.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix="radray-report-"))
    if ARGS.presets_only:
        try:
            results = []
            for s in [Setting(q, quality=q) for q in ("preview", "default", "high")]:
                for mode in ("final", "radiosity"):
                    results.append(render_and_measure(s, mode, tmp, REFERENCES / "cornell_original" / "reference.exr"))
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
        cells = preset_cells(results)
        print(f"load average before {load_before}, after {load_average()}")
        print(table(["preset", "measured"], [[f"`{k}`", v] for k, v in cells.items()]))
        if ARGS.readme:
            update_readme(cells)
        log(f"measured the presets in {time.time() - started:.0f} s")
        return
    try:
        ttE, tte_text = time_to_error(tmp)
        view_text = second_view(tmp)
        pictures_text = pictures(tmp, ttE)
        scaling_text, _ = scaling(tmp)
        guard_text = memory_guard(tmp)
        bench_text = benches()
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    header = machine_header(load_before, started)
    cells = preset_cells(ttE)
    quick_note = "\n\n**Smoke run (`--quick`): fewer and cheaper settings; not the report.**" if ARGS.quick else ""

    accuracy = f"""# radray: accuracy

{header}{quick_note}

Regenerate with `python3 docs/make_report.py` (needs matplotlib). Metrics are `radray compare`'s, the same
as `references/compare.py`: relMSE = mean (x − ref)² / (ref² + 0.01), mean absolute relative error =
mean |x − ref| / (|ref| + 0.01), RMSE, over the three channels of every pixel, linear radiance.

## Time to error on cornell_original

`scenes/cornell_box.toml` against `references/cornell_original/reference.exr` (Mitsuba 3, 16384 spp),
256×256, box filter. Each radray row is one process run from the scene file to the EXR (parse, mesh,
form factors, solve, trace, write); a run under {REPEAT_BELOW_S:g} s is made twice and the faster kept. "final" is the two-pass image with per-pixel direct light
(`--direct pixel`: shadow rays to the emitter, so coarse elements only carry the indirect light);
"radiosity" is the pure radiosity output (`--mode radiosity`). Presets are `--quality NAME`; the other
rows write the values into a copy of the scene. The path tracer's figures are the published ones of
`references/README.md` (same machine type, 2 cores; whole process, with the render alone in the
pass-two column).

{tte_text}

![time to error]({rel(IMAGES / 'report_time_to_error.png')})

## Pictures

{pictures_text}
"""
    performance = f"""# radray: performance

{header}{quick_note}

Regenerate with `python3 docs/make_report.py` (needs matplotlib); `--benches` also runs the criterion
benches. Times are whole-process wall-clock seconds, with the process's CPU seconds (user + system)
beside them; peak memory is the process's peak resident set size (`ru_maxrss`).

## Presets on cornell_original

Whole-process figures of the final image (`--direct pixel`) from the time-to-error study in
[accuracy.md](accuracy.md); these are the figures of README.md's presets table.

{table(["preset", "measured"], [[f"`{k}`", v] for k, v in cells.items()])}

## A second view costs pass two alone

{view_text}

## Scaling of pass one

{scaling_text}

## The memory guard

{guard_text}

## Benchmarks

{bench_text}
"""
    (DOCS / "accuracy.md").write_text(accuracy + kept_sections(DOCS / "accuracy.md"))
    (DOCS / "performance.md").write_text(performance + kept_sections(DOCS / "performance.md"))
    if ARGS.readme:
        update_readme(cells)
    log(f"wrote docs/accuracy.md, docs/performance.md, docs/images/report_*.png in {time.time() - started:.0f} s")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="a fast smoke run with fewer, cheaper settings")
    parser.add_argument("--benches", action="store_true", help="also run the criterion benches briefly")
    parser.add_argument("--readme", action="store_true", help="write the preset figures into README.md")
    parser.add_argument("--no-build", action="store_true", help="use target/release/radray as it is")
    parser.add_argument(
        "--presets-only",
        action="store_true",
        help="measure only the three presets on cornell_original and print their cells (README.md with --readme); "
        "docs/accuracy.md and docs/performance.md are left as they are",
    )
    ARGS = parser.parse_args()
    main()
