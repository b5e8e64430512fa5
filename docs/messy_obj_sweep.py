#!/usr/bin/env python3
"""OBJ/MTL robustness sweep (docs/input.md): writes ~100 tiny OBJ/MTL cases as exporters write them
(a red floor quad lit by a lamp quad, then one oddity each) under target/messy_obj_sweep/, runs
`radray info` and `radray render` (32x24, 1 spp, preview) on each as a user would, and prints the exit
codes, a panic flag, the first stderr lines and the mean sRGB colour of the lower middle of the image
(the floor). Needs Pillow and `cargo build --release`. Usage: python3 docs/messy_obj_sweep.py [NAME...]
(only the cases whose name contains one of the NAMEs)."""
import os, subprocess, sys, shutil
from PIL import Image
REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), '..'))
RADRAY = os.path.join(REPO, 'target', 'release', 'radray')
BASE_V = "v 0 0 0\nv 0 0 1\nv 1 0 1\nv 1 0 0\nv 0.3 1 0.3\nv 0.7 1 0.3\nv 0.7 1 0.7\nv 0.3 1 0.7\nvt 0 0\nvt 0 1\nvt 1 1\nvt 1 0\n"
BASE_F = "usemtl floor\nf 1/1 2/2 3/3 4/4\nusemtl lamp\nf 5 6 7 8\n"
BASE_OBJ = "mtllib scene.mtl\n" + BASE_V + BASE_F
BASE_MTL = "newmtl floor\nKd 0.8 0.2 0.2\nnewmtl lamp\nKd 0 0 0\nKe 5 5 5\n"
TOML = """[camera]
eye = [0.5, 0.9, -0.8]
look_at = [0.5, 0.0, 0.5]
up = [0.0, 1.0, 0.0]
vfov_deg = 50.0
[image]
width = 32
height = 24
samples_per_pixel = 1

[[mesh]]
obj = "scene.obj"
"""

def png(path, mode, colour, size=(4, 4), fmt=None):
    im = Image.new(mode, size, colour)
    im.save(path, format=fmt)

CASES = []
def case(name, obj=BASE_OBJ, mtl=BASE_MTL, files=None, obj_name="scene.obj", mtl_name="scene.mtl", toml=""):
    CASES.append((name, obj, mtl, files or {}, obj_name, mtl_name, toml))

crlf = lambda s: s.replace("\n", "\r\n")
case("baseline")
case("crlf obj+mtl", crlf(BASE_OBJ), crlf(BASE_MTL))
case("bom obj", "\ufeff" + BASE_OBJ)
case("bom mtl", BASE_OBJ, "\ufeff" + BASE_MTL)
case("bom obj starting with v", "\ufeffv 9 9 9\n" + BASE_OBJ.replace("f 1/1 2/2 3/3 4/4", "f 2/1 3/2 4/3 5/4").replace("f 5 6 7 8", "f 6 7 8 9"))
case("latin1 comment obj", b"# caf\xe9 export\n" + BASE_OBJ.encode())
case("latin1 material name", BASE_OBJ.replace("floor", "fl\u00f6or").encode('latin-1'), BASE_MTL.replace("floor", "fl\u00f6or").encode('latin-1'))
case("tabs", BASE_OBJ.replace(" ", "\t"), BASE_MTL.replace(" ", "\t"))
case("backslash continuation", BASE_OBJ.replace("f 1/1 2/2 3/3 4/4", "f 1/1 2/2 \\\n3/3 4/4"))
case("blank usemtl", BASE_OBJ.replace("usemtl lamp\n", "usemtl lamp\nusemtl\n").replace("f 5 6 7 8", "f 5 6 7 8"), )
case("blank usemtl before floor", BASE_OBJ.replace("usemtl floor\n", "usemtl \n"))
case("undefined usemtl", BASE_OBJ.replace("usemtl floor", "usemtl nosuch"))
case("missing mtllib file", BASE_OBJ.replace("mtllib scene.mtl", "mtllib gone.mtl"))
case("two mtllib lines", "mtllib a.mtl\nmtllib b.mtl\n" + BASE_V + BASE_F, None,
     {"a.mtl": "newmtl floor\nKd 0.8 0.2 0.2\n", "b.mtl": "newmtl lamp\nKe 5 5 5\n"})
case("two libs on one mtllib line", "mtllib a.mtl b.mtl\n" + BASE_V + BASE_F, None,
     {"a.mtl": "newmtl floor\nKd 0.8 0.2 0.2\n", "b.mtl": "newmtl lamp\nKe 5 5 5\n"})
