#!/usr/bin/env python3
"""How hierarchical pass one scales (issue 10: time no faster than n^1.2, memory about linear, on
procedural scenes from 16k to 1M input triangles).

For each size, `examples/procedural_scene.rs` writes a procedural room; `radray solve` solves it under
/usr/bin/time -v (CPU seconds and peak RSS; wall times are noisy on a shared machine) with a per-size
timeout. Least squares on log-log gives the exponents over the sizes that finished. The table and the
fit replace the text between the HIERARCHY-SCALING markers of docs/performance.md (or are appended).

usage: docs/scaling.py WORK_DIR [--sizes 16000,32000,...] [--timeout-s 600] [--radray target/release/radray]
       [--no-write]
"""

import argparse
import json
import math
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from timed_run import run_timed  # noqa: E402

REPO = Path(__file__).resolve().parent.parent
BEGIN, END = "<!-- HIERARCHY-SCALING BEGIN -->", "<!-- HIERARCHY-SCALING END -->"


def fit(xs, ys):
    """Exponent and prefactor of y = a·x^k by least squares on logs; None with fewer than 2 points."""
    pts = [(math.log(x), math.log(y)) for x, y in zip(xs, ys) if x > 0 and y > 0 and math.isfinite(y)]
    if len(pts) < 2:
        return None
    mx = sum(p[0] for p in pts) / len(pts)
    my = sum(p[1] for p in pts) / len(pts)
    sxx = sum((p[0] - mx) ** 2 for p in pts)
    k = sum((p[0] - mx) * (p[1] - my) for p in pts) / sxx
    return k, math.exp(my - k * mx)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("work_dir", type=Path)
    ap.add_argument("--sizes", default="16000,32000,64000,128000,256000,512000,1000000")
    ap.add_argument("--timeout-s", type=float, default=600)
    ap.add_argument("--radray", default=str(REPO / "target/release/radray"))
    ap.add_argument("--no-write", action="store_true")
    args = ap.parse_args()
    subprocess.run(["cargo", "build", "--release", "--example", "procedural_scene"], cwd=REPO, check=True)
    example = REPO / "target/release/examples/procedural_scene"
    rows = []
    for n in [int(s) for s in args.sizes.split(",")]:
        d = args.work_dir / f"procedural_{n}"
        subprocess.run([str(example), str(n), str(d)], check=True, stdout=subprocess.DEVNULL)
        stats = d / "solve.json"
        r = run_timed(
            [args.radray, "solve", str(d / "scene.toml"), "-o", str(d / "scene.radsol"), "--stats", str(stats)],
            args.timeout_s)
        code, wall = r["exit"], r["wall_s"]
        cpu = (r["user_s"] or math.nan) + (r["system_s"] or 0.0)
        rss = r["peak_rss_bytes"] or math.nan
        links = elements = ""
        if code == 0 and stats.is_file():
            h = json.loads(stats.read_text()).get("hierarchy", {})
            links, elements = h.get("links", ""), h.get("elements", "")
        rows.append((n, code, wall, cpu, rss, elements, links))
        print(f"{n:>8} exit {code} wall {wall:.1f} s cpu {cpu:.1f} s rss {rss / 1e9:.2f} GB "
              f"elements {elements} links {links}", flush=True)
        if code != 0:
            break  # larger sizes would not finish either
    done = [r for r in rows if r[1] == 0]
    t_fit = fit([r[0] for r in done], [r[3] for r in done])
    m_fit = fit([r[0] for r in done], [r[4] for r in done])
    lines = [BEGIN, "", "### Hierarchical pass one: scaling on procedural rooms (`docs/scaling.py`)", "",
             f"Measured {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, `radray solve` with "
             f"`method = \"hierarchical\"`, default preset, timeout {args.timeout_s:.0f} s per size; CPU "
             "seconds and peak RSS from `/usr/bin/time -v`.", "",
             "| input triangles | exit | wall s | CPU s | peak RSS GB | leaf elements | links |",
             "|---|---|---|---|---|---|---|"]
    for n, code, wall, cpu, rss, elements, links in rows:
        lines.append(f"| {n} | {code} | {wall:.1f} | {cpu:.1f} | {rss / 1e9:.3f} | {elements} | {links} |")
    lines.append("")
    if t_fit and m_fit:
        lines.append(f"Fit over the sizes that finished: CPU time ∝ n^{t_fit[0]:.2f} (target ≤ 1.2), "
                     f"peak RSS ∝ n^{m_fit[0]:.2f} (target about 1).")
    else:
        lines.append("Fewer than two sizes finished, so there is no fit: the target (time ≤ n^1.2, memory "
                     "about linear) is not shown to be met.")
    lines += ["", END]
    text = "\n".join(lines)
    print(text)
    if not args.no_write:
        perf = REPO / "docs/performance.md"
        doc = perf.read_text()
        if BEGIN in doc and END in doc:
            doc = doc[:doc.index(BEGIN)] + text + doc[doc.index(END) + len(END):]
        else:
            doc = doc.rstrip("\n") + "\n\n" + text + "\n"
        perf.write_text(doc)


if __name__ == "__main__":
    sys.exit(main())
