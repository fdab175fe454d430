#!/usr/bin/env python3
"""Writes the terrain textures in assets/textures/: an albedo (sRGB) and a
tangent-space normal map (linear, OpenGL convention: +X right, +Y up in the
image, +Z out) for each of rock, dirt, grass and ore.

Deterministic (fixed seeds) and seamless: every noise field is periodic
over the image, so the textures tile without seams, as triplanar mapping
needs. Only the Python standard library (zlib and struct write the PNGs).

    python3 scripts/make_textures.py [--size 256] [--out assets/textures]
"""

import argparse
import math
import os
import random
import struct
import zlib


# ---------------------------------------------------------------- noise


class Lattice:
    """Random values on a periodic `period`² lattice, interpolated with a
    quintic fade: value noise that tiles over one period."""

    def __init__(self, seed, period):
        rng = random.Random(seed)
        self.period = period
        self.values = [rng.random() for _ in range(period * period)]

    def at(self, u, v):
        """Noise in [0, 1] at (u, v) in [0, 1)², tiling."""
        p = self.period
        x, y = u * p, v * p
        xi, yi = int(math.floor(x)), int(math.floor(y))
        fx, fy = x - xi, y - yi
        x0, y0 = xi % p, yi % p
        x1, y1 = (x0 + 1) % p, (y0 + 1) % p
        vals = self.values
        a = vals[y0 * p + x0]
        b = vals[y0 * p + x1]
        c = vals[y1 * p + x0]
        d = vals[y1 * p + x1]
        sx = fx * fx * fx * (fx * (fx * 6 - 15) + 10)
        sy = fy * fy * fy * (fy * (fy * 6 - 15) + 10)
        top = a + (b - a) * sx
        bottom = c + (d - c) * sx
        return top + (bottom - top) * sy


class Fbm:
    """Fractal sum of lattices with periods `base`, 2·base, 4·base, ...:
    every octave tiles over the image."""

    def __init__(self, seed, base, octaves, gain=0.5):
        self.layers = []
        amplitude = 1.0
        for k in range(octaves):
            self.layers.append((Lattice(seed * 131 + k, base << k), amplitude))
            amplitude *= gain
        self.norm = sum(a for _, a in self.layers)

    def at(self, u, v):
        return sum(lat.at(u, v) * a for lat, a in self.layers) / self.norm


class Cells:
    """Periodic Worley noise: one random point per cell of a `period`²
    grid; `at` gives the distances to the nearest and second-nearest point
    (in cell units) and the nearest point's random id."""

    def __init__(self, seed, period):
        rng = random.Random(seed)
        self.period = period
        self.points = [(rng.random(), rng.random(), rng.random()) for _ in range(period * period)]

    def at(self, u, v):
        p = self.period
        x, y = u * p, v * p
        xi, yi = int(math.floor(x)), int(math.floor(y))
        best, second, ident = 9.0, 9.0, 0.0
        for dy in (-1, 0, 1):
            for dx in (-1, 0, 1):
                cx, cy = xi + dx, yi + dy
                px, py, pid = self.points[(cy % p) * p + (cx % p)]
                d = math.hypot(cx + px - x, cy + py - y)
                if d < best:
                    best, second, ident = d, best, pid
                elif d < second:
                    second = d
        return best, second, ident


def smoothstep(e0, e1, x):
    t = min(max((x - e0) / (e1 - e0), 0.0), 1.0)
    return t * t * (3 - 2 * t)


def mix(a, b, t):
    return tuple(x + (y - x) * t for x, y in zip(a, b))


# ---------------------------------------------------------------- materials
#
# Each material is a function (u, v) -> (height in [0, 1], linear-ish
# albedo rgb in [0, 1]). Heights drive the normal map.


def rock(seed):
    base = Fbm(seed, 4, 6, 0.55)
    cracks = Cells(seed + 1, 5)
    warp = Fbm(seed + 3, 4, 3, 0.5)
    grain = Fbm(seed + 2, 32, 3, 0.5)

    def sample(u, v):
        h = base.at(u, v)
        # Cracks along the edges of warped cells: irregular plates.
        wu = u + 0.06 * (warp.at(u, v) - 0.5)
        wv = v + 0.06 * (warp.at(v, u) - 0.5)
        d1, d2, ident = cracks.at(wu % 1.0, wv % 1.0)
        crack = smoothstep(0.0, 0.06 + 0.08 * h, d2 - d1)
        g = grain.at(u, v)
        height = 0.55 * h + 0.3 * crack + 0.15 * g
        light = 0.24 + 0.3 * h + 0.12 * g + 0.08 * (ident - 0.5)
        light *= 0.6 + 0.4 * crack
        colour = (light * 1.0, light * 0.97, light * 0.92)
        return height, colour

    return sample


def dirt(seed):
    base = Fbm(seed, 4, 5, 0.5)
    pebbles = Cells(seed + 1, 16)
    grain = Fbm(seed + 2, 64, 2, 0.5)

    def sample(u, v):
        h = base.at(u, v)
        d1, _, ident = pebbles.at(u, v)
        pebble = (1.0 - smoothstep(0.18, 0.32, d1)) * (ident > 0.55)
        g = grain.at(u, v)
        height = 0.45 * h + 0.35 * pebble + 0.2 * g
        soil = mix((0.30, 0.20, 0.12), (0.46, 0.33, 0.21), h)
        stone = mix((0.42, 0.38, 0.33), (0.58, 0.54, 0.48), ident)
        colour = mix(soil, stone, pebble)
        colour = tuple(c * (0.85 + 0.3 * g) for c in colour)
        return height, colour

    return sample