case("mtllib with tab", BASE_OBJ.replace("mtllib scene.mtl", "mtllib\tscene.mtl"))
case("mtllib name with spaces", BASE_OBJ.replace("mtllib scene.mtl", "mtllib my scene.mtl"), None, {"my scene.mtl": BASE_MTL})
# textures
TEX_MTL = lambda stmt: "newmtl floor\nKd 1 1 1\n" + stmt + "\nnewmtl lamp\nKd 0 0 0\nKe 5 5 5\n"
G = ("png", "RGB", (40, 200, 40))
case("tex plain", mtl=TEX_MTL("map_Kd tex.png"), files={"tex.png": G})
case("tex windows backslash", mtl=TEX_MTL("map_Kd textures\\tex.png"), files={"textures/tex.png": G})
case("tex absolute windows path", mtl=TEX_MTL("map_Kd C:\\Users\\bob\\Desktop\\proj\\tex.png"), files={"tex.png": G})
case("tex absolute unix path", mtl=TEX_MTL("map_Kd /home/bob/proj/tex.png"), files={"tex.png": G})
case("tex absolute win path, file in textures/", mtl=TEX_MTL("map_Kd C:\\proj\\textures\\tex.png"), files={"textures/tex.png": G})
case("tex spaces", mtl=TEX_MTL("map_Kd my tex.png"), files={"my tex.png": G})
case("tex options", mtl=TEX_MTL("map_Kd -s 1 1 1 -o 0 0 0 -bm 0.5 tex.png"), files={"tex.png": G})
case("tex -clamp on", mtl=TEX_MTL("map_Kd -clamp on tex.png"), files={"tex.png": G})
case("tex upper-case ext", mtl=TEX_MTL("map_Kd TEX.PNG"), files={"TEX.PNG": G})
case("tex case mismatch", mtl=TEX_MTL("map_Kd tex.png"), files={"Tex.PNG": G})
case("tex missing", mtl=TEX_MTL("map_Kd gone.png"))
case("tex undecodable", mtl=TEX_MTL("map_Kd tex.png"), files={"tex.png": b"not a png at all"})
case("tex truncated png", mtl=TEX_MTL("map_Kd tex.png"), files={"tex.png": "TRUNC"})
case("tex grey png", mtl=TEX_MTL("map_Kd tex.png"), files={"tex.png": ("png", "L", 128)})
case("tex 16-bit png", mtl=TEX_MTL("map_Kd tex.png"), files={"tex.png": ("png", "I;16", 30000)})
case("tex rgba png", mtl=TEX_MTL("map_Kd tex.png"), files={"tex.png": ("png", "RGBA", (40, 200, 40, 255))})
case("tex tga", mtl=TEX_MTL("map_Kd tex.tga"), files={"tex.tga": ("tga", "RGB", (40, 200, 40))})
case("tex jpeg", mtl=TEX_MTL("map_Kd tex.jpg"), files={"tex.jpg": ("jpeg", "RGB", (40, 200, 40))})
case("tex directory", mtl=TEX_MTL("map_Kd texdir"), files={"texdir/x": "x"})
# materials
M = lambda body: "newmtl floor\n" + body + "\nnewmtl lamp\nKd 0 0 0\nKe 5 5 5\n"
case("Tr 0", mtl=M("Kd 0.8 0.2 0.2\nTr 0"))
case("Tr 1 alone (MeshLab/3ds Max write alpha)", mtl=M("Kd 0.8 0.2 0.2\nTr 1.000000\nillum 2"))
case("Tr 0.5", mtl=M("Kd 0.8 0.2 0.2\nTr 0.5"))
case("d 0 illum 2", mtl=M("Kd 0.8 0.2 0.2\nd 0\nillum 2"))
case("d 1 Tr 0 (3ds Max)", mtl=M("Kd 0.8 0.2 0.2\nd 1.0\nTr 0.0\nillum 2"))
case("Blender 2.8+ default", mtl=M("Ns 225.000000\nKa 1.000000 1.000000 1.000000\nKd 0.800000 0.200000 0.200000\nKs 0.500000 0.500000 0.500000\nKe 0.000000 0.000000 0.000000\nNi 1.450000\nd 1.000000\nillum 2"))
for il in range(0, 11):
    case(f"illum {il}", mtl=M(f"Kd 0.5 0.1 0.1\nKs 0.3 0.3 0.3\nillum {il}"))
