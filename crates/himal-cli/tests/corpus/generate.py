#!/usr/bin/env python3
"""Writes the malformed-input corpus (issue #16) next to this script.

    python3 crates/himal-cli/tests/corpus/generate.py

    python3 crates/himal-cli/tests/corpus/generate.py DIR

Output: DIR/cases/<class>/<file> (default: next to this script; the test
writes them to a temporary folder, about 10 MB) and cases.tsv (committed
here), one case per line:

    class <TAB> name <TAB> expect <TAB> needle <TAB> arg <TAB> arg ...

expect is `error` (the run must exit non-zero with `needle` in stderr) or
`ok` (a damaged input that must be detected, warned about and worked
around: exit 0). In args, {corpus} is this folder, {out} a fresh folder per
case. tests/corpus.rs runs every case with the rule: no panic, no signal,
no hang, and the message names the input. Deterministic: same bytes on
every run (no randomness without a fixed seed).
"""

import base64
import json
import os
import random
import shutil
import struct
import sys
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
# The files go to the folder given (the test's temporary folder), the
# manifest both there and next to this script (where it is committed).
OUT = os.path.abspath(sys.argv[1]) if len(sys.argv) > 1 else HERE
CASES = os.path.join(OUT, "cases")
rng = random.Random(16)
rows = []
shutil.rmtree(CASES, ignore_errors=True)


def write(cls, name, data):
    path = os.path.join(CASES, cls, name)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode())
    return "{corpus}/cases/%s/%s" % (cls, name)


def case(cls, name, needle, args, expect="error"):
    assert "\t" not in "".join(args) and "\n" not in "".join(args)
    rows.append("\t".join([cls, name, expect, needle] + list(args)))


RENDER = ["render", "--size", "8x8", "--out", "{out}/x.png"]

# ---------------------------------------------------------------- scene files

BASE = """[sun]
time = "10:30"
latitude = 45.0
day_of_year = 172
turbidity = 3.0

[[material]]
name = "stone"
albedo = [0.5, 0.5, 0.5]
glossiness = 0.4
reflectance = 0.04
metallic = 0.0
anisotropy = 0.0
ao = 1.0

[[object]]
name = "ground"
primitive = "plane"
material = "stone"
size = [20.0, 20.0]
segments = 2

[[object]]
name = "ball"
primitive = "sphere"
material = "stone"
radius = 1.0
segments = 8
position = [0.0, 1.0, 0.0]

[[camera]]
name = "front"
position = [0.0, 2.0, 6.0]
target = [0.0, 1.0, 0.0]
fov_y = 50.0
near = 0.1
"""


def scene_case(name, text, needle=None, extra=()):
    path = write("scene", name + ".toml", text)
    case("scene", name, needle or (name + ".toml"), RENDER + ["--scene", path] + list(extra))


def replace_line(text, key, value, section_marker):
    """Replaces `key = ...` in the first block that starts at section_marker."""
    start = text.index(section_marker)
    i = text.index("\n" + key + " =", start) + 1
    j = text.index("\n", i)
    return text[:i] + "%s = %s" % (key, value) + text[j:]


# (block marker, key, bad values)
FIELDS = [
    ("[sun]", "time", ['"25:00"', '"10:61"', '"noon"', "24.5", "-1.0", "nan"]),
    ("[sun]", "latitude", ["91.0", "-90.5", "nan", "inf"]),
    ("[sun]", "day_of_year", ["0", "367", "-5", "9223372036854775807"]),
    ("[sun]", "turbidity", ["0.5", "11.0", "nan", "-inf"]),
    ("[[material]]", "albedo", ["[nan, 0.5, 0.5]", "[2.0, 0.5, 0.5]", "[-0.1, 0.5, 0.5]",
                                 "[0.5, 0.5]", "[0.5, 0.5, 0.5, 0.5]", '"grey"', "[inf, 0.0, 0.0]"]),
    ("[[material]]", "glossiness", ["1.5", "-0.1", "nan", "inf"]),
    ("[[material]]", "reflectance", ["2.0", "-1.0", "nan"]),
    ("[[material]]", "metallic", ["1.01", "-1.0", "nan"]),
    ("[[material]]", "anisotropy", ["2.0", "-2.0", "nan"]),
    ("[[material]]", "ao", ["1.5", "-0.5", "nan"]),
    ('name = "ground"', "size", ["[-1.0, 20.0]", "[0.0, 20.0]", "[nan, 20.0]", "[inf, 20.0]",
                                  "[20.0]", "[20.0, 20.0, 20.0]", "[1e30, 1e30]"]),
    ('name = "ground"', "segments", ["0", "-1", "4097", "100000", "1.5", '"many"']),
    ('name = "ground"', "material", ['"marble"', '""', "3"]),
    ('name = "ground"', "primitive", ['"teapot"', '""', "7"]),
    ('name = "ball"', "radius", ["0.0", "-1.0", "nan", "inf", "1e30", "1e-30"]),
    ('name = "ball"', "segments", ["2", "0", "-8", "100000"]),
    ('name = "ball"', "position", ["[nan, 0.0, 0.0]", "[0.0, inf, 0.0]", "[0.0, 0.0]",
                                    "[1e30, 0.0, 0.0]", '"here"']),
    ("[[camera]]", "position", ["[nan, 2.0, 6.0]", "[0.0, -inf, 6.0]", "[0.0, 1.0, 0.0]"]),
    ("[[camera]]", "target", ["[0.0, nan, 0.0]", "[0.0, 2.0, 6.0]", "[1e30, 0.0, 0.0]"]),
    ("[[camera]]", "fov_y", ["0.0", "180.0", "-5.0", "nan", "1e9"]),
    ("[[camera]]", "near", ["0.0", "-0.1", "nan", "inf", "1e9"]),
]

