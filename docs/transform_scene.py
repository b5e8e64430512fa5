#!/usr/bin/env python3
"""Writes a copy of a radray scene scaled by s and translated by t (x -> s*x + t): every [[mesh]] gets
`scale`/`translate` (its OBJ path made absolute), the camera's eye and look_at are moved the same way
(vfov unchanged), and the explicit lengths max_element_edge / min_element_size are scaled. Used for the
scale and placement sweep in docs/accuracy.md.

usage: transform_scene.py SCENE.toml OUT.toml s tx ty tz
"""
import os
import re
import sys

scene, out = sys.argv[1], sys.argv[2]
s, tx, ty, tz = (float(x) for x in sys.argv[3:7])
base = os.path.dirname(os.path.abspath(scene))
txt = open(scene).read()


def point(m):
    v = [float(x) for x in m.group(2).split(',')]
    v = [s * v[0] + tx, s * v[1] + ty, s * v[2] + tz]
    return f"{m.group(1)} = [{v[0]!r}, {v[1]!r}, {v[2]!r}]"


txt = re.sub(r'^(eye|look_at)\s*=\s*\[([^\]]*)\]', point, txt, flags=re.M)
txt = re.sub(r'^(max_element_edge|min_element_size)\s*=\s*([0-9.eE+-]+)',
             lambda m: f"{m.group(1)} = {float(m.group(2)) * s!r}", txt, flags=re.M)
txt = re.sub(r'^obj\s*=\s*"([^"]*)"',
             lambda m: f'obj = "{os.path.join(base, m.group(1))}"\nscale = {s!r}\ntranslate = [{tx!r}, {ty!r}, {tz!r}]',
             txt, flags=re.M)
open(out, 'w').write(txt)
