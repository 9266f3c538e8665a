#!/usr/bin/env python3
"""Makes the textured teapot: texture coordinates for the Utah teapot and a porcelain image.

Reads   assets/models/teapot.obj            (the public-domain Utah teapot, y-up, no vt/vn)
Writes  assets/models/teapot-textured.obj   (the same vertices and faces, plus vt per corner)
        assets/models/teapot-textured.mtl   (material "porcelain": Kd 1 1 1, map_Kd the image)
        assets/models/teapot-porcelain.png  (512x256, cobalt blue on white)

Python 3 standard library only (the PNG is written with zlib and struct), and deterministic:
running it again rebuilds the same files.

    python3 scripts/assets/make_textured_teapot.py [--models DIR]

Texture coordinates are a cylindrical projection about the teapot's vertical axis (the line
through its lowest and highest points, x = -1.07, z = 0 in the file; not x = 0, since the file
is centred on its bounding box and the spout reaches further than the handle):

    u = 0.5 + atan2(-z, x - axis_x) / 2pi    v = (y - y_min) / (y_max - y_min)

u = 0.5 faces the spout (+x) and the seam u = 0 = 1 runs down the handle (-x), where it shows
least. u grows to the right seen from outside (counter-clockwise faces, y up, as in OBJ files),
so the image is not mirrored. v = 0 is the base and v = 1 the top of the lid's knob, and an
image's v goes up (OBJ convention), so the image's top row wraps the knob. A face straddling
the seam gets its small u values raised by 1 so that it spans the seam (u just under 1 to just
over 1) instead of the whole image backwards; texture lookups repeat, so u > 1 is fine. A
corner on the axis itself (the base's centre, the knob's top) has no angle: it takes the mean
u of the face's other corners.

No vertex normals are written: raylab computes smooth normals itself.
"""

import argparse
import math
import os
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT_MODELS = os.path.normpath(os.path.join(HERE, "..", "..", "assets", "models"))

WIDTH, HEIGHT = 512, 256
SUPERSAMPLE = 4  # 4x4 samples per pixel, averaged in linear light

# Colours in 8-bit sRGB. raylab's default display shows linear values without a gamma curve,
# so the ground is near white and most of the image stays bright; the cobalt is an accent.
WHITE = (250, 250, 246)
COBALT = (30, 74, 172)
WASH = (156, 186, 232)  # the pale blue of thinned cobalt


# --- Texture coordinates ------------------------------------------------------------------


def read_obj(path):
    """The vertex lines (as text), the positions and the faces (0-based vertex indices)."""
    vertex_lines, positions, faces = [], [], []
    with open(path, encoding="utf-8") as f:
        for line in f:
            parts = line.split()
            if not parts:
                continue
            if parts[0] == "v":
                vertex_lines.append(line.rstrip("\n"))
                positions.append(tuple(float(p) for p in parts[1:4]))
            elif parts[0] == "f":
                face = []
                for corner in parts[1:]:
                    i = int(corner.split("/")[0])
                    face.append(i - 1 if i > 0 else len(positions) + i)
                faces.append(face)
    return vertex_lines, positions, faces


def cylindrical_uvs(positions, faces):
    """Per face, the (u, v) of each corner, the seam and the axis handled."""
    y_min = min(p[1] for p in positions)
    y_max = max(p[1] for p in positions)
    ends = [p for p in positions if p[1] in (y_min, y_max)]
    axis_x = sum(p[0] for p in ends) / len(ends)
    axis_z = sum(p[2] for p in ends) / len(ends)
    extent = max(abs(p[0] - axis_x) for p in positions)

    def angle_u(p):
        dx, dz = p[0] - axis_x, p[2] - axis_z
        if math.hypot(dx, dz) < 1e-6 * extent:
            return None  # on the axis: no angle
        return 0.5 + math.atan2(-dz, dx) / (2.0 * math.pi)

    face_uvs = []
    for face in faces:
        us = [angle_u(positions[i]) for i in face]
        known = [u for u in us if u is not None]
        if known and max(known) - min(known) > 0.5:
            # Across the seam: lift the small side past 1.
            us = [u + 1.0 if u is not None and u < 0.5 else u for u in us]
            known = [u for u in us if u is not None]
        fill = sum(known) / len(known) if known else 0.5
        us = [fill if u is None else u for u in us]
        vs = [(positions[i][1] - y_min) / (y_max - y_min) for i in face]
        face_uvs.append(list(zip(us, vs)))
    return face_uvs, (axis_x, axis_z)