for marker, key, values in FIELDS:
    tag = marker.strip("[]").split('"')[-2] if '"' in marker else marker.strip("[]")
    for k, v in enumerate(values):
        scene_case("%s_%s_%d" % (tag, key, k), replace_line(BASE, key, v, marker))


def ball_extra(name, lines):
    """The base scene with extra `key = value` lines on the ball."""
    text = BASE.replace('position = [0.0, 1.0, 0.0]\n', 'position = [0.0, 1.0, 0.0]\n' + lines + "\n")
    scene_case(name, text)


for k, v in enumerate(["[nan, 0.0, 0.0]", "[0.0, inf, 0.0]", "[1.0, 2.0]"]):
    ball_extra("ball_rotation_%d" % k, "rotation = " + v)
for k, v in enumerate(["0.0", "-1.0", "nan", "[1.0, 0.0, 1.0]", "[1.0, nan, 1.0]", "inf", "1e30"]):
    ball_extra("ball_scale_%d" % k, "scale = " + v)
for k, v in enumerate(["{ count = 0, step = [1.0, 0.0, 0.0] }", "{ count = -3, step = [1.0, 0.0, 0.0] }",
                       "{ count = 10001, step = [1.0, 0.0, 0.0] }", "{ count = 3, step = [nan, 0.0, 0.0] }",
                       "{ count = 3 }", "{ count = 3, step = [1.0, 0.0, 0.0], extra = 1 }"]):
    ball_extra("ball_repeat_%d" % k, "repeat = " + v)
for k, v in enumerate(["{ radius = nan, period = 4.0 }", "{ radius = -1.0, period = 4.0 }",
                       "{ radius = 2.0, period = 0.0 }", "{ radius = 2.0, period = nan }",
                       "{ radius = 2.0, period = 4.0, phase = inf }", "{ radius = 2.0 }"]):
    ball_extra("ball_orbit_%d" % k, "orbit = " + v)
ball_extra("ball_rest_on_missing", 'rest_on = "table"')
ball_extra("ball_rest_on_self", 'rest_on = "ball"')
ball_extra("ball_snap_and_rest", 'rest_on = "ground"\nsnap_to_ground = true')
ball_extra("ball_wrong_key", "height = 3.0")
ball_extra("ball_unknown_key", "colour = 3")
ball_extra("ball_duplicate_key", "radius = 2.0")

# Structure.
scene_case("empty", "")
scene_case("comments_only", "# nothing here\n")
scene_case("no_camera", BASE[: BASE.index("[[camera]]")])
scene_case("unknown_table", BASE + "\n[weather]\nrain = 1\n")
scene_case("unknown_top_key", "gravity = 9.81\n" + BASE)
scene_case("duplicate_material", BASE.replace("[[object]]", '[[material]]\nname = "stone"\nalbedo = [0.1, 0.1, 0.1]\n\n[[object]]', 1))
scene_case("duplicate_object", BASE + '\n[[object]]\nname = "ball"\nprimitive = "box"\nmaterial = "stone"\nsize = [1.0, 1.0, 1.0]\n')
scene_case("duplicate_camera", BASE + '\n[[camera]]\nname = "front"\nposition = [1.0, 1.0, 1.0]\ntarget = [0.0, 0.0, 0.0]\n')
scene_case("camera_target_and_forward", BASE.replace("fov_y = 50.0", "forward = [0.0, 0.0, -1.0]\nfov_y = 50.0"))
scene_case("camera_up_parallel", BASE.replace("fov_y = 50.0", "up = [0.0, -1.0, -6.0]\nfov_y = 50.0"))
scene_case("camera_up_zero", BASE.replace("fov_y = 50.0", "up = [0.0, 0.0, 0.0]\nfov_y = 50.0"))
scene_case("object_no_primitive", BASE.replace('primitive = "sphere"\n', ""))
scene_case("object_no_name", BASE.replace('name = "ball"\n', ""))
scene_case("material_no_albedo", BASE.replace("albedo = [0.5, 0.5, 0.5]\n", ""))
scene_case("material_both_albedos", BASE.replace("albedo = [0.5, 0.5, 0.5]\n", "albedo = [0.5, 0.5, 0.5]\nalbedo_linear = [0.2, 0.2, 0.2]\n"))
scene_case("syntax_unclosed_table", BASE.replace("[[camera]]", "[[camera]"))
scene_case("syntax_unclosed_string", BASE.replace('"front"', '"front'))
scene_case("syntax_bare_value", BASE + "\nthis is not toml\n")
scene_case("invalid_utf8", BASE.encode().replace(b"stone", b"st\xff\xfeone", 1).decode("latin-1"))
for k, cut in enumerate([40, 130, 300, 480]):
    text = BASE[:cut]
    # Only cuts that leave broken TOML or a scene that cannot stand.
    scene_case("truncated_%d" % k, text)
scene_case("deep_array", "x = " + "[" * 100000 + "]" * 100000 + "\n" + BASE)
scene_case("deep_inline_table", "x = " + "{a = " * 20000 + "1" + "}" * 20000 + "\n" + BASE)
scene_case("long_line", "# " + "x" * 2_000_000 + "\n" + BASE.replace("time", "tiem"))
scene_case("nul_bytes", BASE.replace("[[camera]]", "\0\0\0[[camera]]"))
garbage = bytes(rng.randrange(256) for _ in range(4096))
path = write("scene", "garbage.toml", garbage)
case("scene", "garbage", "garbage.toml", RENDER + ["--scene", path])
case("scene", "missing_file", "no_such_scene.toml", RENDER + ["--scene", "{corpus}/cases/scene/no_such_scene.toml"])
case("scene", "directory", "cases/scene", RENDER + ["--scene", "{corpus}/cases/scene"])

