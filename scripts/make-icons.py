"""Draws the app icons (www/icons/*.png) with no dependencies: a four-petal
rosette in the accent colour on the app's dark background. Run once when the
design changes; the PNGs are committed."""
import math, struct, zlib, sys, os

BG, FG, FG2 = (29, 27, 38), (201, 162, 255), (127, 209, 199)

def png(path, size, pixels):
    raw = b''.join(b'\x00' + bytes(pixels[y * size * 4:(y + 1) * size * 4]) for y in range(size))
    def chunk(t, d): return struct.pack('>I', len(d)) + t + d + struct.pack('>I', zlib.crc32(t + d) & 0xffffffff)
    data = b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', size, size, 8, 6, 0, 0, 0)) \
        + chunk(b'IDAT', zlib.compress(raw, 9)) + chunk(b'IEND', b'')
    open(path, 'wb').write(data)

def draw(size, maskable):
    px = bytearray(size * size * 4)
    scale = 0.62 if maskable else 0.8  # maskable icons keep art inside the 80% safe zone
    for y in range(size):
        for x in range(size):
            u, v = (x + .5) / size * 2 - 1, (y + .5) / size * 2 - 1
            # rounded-square background (full bleed when maskable)
            q = max(abs(u), abs(v))
            corner = math.hypot(max(abs(u) - .7, 0), max(abs(v) - .7, 0)) - .3
            bg_a = 1.0 if maskable else min(1, max(0, -corner * size / 2 + .5))
            u, v = u / scale, v / scale
            r, t = math.hypot(u, v), math.atan2(v, u)
            rose = abs(r - abs(math.cos(2 * t))) * (1 + abs(math.sin(2 * t)) * .0)
            ring = abs(r - .28)
            w = 1.6 / size / scale * 2
            a1 = min(1, max(0, (.07 - rose) / w + .5)) if r < 1.02 else 0
            a2 = min(1, max(0, (.06 - ring) / w + .5))
            col = list(BG)
            for c, a in ((FG, a1), (FG2, a2)):
                col = [col[i] * (1 - a) + c[i] * a for i in range(3)]
            i = (y * size + x) * 4
            px[i:i + 4] = bytes([round(col[0]), round(col[1]), round(col[2]), round(255 * bg_a)])
    return px

out = os.path.join(os.path.dirname(__file__), '..', 'www', 'icons')
for name, size, m in (('icon-192.png', 192, False), ('icon-512.png', 512, False), ('icon-maskable-512.png', 512, True)):
    png(os.path.join(out, name), size, draw(size, m))