def write_obj(path, vertex_lines, faces, face_uvs, axis):
    vt_index, vt_lines, face_lines = {}, [], []
    for face, uvs in zip(faces, face_uvs):
        corners = []
        for i, (u, v) in zip(face, uvs):
            key = f"vt {u:.6f} {v:.6f}"
            if key not in vt_index:
                vt_index[key] = len(vt_lines) + 1
                vt_lines.append(key)
            corners.append(f"{i + 1}/{vt_index[key]}")
        face_lines.append("f " + " ".join(corners))
    header = [
        "# Utah teapot with texture coordinates (public domain), made from teapot.obj by",
        "# scripts/assets/make_textured_teapot.py: a cylindrical projection about the",
        f"# vertical axis x = {axis[0]:g}, z = {axis[1]:g}; u = 0.5 at the spout, the seam at the handle.",
        f"# {len(vertex_lines)} vertices, {len(vt_lines)} texture coordinates, {len(faces)} faces",
        "mtllib teapot-textured.mtl",
    ]
    body = vertex_lines + vt_lines + ["usemtl porcelain"] + face_lines
    with open(path, "w", encoding="utf-8", newline="\n") as f:
        f.write("\n".join(header + body) + "\n")
    return len(vt_lines)


def write_mtl(path):
    with open(path, "w", encoding="utf-8", newline="\n") as f:
        f.write(
            "# Blue-and-white porcelain for teapot-textured.obj; made by\n"
            "# scripts/assets/make_textured_teapot.py\n"
            "newmtl porcelain\n"
            "Kd 1 1 1\n"
            "map_Kd teapot-porcelain.png\n"
        )


# --- The porcelain image --------------------------------------------------------------------
#
# Drawn as a function of (u, v) in the texture's own convention (v up). Motifs are laid out in
# units of the teapot's surface: a band at height v wraps a circumference of 2 pi r, and the
# teapot is 15.75 high, so a motif drawn in those units looks round on the pot, not stretched
# around it. Each band repeats a whole number of times around, so the seam does not show.

POT_HEIGHT = 15.75


def srgb_to_linear(c):
    c /= 255.0
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


def linear_to_srgb8(x):
    x = min(max(x, 0.0), 1.0)
    c = x * 12.92 if x <= 0.0031308 else 1.055 * x ** (1.0 / 2.4) - 0.055
    return int(round(c * 255.0))


def cell(u, v, count, radius, v_centre):
    """Where (u, v) lies in the nearest of `count` motifs centred at u = k/count, v_centre:
    (dx, dy) in surface units for a band of the given radius."""
    t = u * count
    dx = (t - math.floor(t + 0.5)) * 2.0 * math.pi * radius / count
    dy = (v - v_centre) * POT_HEIGHT
    return dx, dy


def medallion(u, v):
    """Eight roundels round the widest part: a double cobalt ring round a pale rosette."""
    dx, dy = cell(u, v, 8, 9.8, 0.41)
    r = math.hypot(dx, dy)
    if r < 2.35:
        if r > 2.05:
            return COBALT
        if r > 1.85:
            return WHITE
        if r > 1.72:
            return COBALT
        if r < 0.32:
            return COBALT
        # Eight petals: the outline r = 1.55 (0.5 + 0.5 |cos 4 theta|).
        edge = 1.55 * (0.45 + 0.55 * abs(math.cos(4.0 * math.atan2(dy, dx))))
        if r < edge - 0.14:
            return WASH
        if r < edge:
            return COBALT
        return WHITE
    # Between roundels: a diamond with a dot above and below.
    gx, gy = cell(u + 0.5 / 8, v, 8, 9.8, 0.41)
    if abs(gx) / 0.55 + abs(gy) / 0.9 < 1.0:
        return COBALT
    for centre in (1.55, -1.55):
        if math.hypot(gx, gy - centre) < 0.24:
            return COBALT
    return None


def petals(u, v):
    """Sixteen upright lotus petals above the foot: pale, outlined in cobalt."""
    base, tip = 0.08, 0.195
    if not base <= v <= tip:
        return None
    dx, dy = cell(u, v, 16, 8.6, base)
    height = (tip - base) * POT_HEIGHT
    s = dy / height  # 0 at the base, 1 at the tip
    half_width = 1.35 * math.sqrt(max(0.0, 1.0 - s * s)) * (1.0 - 0.35 * s)
    inside = abs(dx) - half_width
    if inside < -0.16:
        # A cobalt vein up the middle of the lower half.
        return COBALT if abs(dx) < 0.09 and s < 0.55 else WASH
    if inside < 0.0:
        return COBALT
    # A dot between the petals' tips.
    gx, gy = cell(u + 0.5 / 16, v, 16, 8.6, 0.16)
    if math.hypot(gx, gy) < 0.2:
        return COBALT
    return None