# Lights, probes, environment, gltf tables.
LIGHT = '\n[[light]]\nname = "lamp"\nkind = "spot"\nposition = [0.0, 3.0, 0.0]\nintensity = 100.0\nrange = 10.0\ndirection = [0.0, -1.0, 0.0]\nouter_angle = 40.0\ninner_angle = 20.0\n'
for k, (key, v) in enumerate([("kind", '"laser"'), ("intensity", "-1.0"), ("intensity", "nan"),
                              ("range", "0.0"), ("range", "inf"), ("direction", "[0.0, 0.0, 0.0]"),
                              ("direction", "[nan, 1.0, 0.0]"), ("outer_angle", "95.0"),
                              ("inner_angle", "50.0"), ("position", "[nan, 0.0, 0.0]")]):
    scene_case("light_%s_%d" % (key, k), replace_line(BASE + LIGHT, key, v, "[[light]]"))
scene_case("light_color_nan", (BASE + LIGHT).replace("range = 10.0", "range = 10.0\ncolor = [nan, 1.0, 1.0]"))
scene_case("light_color_negative", (BASE + LIGHT).replace("range = 10.0", "range = 10.0\ncolor = [-1.0, 1.0, 1.0]"))
scene_case("light_duplicate", BASE + LIGHT + LIGHT)
scene_case("probe_nan", BASE + "\n[[probe]]\nposition = [nan, 1.0, 0.0]\n")
ENV = '\n[environment]\nfile = "sky.hdr"\nintensity = 1.0\nrotation = 0.0\n'
scene_case("environment_missing_file", BASE + ENV, "sky.hdr")
write("scene", "sky.hdr", b"")
for k, (key, v) in enumerate([("intensity", "-1.0"), ("intensity", "nan"), ("rotation", "1000.0"),
                              ("rotation", "inf")]):
    scene_case("environment_%s_%d" % (key, k), replace_line(BASE + ENV, key, v, "[environment]"))
GLTF = '\n[[gltf]]\nfile = "model.gltf"\ntranslation = [0.0, 0.0, 0.0]\n'
scene_case("gltf_missing_file", BASE + GLTF, "model.gltf")
for k, (key, v) in enumerate([("translation", "[nan, 0.0, 0.0]"), ("translation", "[0.0, inf, 0.0]")]):
    scene_case("gltf_%s_%d" % (key, k), replace_line(BASE + GLTF, key, v, "[[gltf]]"))
scene_case("gltf_rotation_zero_quat", (BASE + GLTF).replace("translation", "rotation = [0.0, 0.0, 0.0, 0.0]\ntranslation"))
scene_case("gltf_rotation_nan", (BASE + GLTF).replace("translation", "rotation = nan\ntranslation"))
scene_case("gltf_scale_zero", (BASE + GLTF).replace("translation", "scale = 0.0\ntranslation"))
scene_case("gltf_rest_on_missing", (BASE + GLTF).replace("translation", 'rest_on = "table"\ntranslation'))

# Height fields and vegetation.
HF = '\n[[object]]\nname = "hills"\nprimitive = "heightfield"\nmaterial = "stone"\nsize = [100.0, 100.0]\nresolution = 9\nnoise = { seed = 1, octaves = 3, frequency = 0.02, amplitude = 5.0 }\n'
for k, v in enumerate(["1", "0", "-4", "4098", "1000000"]):
    scene_case("heightfield_resolution_%d" % k, replace_line(BASE + HF, "resolution", v, 'name = "hills"'))
for k, v in enumerate(["{ octaves = 0 }", "{ octaves = 17 }", "{ frequency = 0.0 }", "{ frequency = nan }",
                       "{ amplitude = nan }", "{ amplitude = inf }", "{ lacunarity = 0.5 }",
                       "{ gain = 2.0 }", "{ warp = nan }", "{ erosion = nan }", "{ erosion = -1.0 }",
                       "{ flat_radius = nan }", "{ valley_radius = -5.0 }", "{ floor_amplitude = inf }",
                       "{ seed = -1 }", "{ seed = 1, unknown = 2 }"]):
    scene_case("heightfield_noise_%d" % k, replace_line(BASE + HF, "noise", v, 'name = "hills"'))
scene_case("heightfield_no_source", (BASE + HF).replace("noise = { seed = 1, octaves = 3, frequency = 0.02, amplitude = 5.0 }\n", ""))
scene_case("heightfield_no_resolution", (BASE + HF).replace("resolution = 9\n", ""))
for k, v in enumerate(['[{ material = "stone", min_slope = 100.0 }]', '[{ material = "stone", blend = nan }]',
                       '[{ material = "marble" }]', '[{ material = "stone", min_height = nan }]',
                       '[{ material = "stone", max_slope = -1.0 }]', '[{ material = "stone", jitter = inf }]']):
    scene_case("heightfield_layers_%d" % k, (BASE + HF).replace("resolution = 9", "resolution = 9\nlayers = " + v))
GRASS = '\n[[object]]\nname = "lawn"\nprimitive = "grass"\nmaterial = "stone"\nsize = [4.0, 4.0]\ndensity = 10.0\n'
for k, v in enumerate(["density = 0.0", "density = nan", "density = 1e12", "width = nan", "width = -1.0",
                       "cards = 0", "cards = 5", "sway = 2.0", "seed = -1", "height = inf"]):
    key = v.split(" ")[0]
    text = BASE + GRASS
    text = replace_line(text, key, v.split(" = ")[1], 'name = "lawn"') if key in GRASS else text.replace("density = 10.0", "density = 10.0\n" + v)
    scene_case("grass_%s_%d" % (key, k), text)