case("Ka nonzero", mtl=M("Kd 0.8 0.2 0.2\nKa 0.2 0.2 0.2"))
case("Ns only", mtl=M("Kd 0.8 0.2 0.2\nNs 96"))
case("Ni without transparency", mtl=M("Kd 0.8 0.2 0.2\nNi 1.45"))
case("Kd > 1", mtl=M("Kd 1.5 0.2 0.2"))
case("Kd negative", mtl=M("Kd -0.1 0.2 0.2"))
case("Kd nan", mtl=M("Kd nan 0.2 0.2"))
case("Kd 2 numbers", mtl=M("Kd 0.2 0.2"))
case("Ke with map_Ke", mtl="newmtl floor\nKd 0.8 0.2 0.2\nnewmtl lamp\nKd 0 0 0\nKe 5 5 5\nmap_Ke tex.png\n", files={"tex.png": G})
case("map_Ke without Ke", mtl="newmtl floor\nKd 0.8 0.2 0.2\nnewmtl lamp\nKd 0 0 0\nmap_Ke tex.png\n", files={"tex.png": G})
UP_LAMP = BASE_OBJ.replace("f 5 6 7 8", "f 8 7 6 5")
case("Ke lamp facing away, one-sided", UP_LAMP)
case("Ke lamp facing away, two_sided = true", UP_LAMP, toml="two_sided = true\n")
case("PBR extensions", mtl=M("Kd 0.8 0.2 0.2\nPr 0.5\nPm 0.1\nPs 0.2\nPc 0.1\nPcr 0.1\naniso 0\nanisor 0\nmap_Pr r.png\nnorm n.png\nmap_Bump -bm 1 b.png\nbump b.png\nmap_Ks s.png\nrefl -type sphere r.png"))
case("unknown statement before newmtl", mtl="Kd 1 1 1\n" + BASE_MTL)
case("newmtl without name", mtl="newmtl\nKd 1 1 1\n" + BASE_MTL)
case("empty mtl", mtl="")
case("mtl is a directory", BASE_OBJ.replace("mtllib scene.mtl", "mtllib sub"), files={"sub/x": "x"})
# geometry
GV = "mtllib scene.mtl\nv 0.3 1 0.3\nv 0.7 1 0.3\nv 0.7 1 0.7\nv 0.3 1 0.7\nusemtl lamp\nf 1 2 3 4\nusemtl floor\n"
case("pentagon", GV + "v 0 0 0\nv 0 0 1\nv 0.5 0 1.3\nv 1 0 1\nv 1 0 0\nf 5 6 7 8 9\n")
# L-shaped hexagon in xz at y=0, CCW seen from +y, starting at the reflex-adjacent vertex
case("concave L 6-gon (fan from a bad vertex)", GV + "v 1 0 0.5\nv 0.5 0 0.5\nv 0.5 0 1\nv 0 0 1\nv 0 0 0\nv 1 0 0\nf 5 10 9 8 7 6\n")
case("concave dart quad", GV + "v 0 0 0\nv 0.5 0 0.3\nv 1 0 0\nv 0.5 0 1\nf 6 7 8 5\n".replace("f 6 7 8 5", "f 5 8 7 6"))
case("non-planar quad", GV + "v 0 0 0\nv 0 0.2 1\nv 1 0 1\nv 1 0.2 0\nf 5 6 7 8\n")
case("degenerate faces", BASE_OBJ + "f 1 1 1\nf 1 2 1\nv 2 0 0\nf 1 4 9\n")
case("many degenerate faces", BASE_OBJ + "f 1 1 2\n" * 5000)
case("duplicate vertex in face", GV + "v 0 0 0\nv 0 0 1\nv 1 0 1\nv 1 0 0\nf 5 6 6 7 8\n")
case("negative indices", GV + "v 0 0 0\nv 0 0 1\nv 1 0 1\nv 1 0 0\nf -4 -3 -2 -1\n")
case("index out of range", BASE_OBJ + "f 1 2 99\n")
case("index 0", BASE_OBJ + "f 0 1 2\n")
case("vt with 3 components", BASE_OBJ.replace("vt 0 0\n", "vt 0 0 0\n"))
case("vn zero length", GV + "v 0 0 0\nv 0 0 1\nv 1 0 1\nv 1 0 0\nvn 0 0 0\nf 5//1 6//1 7//1 8//1\n")
case("vn nan", GV + "v 0 0 0\nv 0 0 1\nv 1 0 1\nv 1 0 0\nvn nan 1 0\nf 5//1 6//1 7//1 8//1\n")
case("v nan", BASE_OBJ + "v nan 0 0\n")
case("v inf", BASE_OBJ + "v 1 inf 0\n")
case("l and p elements", BASE_OBJ + "l 1 2 3\np 1\nl 1 99\n")
case("s off / s 1", BASE_OBJ.replace("usemtl floor", "s off\nusemtl floor").replace("usemtl lamp", "s 1\nusemtl lamp"))
case("o/g without names", BASE_OBJ.replace("usemtl floor", "o\ng\nusemtl floor"))
case("empty obj", "")
case("only comments obj", "# nothing\n")
case("obj with vertices but no faces", "v 0 0 0\nv 1 0 0\n")
case("huge coordinate 1e30", BASE_OBJ + "v 1e30 0 0\nv 1e30 0 1\nv 1e30 1 0\nusemtl floor\nf 9 10 11\n")
case("huge coordinate 1e38", BASE_OBJ + "v 3e38 0 0\nv 3e38 0 1\nv 3e38 1 0\nusemtl floor\nf 9 10 11\n")
case("v with w", BASE_OBJ.replace("v 0 0 0\n", "v 0 0 0 1\n"))
case("v with colour", BASE_OBJ.replace("v 0 0 0\n", "v 0 0 0 1 0 0\n"))
case("v with 5 numbers", BASE_OBJ.replace("v 0 0 0\n", "v 0 0 0 1 0\n"))
case("face with 2 vertices", BASE_OBJ + "f 1 2\n")
case("obj is binary junk", b"\x00\x01\x02\xff\xfe" * 100)
case("curv/cstype statements", BASE_OBJ + "cstype bspline\ndeg 3\ncurv 0 1 1 2 3 4\nend\n")