def waves(u, v):
    """A running wave round the shoulder, with pale dots in its hollows."""
    v_centre = 0.6625
    count = 12
    radius = 8.3
    x = u * count
    amplitude = 0.42
    dy = (v - v_centre) * POT_HEIGHT
    crest = amplitude * math.sin(2.0 * math.pi * x)
    # Thickness measured across the wave, not vertically: divide by the slope's secant.
    slope = amplitude * 2.0 * math.pi * math.cos(2.0 * math.pi * x) * count / (2.0 * math.pi * radius)
    if abs(dy - crest) / math.sqrt(1.0 + slope * slope) < 0.13:
        return COBALT
    # Dots above the troughs and below the crests.
    for phase, side in ((0.75, 1.0), (0.25, -1.0)):
        gx, _ = cell(u - phase / count, v, count, radius, v_centre)
        if math.hypot(gx, dy - side * 0.38) < 0.2:
            return WASH
    return None


def spokes(u, v):
    """The lid: a pale wash with 24 cobalt rays running to the knob."""
    dx, _ = cell(u, v, 24, 4.0, 0.0)
    return COBALT if abs(dx) < 0.16 else WASH


def porcelain(u, v):
    """The colour (8-bit sRGB) at (u, v), v up: bottom of the pot at v = 0."""
    bands = [  # (from v, to v, solid colour or pattern)
        (0.000, 0.045, COBALT),  # the foot
        (0.060, 0.068, COBALT),
        (0.075, 0.205, petals),
        (0.205, 0.214, COBALT),
        (0.225, 0.595, medallion),
        (0.603, 0.611, COBALT),
        (0.620, 0.705, waves),
        (0.713, 0.721, COBALT),
        (0.755, 0.797, COBALT),  # the rim of the pot and the lid's edge
        (0.797, 0.852, spokes),  # the lid
        (0.852, 0.900, COBALT),  # the knob's neck
        (0.965, 1.001, COBALT),  # the top of the knob
    ]
    for lo, hi, fill in bands:
        if lo <= v < hi:
            colour = fill(u, v) if callable(fill) else fill
            return colour if colour is not None else WHITE
    return WHITE


def render_image():
    lut = {}

    def linear(colour):
        if colour not in lut:
            lut[colour] = tuple(srgb_to_linear(c) for c in colour)
        return lut[colour]

    n = SUPERSAMPLE
    rows = []
    for y in range(HEIGHT):
        row = bytearray()
        for x in range(WIDTH):
            total = [0.0, 0.0, 0.0]
            for sy in range(n):
                # Image rows go down, v goes up.
                v = 1.0 - (y + (sy + 0.5) / n) / HEIGHT
                for sx in range(n):
                    u = (x + (sx + 0.5) / n) / WIDTH
                    c = linear(porcelain(u, v))
                    total[0] += c[0]
                    total[1] += c[1]
                    total[2] += c[2]
            row.extend(linear_to_srgb8(t / (n * n)) for t in total)
        rows.append(bytes(row))
    return rows


def png_chunk(kind, data):
    body = kind + data
    return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)


def filtered(rows, stride):
    """Each row with the PNG filter (none, sub or up) that leaves the smallest residuals."""
    out = bytearray()
    previous = bytes(len(rows[0]))
    for row in rows:
        candidates = [
            (0, row),
            (1, bytes((row[i] - (row[i - stride] if i >= stride else 0)) & 0xFF for i in range(len(row)))),
            (2, bytes((row[i] - previous[i]) & 0xFF for i in range(len(row)))),
        ]
        cost = lambda data: sum(b if b < 128 else 256 - b for b in data)  # noqa: E731
        kind, data = min(candidates, key=lambda c: cost(c[1]))
        out.append(kind)
        out.extend(data)
        previous = row
    return bytes(out)


def write_png(path, rows, width, height):
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)  # 8-bit RGB
    data = zlib.compress(filtered(rows, 3), 9)
    png = (
        b"\x89PNG\r\n\x1a\n"
        + png_chunk(b"IHDR", ihdr)
        + png_chunk(b"sRGB", b"\x00")  # the values are sRGB (perceptual intent)
        + png_chunk(b"IDAT", data)
        + png_chunk(b"IEND", b"")
    )
    with open(path, "wb") as f:
        f.write(png)
    return len(png)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--models", default=DEFAULT_MODELS, help="the assets/models directory")
    args = parser.parse_args()

    source = os.path.join(args.models, "teapot.obj")
    vertex_lines, positions, faces = read_obj(source)
    face_uvs, axis = cylindrical_uvs(positions, faces)
    obj_path = os.path.join(args.models, "teapot-textured.obj")
    vt_count = write_obj(obj_path, vertex_lines, faces, face_uvs, axis)
    write_mtl(os.path.join(args.models, "teapot-textured.mtl"))
    png_path = os.path.join(args.models, "teapot-porcelain.png")
    size = write_png(png_path, render_image(), WIDTH, HEIGHT)
    print(f"{obj_path}: {len(positions)} vertices, {vt_count} vt, {len(faces)} faces")
    print(f"{png_path}: {WIDTH}x{HEIGHT}, {size} bytes")


if __name__ == "__main__":
    main()