BUSH = '\n[[object]]\nname = "shrub"\nprimitive = "bush"\nmaterial = "stone"\nradius = 1.0\n'
for k, v in enumerate(["cards = 0", "cards = 100001", "radius = -1.0", "radius = nan"]):
    key = v.split(" ")[0]
    text = BASE + BUSH
    text = replace_line(text, key, v.split(" = ")[1], 'name = "shrub"') if key in BUSH else text.replace("radius = 1.0\n", "radius = 1.0\n" + v + "\n")
    scene_case("bush_%s_%d" % (key, k), text)

# Budgets: well-formed but too large for the memory budget given.
SMALL = ["--memory-budget", "256MiB"]
scene_case("budget_plane_segments", replace_line(BASE, "segments", "4096", 'name = "ground"'), "segments", SMALL)
scene_case("budget_sphere_segments", replace_line(replace_line(BASE, "segments", "4096", 'name = "ball"'), "radius", "1.0", 'name = "ball"').replace("segments = 4096", "segments = 4096\nrings = 4096"), "segments", SMALL)
scene_case("budget_heightfield", replace_line(BASE + HF, "resolution", "4097", 'name = "hills"').replace("octaves = 3", "octaves = 16"), "4097x4097", SMALL)
scene_case("budget_grass", (BASE + GRASS).replace("size = [4.0, 4.0]", "size = [1000.0, 1000.0]").replace("density = 10.0", "density = 1000.0"), "clumps", SMALL)
scene_case("budget_grass_cards", (BASE + GRASS).replace("size = [4.0, 4.0]", "size = [300.0, 300.0]").replace("density = 10.0", "density = 100.0"), "cards", SMALL)
scene_case("budget_bushes", BASE + BUSH + "cards = 100000\n", "100000 cards", ["--memory-budget", "64MiB"])

# ---------------------------------------------------------------- images (height maps)