def write(d, name, content):
    p = os.path.join(d, name)
    os.makedirs(os.path.dirname(p), exist_ok=True)
    if isinstance(content, tuple):
        fmt, mode, colour = content
        png(p, mode, colour, fmt={"png": "PNG", "tga": "TGA", "jpeg": "JPEG"}[fmt])
    elif content == "TRUNC":
        png(p, "RGB", (40, 200, 40), size=(64, 64)); data = open(p, 'rb').read(); open(p, 'wb').write(data[: len(data) // 2])
    else:
        open(p, 'wb').write(content if isinstance(content, bytes) else content.encode())

def floor_mean(png_path):
    im = Image.open(png_path).convert("RGB")
    w, h = im.size
    box = im.crop((w // 4, h * 2 // 3, 3 * w // 4, h - 1))
    px = [box.getpixel((x, y)) for y in range(box.size[1]) for x in range(box.size[0])]
    return tuple(round(sum(p[i] for p in px) / len(px)) for i in range(3))

only = sys.argv[1:] 
out_dir = os.path.join(REPO, 'target', 'messy_obj_sweep')
for name, obj, mtl, files, obj_name, mtl_name, toml in CASES:
    if only and not any(o in name for o in only):
        continue
    d = os.path.join(out_dir, name.replace(' ', '_').replace('/', '_'))
    shutil.rmtree(d, ignore_errors=True); os.makedirs(d)
    write(d, "scene.toml", TOML + toml)
    write(d, obj_name, obj)
    if mtl is not None:
        write(d, mtl_name, mtl)
    for f, c in files.items():
        write(d, f, c)
    info = subprocess.run([RADRAY, 'info', os.path.join(d, 'scene.toml')], capture_output=True, text=True, errors='replace', timeout=120)
    r = subprocess.run([RADRAY, 'render', os.path.join(d, 'scene.toml'), '-o', os.path.join(d, 'out.png'), '--quality', 'preview'],
                       capture_output=True, text=True, errors='replace', timeout=300)
    err = [l for l in r.stderr.splitlines() if l.strip() and 'Solving' not in l and '%' not in l]
    mean = floor_mean(os.path.join(d, 'out.png')) if r.returncode == 0 and os.path.exists(os.path.join(d, 'out.png')) else None
    panic = 'panicked' in r.stderr or 'panicked' in info.stderr
    print(f"## {name}: info rc={info.returncode} render rc={r.returncode}{' PANIC' if panic else ''} floor={mean}")
    for l in err[:6]:
        print("   " + l[:300])
    if len(err) > 6:
        print(f"   ... {len(err) - 6} more stderr lines")
    sys.stdout.flush()