def grass(seed):
    base = Fbm(seed, 4, 4, 0.5)
    blades = Fbm(seed + 1, 64, 2, 0.6)
    tufts = Cells(seed + 2, 24)

    def sample(u, v):
        h = base.at(u, v)
        b = blades.at(u, v)
        d1, _, ident = tufts.at(u, v)
        tuft = 1.0 - smoothstep(0.0, 0.5, d1)
        height = 0.3 * h + 0.4 * b + 0.3 * tuft
        colour = mix((0.16, 0.30, 0.08), (0.34, 0.52, 0.16), 0.2 * h + 0.8 * tuft)
        colour = mix(colour, (0.48, 0.50, 0.20), 0.35 * ident * (h > 0.55))
        colour = tuple(c * (0.75 + 0.5 * b) for c in colour)
        return height, colour

    return sample


def ore(seed):
    stone = rock(seed)
    veins = Fbm(seed + 7, 4, 5, 0.5)
    flecks = Cells(seed + 8, 20)

    def sample(u, v):
        height, colour = stone(u, v)
        colour = tuple(c * 0.8 for c in colour)
        vein = 1.0 - smoothstep(0.0, 0.05, abs(veins.at(u, v) - 0.5))
        d1, _, ident = flecks.at(u, v)
        fleck = (1.0 - smoothstep(0.12, 0.22, d1)) * (ident > 0.5)
        metal = max(vein, fleck)
        gold = mix((0.72, 0.52, 0.14), (0.95, 0.78, 0.32), ident)
        colour = mix(colour, gold, metal)
        height = height * (1.0 - 0.4 * metal) + 0.4 * metal
        return height, colour

    return sample


MATERIALS = {
    "rock": (rock, 11, 5.0),
    "dirt": (dirt, 23, 3.0),
    "grass": (grass, 37, 3.5),
    "ore": (ore, 11, 5.0),
}


# ---------------------------------------------------------------- PNG


def png(path, width, height, rows):
    """Writes 8-bit RGB `rows` (lists of bytes) as a PNG, choosing each
    row's filter by the minimum-sum-of-absolute-differences heuristic."""

    def paeth(a, b, c):
        p = a + b - c
        pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
        if pa <= pb and pa <= pc:
            return a
        return b if pb <= pc else c

    raw = bytearray()
    prev = bytes(width * 3)
    for row in rows:
        row = bytes(row)
        candidates = []
        for kind in range(5):
            out = bytearray([kind])
            for i, x in enumerate(row):
                a = row[i - 3] if i >= 3 else 0
                b = prev[i]
                c = prev[i - 3] if i >= 3 else 0
                predicted = (0, a, b, (a + b) // 2, paeth(a, b, c))[kind]
                out.append((x - predicted) & 0xFF)
            cost = sum(min(d, 256 - d) for d in out[1:])
            candidates.append((cost, kind, out))
        raw += min(candidates)[2]
        prev = row

    def chunk(tag, data):
        body = tag + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)

    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    data = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header)
    data += chunk(b"IDAT", zlib.compress(bytes(raw), 9)) + chunk(b"IEND", b"")
    with open(path, "wb") as f:
        f.write(data)


def to_byte(x):
    return max(0, min(255, int(round(x * 255.0))))


def write_material(name, out_dir, size):
    make, seed, strength = MATERIALS[name]
    sample = make(seed)
    heights = [[0.0] * size for _ in range(size)]
    albedo_rows = []
    for y in range(size):
        row = bytearray()
        for x in range(size):
            h, colour = sample((x + 0.5) / size, (y + 0.5) / size)
            heights[y][x] = h
            # The colours above are chosen by eye as display values; store
            # them as they are (the albedo texture is read as sRGB).
            row += bytes(to_byte(c) for c in colour)
        albedo_rows.append(row)
    png(os.path.join(out_dir, f"{name}_albedo.png"), size, size, albedo_rows)

    # Normals from the periodic height field by central differences:
    # n = normalize(-dh/dx, +dh/drow, 1) (image y points down, +Y up).
    normal_rows = []
    k = strength * size / 256.0
    for y in range(size):
        row = bytearray()
        for x in range(size):
            dx = heights[y][(x + 1) % size] - heights[y][(x - 1) % size]
            dy = heights[(y + 1) % size][x] - heights[(y - 1) % size][x]
            nx, ny, nz = -k * dx, k * dy, 1.0
            inv = 1.0 / math.sqrt(nx * nx + ny * ny + nz * nz)
            row += bytes(to_byte(c * inv * 0.5 + 0.5) for c in (nx, ny, nz))
        normal_rows.append(row)
    png(os.path.join(out_dir, f"{name}_normal.png"), size, size, normal_rows)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--size", type=int, default=256, help="edge in pixels (a power of two)")
    parser.add_argument("--out", default=os.path.join(os.path.dirname(__file__), "..", "assets", "textures"))
    parser.add_argument("materials", nargs="*", default=list(MATERIALS))
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)
    for name in args.materials:
        write_material(name, args.out, args.size)
        print(f"wrote {name}_albedo.png and {name}_normal.png in {os.path.normpath(args.out)}")


if __name__ == "__main__":
    main()