def png(width, height, depth, color, rows=None, data=None):
    """A PNG with filter 0 rows; `data` overrides the compressed stream."""
    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF)
    channels = {0: 1, 2: 3, 4: 2, 6: 4}[color]
    row_bytes = width * channels * depth // 8
    if data is None:
        raw = b"".join(b"\0" + (rows(y) if rows else bytes(row_bytes)) for y in range(height))
        data = zlib.compress(raw, 9)
    ihdr = struct.pack(">IIBBBBB", width, height, depth, color, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", data) + chunk(b"IEND", b"")


HF_PNG = '\n[[object]]\nname = "hills"\nprimitive = "heightfield"\nmaterial = "stone"\nsize = [100.0, 100.0]\npng = "%s"\nheight_scale = 10.0\n'


def height_case(name, data, needle=None, extra=(), resolution=None):
    write("image", name + ".png", data)
    text = BASE + HF_PNG % (name + ".png")
    if resolution is not None:
        text = text.replace("height_scale", "resolution = %d\nheight_scale" % resolution)
    path = write("image", name + ".toml", text)
    case("image", name, needle or (name + ".png"), RENDER + ["--scene", path] + list(extra))


good = png(16, 16, 16, 0, rows=lambda y: b"".join(struct.pack(">H", (x * y * 200) & 0xFFFF) for x in range(16)))
height_case("truncated_half", good[: len(good) // 2])
height_case("truncated_header", good[:20])
height_case("not_png", b"GIF89a" + bytes(200))
height_case("empty", b"")
height_case("bad_crc", good[:29] + b"\0\0\0\0" + good[33:])
height_case("bad_zlib", png(16, 16, 16, 0, data=b"\x78\x9c" + bytes(range(64))))
height_case("short_data", png(16, 16, 16, 0, data=zlib.compress(bytes(40))))
height_case("zero_width", png(0, 16, 8, 0))
height_case("huge_header", png(100000, 100000, 16, 0, data=zlib.compress(bytes(100))))
height_case("huge_wide", png(1 << 24, 2, 16, 0, data=zlib.compress(bytes(100))))
height_case("one_pixel", png(1, 1, 16, 0))
height_case("budget_8192", png(8192, 8192, 16, 0), "8192", SMALL)
height_case("resolution_above_png", good, "resolution", resolution=100000)
write("image", "directory.png/keep", b"")
path = write("image", "directory.toml", BASE + HF_PNG % "directory.png")
case("image", "directory", "directory.png", RENDER + ["--scene", path])
path = write("image", "missing.toml", BASE + HF_PNG % "no_such_map.png")
case("image", "missing", "no_such_map.png", RENDER + ["--scene", path])

# ---------------------------------------------------------------- environment maps


def hdr(width, height, pixels=None, header=None):
    head = header if header is not None else b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n" % (height, width)
    body = pixels if pixels is not None else bytes([128, 128, 128, 129]) * (width * height)
    return head + body


def exr(width, height, window=None, pixel=None, channels=b"BGR", lines=None, offsets_valid=True):
    """A scanline, uncompressed, float EXR; `window` = (xmin, ymin, xmax, ymax)."""
    def attr(name, kind, body):
        return name + b"\0" + kind + b"\0" + struct.pack("<i", len(body)) + body
    xmin, ymin, xmax, ymax = window or (0, 0, width - 1, height - 1)
    chlist = b"".join(c.to_bytes(1, "little") + b"\0" + struct.pack("<iBBBBii", 2, 0, 0, 0, 0, 1, 1) for c in channels) + b"\0"
    box = struct.pack("<iiii", xmin, ymin, xmax, ymax)
    header = (b"\x76\x2f\x31\x01" + struct.pack("<i", 2)
              + attr(b"channels", b"chlist", chlist)
              + attr(b"compression", b"compression", b"\0")
              + attr(b"dataWindow", b"box2i", box)
              + attr(b"displayWindow", b"box2i", box)
              + attr(b"lineOrder", b"lineOrder", b"\0")
              + attr(b"pixelAspectRatio", b"float", struct.pack("<f", 1.0))
              + attr(b"screenWindowCenter", b"v2f", struct.pack("<ff", 0.0, 0.0))
              + attr(b"screenWindowWidth", b"float", struct.pack("<f", 1.0))
              + b"\0")
    n = lines if lines is not None else max(0, ymax - ymin + 1)
    w = max(0, xmax - xmin + 1)
    line_bytes = 4 * len(channels) * w
    table_at = len(header)
    first = table_at + 8 * n
    offsets = b"".join(struct.pack("<Q", first + i * (8 + line_bytes) if offsets_valid else 1 << 60) for i in range(n))
    value = struct.pack("<f", pixel if pixel is not None else 0.5)
    body = b"".join(struct.pack("<ii", ymin + i, line_bytes) + value * (len(channels) * w) for i in range(n))
    return header + offsets + body


def env_case(name, ext, data, needle=None):
    path = write("env", name + "." + ext, data)
    case("env", name, needle or (name + "." + ext), RENDER + ["--env", path])


good_exr = exr(8, 4)
env_case("exr_inverted_window", "exr", exr(8, 4, window=(7, 0, 0, 3), lines=4))
env_case("exr_inverted_rows", "exr", exr(8, 4, window=(0, 3, 7, 0), lines=4))
env_case("exr_huge_header", "exr", exr(40000, 20000, lines=0))
env_case("exr_huge_window", "exr", exr(8, 4, window=(-2147483000, 0, 2147483000, 3), lines=0))
env_case("exr_truncated", "exr", good_exr[: len(good_exr) - 40])
env_case("exr_header_only", "exr", good_exr[:200])
env_case("exr_bad_magic", "exr", b"\0\0\0\0" + good_exr[4:])
env_case("exr_bad_offsets", "exr", exr(8, 4, offsets_valid=False))
env_case("exr_not_twice_as_wide", "exr", exr(8, 8))
env_case("exr_nan_pixels", "exr", exr(8, 4, pixel=float("nan")))
env_case("exr_inf_pixels", "exr", exr(8, 4, pixel=float("inf")))
env_case("exr_no_rgb", "exr", exr(8, 4, channels=b"Z"))
env_case("exr_empty", "exr", b"")
env_case("exr_is_hdr", "exr", hdr(8, 4))
env_case("hdr_truncated", "hdr", hdr(8, 4)[:60])
env_case("hdr_bad_magic", "hdr", hdr(8, 4, header=b"#?NOTRADIANCE\n\n-Y 4 +X 8\n"))
env_case("hdr_bad_resolution", "hdr", hdr(8, 4, header=b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y four +X 8\n"))
env_case("hdr_huge_header", "hdr", hdr(8, 4, header=b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 2000000 +X 4000000\n"))
env_case("hdr_zero", "hdr", hdr(0, 0, pixels=b""))
env_case("hdr_not_twice_as_wide", "hdr", hdr(4, 4))
env_case("hdr_empty", "hdr", b"")
env_case("hdr_is_png", "hdr", good)
env_case("hdr_bad_rle", "hdr", hdr(64, 32, pixels=b"\x02\x02\x00\x40" + bytes([255]) * 200))
env_case("wrong_extension", "jpg", good)
case("env", "missing", "no_such_sky.hdr", RENDER + ["--env", "{corpus}/cases/env/no_such_sky.hdr"])

# ---------------------------------------------------------------- glTF / GLB


def triangle():
    positions = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0)
    normals = struct.pack("<9f", 0, 0, 1, 0, 0, 1, 0, 0, 1)
    uvs = struct.pack("<6f", 0, 0, 1, 0, 0, 1)
    indices = struct.pack("<3H", 0, 1, 2) + b"\0\0"
    blob = positions + normals + uvs + indices
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": "tri"}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2},
                                    "indices": 3, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
        "textures": [{"source": 0}],
        "images": [{"uri": "data:image/png;base64," + base64.b64encode(png(2, 2, 8, 6)).decode()}],
        "buffers": [{"byteLength": len(blob), "uri": "data:application/octet-stream;base64," + base64.b64encode(blob).decode()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 36},
            {"buffer": 0, "byteOffset": 72, "byteLength": 24},
            {"buffer": 0, "byteOffset": 96, "byteLength": 6},
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC2"},
            {"bufferView": 3, "componentType": 5123, "count": 3, "type": "SCALAR"},
        ],
    }
    return doc, blob


def gltf_case(name, mutate, needle=None):
    doc, _ = triangle()
    mutate(doc)
    path = write("gltf", name + ".gltf", json.dumps(doc))
    case("gltf", name, needle or (name + ".gltf"), RENDER + ["--gltf", path])


def setter(path, value):
    def mutate(doc):
        node = doc
        for p in path[:-1]:
            node = node[p]
        if value is DELETE:
            del node[path[-1]]
        else:
            node[path[-1]] = value
    return mutate


DELETE = object()
MUTATIONS = [
    ("no_asset", ["asset"], DELETE),
    ("version_3", ["asset", "version"], "3.0"),
    ("scene_out_of_range", ["scene"], 5),
    ("scene_node_out_of_range", ["scenes", 0, "nodes"], [9]),
    ("node_mesh_out_of_range", ["nodes", 0, "mesh"], 4),
    ("node_scale_nan", ["nodes", 0, "scale"], "nan"),
    ("node_rotation_zero", ["nodes", 0, "rotation"], [0, 0, 0, 0]),
    ("node_matrix_short", ["nodes", 0, "matrix"], [1, 0, 0]),
    ("node_matrix_and_trs", ["nodes", 0], {"mesh": 0, "translation": [0, 1, 0], "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]}),
    ("node_self_child", ["nodes", 0, "children"], [0]),
    ("node_child_out_of_range", ["nodes", 0, "children"], [7]),
    ("mesh_no_primitives", ["meshes", 0, "primitives"], []),
    ("mesh_material_out_of_range", ["meshes", 0, "primitives", 0, "material"], 3),
    ("mesh_mode_invalid", ["meshes", 0, "primitives", 0, "mode"], 9),
    ("mesh_no_position", ["meshes", 0, "primitives", 0, "attributes", "POSITION"], DELETE),
    ("mesh_indices_out_of_range", ["meshes", 0, "primitives", 0, "indices"], 11),
    ("attribute_out_of_range", ["meshes", 0, "primitives", 0, "attributes", "NORMAL"], 12),
    ("position_vec2", ["accessors", 0, "type"], "VEC2"),
    ("position_byte", ["accessors", 0, "componentType"], 5120),
    ("position_count_too_big", ["accessors", 0, "count"], 1000),
    ("position_count_zero", ["accessors", 0, "count"], 0),
    ("position_count_negative", ["accessors", 0, "count"], -3),
    ("position_count_huge", ["accessors", 0, "count"], 1 << 40),
    ("position_offset_beyond", ["accessors", 0, "byteOffset"], 40),
    ("position_stride_small", ["bufferViews", 0, "byteStride"], 4),
    ("position_stride_huge", ["bufferViews", 0, "byteStride"], 252),
    ("normal_vec4", ["accessors", 1, "type"], "VEC4"),
    ("normal_scalar", ["accessors", 1, "type"], "SCALAR"),
    ("uv_short", ["accessors", 2, "componentType"], 5122),
    ("uv_uint", ["accessors", 2, "componentType"], 5125),
    ("uv_vec3", ["accessors", 2, "type"], "VEC3"),
    ("indices_float", ["accessors", 3, "componentType"], 5126),
    ("indices_byte", ["accessors", 3, "componentType"], 5120),
    ("indices_short", ["accessors", 3, "componentType"], 5122),
    ("indices_vec2", ["accessors", 3, "type"], "VEC2"),
    ("indices_count_not_triangles", ["accessors", 3, "count"], 2),
    ("component_type_unknown", ["accessors", 1, "componentType"], 9999),
    ("type_unknown", ["accessors", 1, "type"], "VEC9"),
    ("view_out_of_range", ["accessors", 1, "bufferView"], 10),
    ("view_beyond_buffer", ["bufferViews", 1, "byteLength"], 4000),
    ("view_offset_beyond_buffer", ["bufferViews", 1, "byteOffset"], 1 << 33),
    ("view_buffer_out_of_range", ["bufferViews", 1, "buffer"], 3),
    ("buffer_length_above_data", ["buffers", 0, "byteLength"], 4096),
    ("buffer_length_huge", ["buffers", 0, "byteLength"], 1 << 40),
    ("buffer_missing_file", ["buffers", 0, "uri"], "nowhere.bin"),
    ("buffer_bad_base64", ["buffers", 0, "uri"], "data:application/octet-stream;base64,@@@@"),
    ("buffer_no_uri", ["buffers", 0, "uri"], DELETE),
    ("buffer_uri_escape", ["buffers", 0, "uri"], "../../../../../../etc/passwd"),
    ("image_missing_file", ["images", 0, "uri"], "nowhere.png"),
    ("image_bad_bytes", ["images", 0, "uri"], "data:image/png;base64," + base64.b64encode(b"not a png at all").decode()),
    ("image_truncated_png", ["images", 0, "uri"], "data:image/png;base64," + base64.b64encode(png(64, 64, 8, 6)[:80]).decode()),
    ("image_huge_png", ["images", 0, "uri"], "data:image/png;base64," + base64.b64encode(png(60000, 60000, 8, 6, data=zlib.compress(bytes(64)))).decode()),
    ("image_no_source", ["images", 0], {}),
    ("image_out_of_range", ["textures", 0, "source"], 6),
    ("texture_out_of_range", ["materials", 0, "pbrMetallicRoughness", "baseColorTexture", "index"], 9),
    ("texcoord_set_missing", ["materials", 0, "pbrMetallicRoughness", "baseColorTexture", "texCoord"], 3),
    ("base_color_nan", ["materials", 0, "pbrMetallicRoughness", "baseColorFactor"], [1, "nan", 1, 1]),
    ("base_color_short", ["materials", 0, "pbrMetallicRoughness", "baseColorFactor"], [1, 1]),
    ("alpha_mode_unknown", ["materials", 0, "alphaMode"], "GLASS"),
    ("extension_required", ["extensionsRequired"], ["KHR_draco_mesh_compression"]),
    ("extension_required_unknown", ["extensionsRequired"], ["HIMAL_nonsense"]),
    ("skin_out_of_range", ["nodes", 0, "skin"], 2),
    ("camera_out_of_range", ["nodes", 0, "camera"], 2),
    ("accessor_no_type", ["accessors", 0, "type"], DELETE),
    ("accessor_min_wrong_length", ["accessors", 0, "min"], [0]),
]
for name, path_, value in MUTATIONS:
    gltf_case(name, setter(path_, value))


def node_cycle(doc):
    doc["nodes"] = [{"mesh": 0, "children": [1]}, {"children": [0]}]


def exponential_dag(doc):
    # 40 levels, each node twice a child of the one above: 2^40 instances.
    doc["nodes"] = [{"children": [i + 1, i + 1]} for i in range(40)] + [{"mesh": 0}]


def wide_dag(doc):
    doc["nodes"] = [{"children": [1] * 5000}, {"children": [2] * 5000}, {"mesh": 0}]


def sparse(count, indices_view=4, values_view=5, index_offset=0):
    def mutate(doc):
        doc["bufferViews"] += [{"buffer": 0, "byteOffset": 96, "byteLength": 6},
                               {"buffer": 0, "byteOffset": 0, "byteLength": 36}]
        doc["accessors"][0]["sparse"] = {
            "count": count,
            "indices": {"bufferView": indices_view, "byteOffset": index_offset, "componentType": 5123},
            "values": {"bufferView": values_view},
        }
    return mutate


def sparse_index_too_big(doc):
    sparse(3)(doc)
    doc["bufferViews"][4] = {"buffer": 0, "byteOffset": 0, "byteLength": 6}  # floats read as indices


def animation_bad(doc):
    doc["animations"] = [{"channels": [{"sampler": 4, "target": {"node": 0, "path": "translation"}}],
                          "samplers": [{"input": 0, "output": 1}]}]


def animation_input_vec3(doc):
    doc["animations"] = [{"channels": [{"sampler": 0, "target": {"node": 0, "path": "rotation"}}],
                          "samplers": [{"input": 0, "output": 1}]}]


def deep_tree(doc):
    doc["nodes"] = [{"children": [i + 1]} for i in range(100000)] + [{"mesh": 0}]


for name, mutate in [("node_cycle", node_cycle), ("node_exponential_dag", exponential_dag),
                     ("node_wide_dag", wide_dag), ("node_deep_chain", deep_tree),
                     ("sparse_count_huge", sparse(1 << 26)), ("sparse_count_zero", sparse(0)),
                     ("sparse_count_above", sparse(4)), ("sparse_index_view_missing", sparse(1, indices_view=9)),
                     ("sparse_value_view_missing", sparse(1, values_view=9)),
                     ("sparse_index_offset_beyond", sparse(1, index_offset=4000)),
                     ("sparse_index_beyond_count", sparse_index_too_big),
                     ("animation_sampler_out_of_range", animation_bad),
                     ("animation_input_vec3", animation_input_vec3)]:
    gltf_case(name, mutate)

doc, blob = triangle()
text = json.dumps(doc)
for k, cut in enumerate([0, 1, 50, len(text) // 2, len(text) - 1]):
    path = write("gltf", "truncated_%d.gltf" % k, text[:cut])
    case("gltf", "truncated_%d" % k, "truncated_%d.gltf" % k, RENDER + ["--gltf", path])
for name, data in [("not_json", b"hello"), ("json_array", b"[1, 2, 3]"), ("json_null", b"null"),
                   ("invalid_utf8", text.encode().replace(b"tri", b"\xff\xfe\xfd")),
                   ("deep_json", b"[" * 100000 + b"]" * 100000),
                   ("garbage", bytes(rng.randrange(256) for _ in range(2048)))]:
    path = write("gltf", name + ".gltf", data)
    case("gltf", name, name + ".gltf", RENDER + ["--gltf", path])
case("gltf", "missing_file", "no_such_model.gltf", RENDER + ["--gltf", "{corpus}/cases/gltf/no_such_model.gltf"])
# An external buffer that is shorter than declared.
doc, blob = triangle()
doc["buffers"][0]["uri"] = "short.bin"
write("gltf", "short.bin", blob[:50])
path = write("gltf", "external_buffer_short.gltf", json.dumps(doc))
case("gltf", "external_buffer_short", "external_buffer_short.gltf", RENDER + ["--gltf", path])
# Out-of-range index values (vertex 7 of 3).
doc, blob = triangle()
blob = blob[:96] + struct.pack("<3H", 0, 7, 2) + b"\0\0"
doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64.b64encode(blob).decode()
path = write("gltf", "index_value_out_of_range.gltf", json.dumps(doc))
case("gltf", "index_value_out_of_range", "index_value_out_of_range.gltf", RENDER + ["--gltf", path])
# NaN positions in the buffer.
doc, blob = triangle()
blob = struct.pack("<f", float("nan")) + blob[4:]
doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64.b64encode(blob).decode()
doc["accessors"][0].pop("min")
doc["accessors"][0].pop("max")
path = write("gltf", "position_nan.gltf", json.dumps(doc))
case("gltf", "position_nan", "position_nan.gltf", RENDER + ["--gltf", path])


def glb(doc, blob, magic=b"glTF", version=2, length=None, json_kind=b"JSON", bin_kind=b"BIN\0", json_len=None, bin_len=None):
    j = json.dumps(doc).encode()
    j += b" " * (-len(j) % 4)
    blob = blob + b"\0" * (-len(blob) % 4)
    body = (struct.pack("<I", json_len if json_len is not None else len(j)) + json_kind + j
            + struct.pack("<I", bin_len if bin_len is not None else len(blob)) + bin_kind + blob)
    total = 12 + len(body)
    return magic + struct.pack("<II", version, length if length is not None else total) + body


def glb_doc():
    doc, blob = triangle()
    doc["buffers"][0].pop("uri")
    return doc, blob


def glb_case(name, data):
    path = write("glb", name + ".glb", data)
    case("glb", name, name + ".glb", RENDER + ["--gltf", path])


doc, blob = glb_doc()
good_glb = glb(doc, blob)
glb_case("bad_magic", glb(doc, blob, magic=b"gLTF"))
glb_case("version_1", glb(doc, blob, version=1))
glb_case("length_smaller", glb(doc, blob, length=40))
glb_case("length_larger", glb(doc, blob, length=len(good_glb) + 100))
glb_case("length_huge", glb(doc, blob, length=0xFFFFFFFF))
glb_case("json_chunk_beyond", glb(doc, blob, json_len=1 << 30))
glb_case("json_chunk_zero", glb(doc, blob, json_len=0))
glb_case("json_chunk_kind", glb(doc, blob, json_kind=b"JSOX"))
glb_case("bin_chunk_beyond", glb(doc, blob, bin_len=1 << 30))
glb_case("bin_chunk_short", glb(doc, blob, bin_len=8))
glb_case("bin_chunk_kind", glb(doc, blob, bin_kind=b"BON\0"))
glb_case("header_only", good_glb[:12])
glb_case("truncated_half", good_glb[: len(good_glb) // 2])
glb_case("truncated_last_byte", good_glb[:-1])
glb_case("empty", b"")
glb_case("json_not_json", good_glb[:20] + b"{{{{" + good_glb[24:])
doc2, blob2 = glb_doc()
doc2["buffers"][0]["byteLength"] = 100000
glb_case("buffer_longer_than_bin", glb(doc2, blob2))
doc3, _ = glb_doc()
glb_case("no_bin_chunk", glb(doc3, b"")[: 20 + len(json.dumps(doc3)) + (-len(json.dumps(doc3)) % 4)])
for k in range(12):
    data = bytearray(good_glb)
    for _ in range(8):
        data[rng.randrange(20, len(data))] = rng.randrange(256)
    # Byte flips that leave the JSON intact may render: keep only the ones that break it.
    glb_case("flipped_%d" % k, bytes(data[:20]) + b"\x01" + bytes(data[21:]))

# ---------------------------------------------------------------- arguments


def arg_case(name, needle, args):
    case("args", name, needle, args)


for opt, values in [
    ("--size", ["0x0", "8", "8x", "x8", "-8x8", "8x-8", "16385x8", "99999999999x8", "axb", "8x8x8", ""]),
    ("--frames", ["0", "-1", "4294967296", "1.5", "many"]),
    ("--speed", ["nan", "inf", "-inf", "1e30", "-1e30", "fast"]),
    ("--env-intensity", ["nan", "-1", "inf", "x"]),
    ("--ao-radius", ["nan", "-1", "0", "inf", "1e30"]),
    ("--exposure", ["nan", "inf", "bright", "1e30"]),
    ("--bloom", ["maybe", ""]),
    ("--bloom-threshold", ["nan", "-1", "inf"]),
    ("--bloom-strength", ["nan", "-1", "inf"]),
    ("--bloom-passes", ["9", "-1", "100000"]),
    ("--white-point", ["nan", "0", "-1", "inf"]),
    ("--aa", ["msaa", ""]),
    ("--aa-buffers", ["depth", "ao,ao,motion,x"]),
    ("--sky", ["hosek"]),
    ("--sky-tables", ["huge"]),
    ("--shadows", ["pcss"]),
    ("--shadow-resolution", ["0", "15", "16385", "-1", "99999999999"]),
    ("--static-resolution", ["0", "16385", "-5"]),
    ("--hero", ["nobody"]),
    ("--camera", ["nowhere"]),
    ("--time", ["25:00", "noon", "-1:00", "12:60"]),
    ("--time-lapse", ["10:00", "10:00..", "..12:00", "10:00..26:00"]),
    ("--view", ["xray"]),
    ("--env-specular", ["maybe"]),
    ("--env-probes", ["maybe"]),
    ("--sky-occlusion", ["maybe"]),
    ("--bent-normals", ["maybe"]),
    ("--adapter", ["nonexistent-gpu-9000"]),
    ("--memory-budget", ["0", "-1", "lots", "1e30GiB", "12XB"]),
]:
    for k, v in enumerate(values):
        arg_case("%s_%d" % (opt.strip("-"), k), opt, RENDER + [opt, v])
for opt in ["--ao", "--ao-resolution", "--ao-blur", "--ao-blur-radius"]:
    for k, v in enumerate(["nan", "-1", "1000000", "zzz"]):
        arg_case("%s_%d" % (opt.strip("-"), k), opt, RENDER + [opt, v])
arg_case("out_extension", "x.bmp", ["render", "--size", "8x8", "--out", "{out}/x.bmp"])
arg_case("out_unwritable", "/proc/himal-corpus/x.png", ["render", "--size", "8x8", "--out", "/proc/himal-corpus/x.png"])
arg_case("out_is_directory", "{out}", ["render", "--size", "8x8", "--out", "{out}"])
arg_case("cache_is_file", "cases.tsv", RENDER + ["--cache", "{corpus}/cases.tsv"])
arg_case("frames_budget", "--frames", ["render", "--size", "256x256", "--frames", "4294967295", "--out", "{out}/x.png"])
arg_case("size_budget", "--size", ["render", "--size", "16384x16384", "--memory-budget", "256MiB", "--out", "{out}/x.png"])
arg_case("gltf_and_scene_missing", "no_such.glb", ["render", "--gltf", "no_such.glb", "--size", "8x8", "--out", "{out}/x.png"])
arg_case("bench_size", "--size", ["bench", "--size", "0x0"])
arg_case("soak_frames", "--frames", ["soak", "--frames", "0"])
arg_case("soak_growth", "--max-growth", ["soak", "--frames", "4", "--max-growth", "nan"])
arg_case("bake_tables", "--tables", ["bake", "--tables", "huge"])
arg_case("view_size", "--size", ["view", "--size", "0x0"])
arg_case("unknown_command", "frobnicate", ["frobnicate"])
arg_case("unknown_flag", "--frobnicate", ["render", "--frobnicate"])

# ---------------------------------------------------------------- write the manifest

manifest = "# generated by generate.py: class, name, expect, needle, args (see its docstring)\n"
manifest += "\n".join(rows) + "\n"
for folder in {OUT, HERE}:
    with open(os.path.join(folder, "cases.tsv"), "w") as f:
        f.write(manifest)
counts = {}
for r in rows:
    counts[r.split("\t")[0]] = counts.get(r.split("\t")[0], 0) + 1
print("%d cases: %s" % (len(rows), ", ".join("%s %d" % kv for kv in sorted(counts.items()))))
