#!/usr/bin/env python3
"""The SH course notes' "Is SH basis well-suited?" figure (Kautz 2004, after Sloan et al. 2002):
a square blocker over a receiver plane, lit from the zenith by a point light and by 20 and
40 degree sources, relit with SH of several orders and with Haar wavelets, against the exact
shadow. Python standard library only (bench/sh_quality.sh runs prt between the steps).

  sh_quality.py scene DIR [--cells N]     the OBJ, the disc environment maps, geometry.json
  sh_quality.py analyse DIR [--check]     exact shadow, errors, table, PNG grid, SVG profiles

Geometry (scene units): the plane [-1, 1]^2 at y = 0 with N x N cells, normal +y, albedo 1; the
blocker a 0.6 x 0.6 box between y = 0.38 and 0.40 centred over the plane. The light sits at the
zenith. A source's size is its cone angle, the angular diameter of the disc (the sun is a half-degree
source): a 20 degree source is a disc of radius 10 degrees. It is a lat-long map whose top rows
hold it exactly (rows are bands of the sphere), so SH, wavelets and the exact answer all see the
same light; its radiance gives the open plane an irradiance of pi (exit radiance 1). The point
light is a directional light of irradiance pi, which both methods relight.
"""
import json
import math
import os
import struct
import sys
import zlib

HALF = 0.3                  # the blocker's half side
Y_BOTTOM, Y_TOP = 0.38, 0.40
PLANE = 1.0                 # the plane's half side
VIEW = 0.75                 # half side of the plane shown in each panel
MEASURE = 0.7               # errors are measured where |x|, |z| <= this: the shadow and around it
ENV_ROWS = 720              # lat-long map height: a quarter of a degree per row


def parse_sizes(text):
    return [float(s) for s in text.split(',')]


# ---------------------------------------------------------------- scene

def write_scene(d, cells):
    os.makedirs(d, exist_ok=True)
    n = cells
    lines = ['# plane and blocker for bench/sh_quality.py', 'o plane']
    for j in range(n + 1):
        for i in range(n + 1):
            lines.append('v %.6f 0 %.6f' % (-PLANE + 2 * PLANE * i / n, -PLANE + 2 * PLANE * j / n))
    lines.append('vn 0 1 0')

    def vid(i, j):
        return j * (n + 1) + i + 1
    for j in range(n):
        for i in range(n):
            a, b, c, e = vid(i, j), vid(i + 1, j), vid(i + 1, j + 1), vid(i, j + 1)
            lines.append('f %d//1 %d//1 %d//1' % (a, e, c))
            lines.append('f %d//1 %d//1 %d//1' % (a, c, b))
    # The box: each face its own four vertices and normal, wound counter-clockwise from outside.
    base = (n + 1) * (n + 1)
    h, lo, hi = HALF, Y_BOTTOM, Y_TOP
    faces = [((0, 1, 0), [(-h, hi, -h), (-h, hi, h), (h, hi, h), (h, hi, -h)]),
             ((0, -1, 0), [(-h, lo, -h), (h, lo, -h), (h, lo, h), (-h, lo, h)]),
             ((1, 0, 0), [(h, lo, -h), (h, hi, -h), (h, hi, h), (h, lo, h)]),
             ((-1, 0, 0), [(-h, lo, -h), (-h, lo, h), (-h, hi, h), (-h, hi, -h)]),
             ((0, 0, 1), [(-h, lo, h), (h, lo, h), (h, hi, h), (-h, hi, h)]),
             ((0, 0, -1), [(-h, lo, -h), (-h, hi, -h), (h, hi, -h), (h, lo, -h)])]
    lines.append('o blocker')
    for k, (nrm, quad) in enumerate(faces):
        for v in quad:
            lines.append('v %g %g %g' % v)
        lines.append('vn %d %d %d' % nrm)
        v0 = base + 4 * k + 1
        ni = 2 + k
        lines.append('f %d//%d %d//%d %d//%d' % (v0, ni, v0 + 1, ni, v0 + 2, ni))
        lines.append('f %d//%d %d//%d %d//%d' % (v0, ni, v0 + 2, ni, v0 + 3, ni))
    with open(os.path.join(d, 'scene.obj'), 'w') as f:
        f.write('\n'.join(lines) + '\n')
    with open(os.path.join(d, 'geometry.json'), 'w') as f:
        json.dump({'cells': n, 'plane': PLANE, 'half': HALF, 'y_bottom': Y_BOTTOM, 'y_top': Y_TOP}, f)


def write_disc_env(path, cone_deg):
    """A lat-long PFM (rows bottom-up on disk), the zenith disc of angular diameter cone_deg."""
    h = ENV_ROWS
    w = 2 * h
    r = math.radians(cone_deg / 2)
    rows = int(round(r / math.pi * h))
    if abs(rows * math.pi / h - r) > 1e-9:
        raise SystemExit('a %g degree disc does not fill whole rows of a %d-row map' % (cone_deg, h))
    radiance = 1.0 / math.sin(r) ** 2     # irradiance pi on the open plane
    lit = struct.pack('<3f', radiance, radiance, radiance) * w
    dark = struct.pack('<3f', 0, 0, 0) * w
    with open(path, 'wb') as f:
        f.write(b'PF\n%d %d\n-1.0\n' % (w, h))
        for y in range(h - 1, -1, -1):        # PFM rows run bottom-up; map row 0 is the zenith
            f.write(lit if y < rows else dark)


# ---------------------------------------------------------------- exact shadow

def exact_point(x, z):
    return 0.0 if abs(x) < HALF and abs(z) < HALF else 1.0


def exact_disc(x, z, cone_deg, steps=720):
    """Exit radiance (albedo 1, open plane 1) under the zenith disc: per azimuth the blocked
    polar angles are one interval (the box is convex), and cos(t) sin(t) integrates in closed form."""
    r = math.radians(cone_deg / 2)
    s2r = math.sin(r) ** 2
    reach = Y_BOTTOM * math.tan(r)
    if max(abs(x) - HALF, abs(z) - HALF) > reach:
        return 1.0
    blocked = 0.0
    for k in range(steps):
        phi = 2 * math.pi * (k + 0.5) / steps
        ux, uz = math.cos(phi), math.sin(phi)
        t0, t1 = 0.0, math.inf           # the horizontal ray x + t u through the square |x|, |z| < HALF
        empty = False
        for p, u in ((x, ux), (z, uz)):
            if abs(u) < 1e-15:
                if abs(p) >= HALF:
                    empty = True
                continue
            a, b = (-HALF - p) / u, (HALF - p) / u
            if a > b:
                a, b = b, a
            t0, t1 = max(t0, a), min(t1, b)
        if empty or t0 >= t1:
            continue
        ta = math.atan(t0 / Y_TOP)
        if ta >= r:
            continue
        tb = min(math.atan(t1 / Y_BOTTOM), r)
        blocked += (math.sin(tb) ** 2 - math.sin(ta) ** 2) / 2
    return 1.0 - blocked * (2 * math.pi / steps) / (math.pi * s2r)


def exact_grid(xs, zs, size):
    memo = {}
    out = []
    for x, z in zip(xs, zs):
        key = (round(min(abs(x), abs(z)), 6), round(max(abs(x), abs(z)), 6))   # 8-fold symmetry
        if key not in memo:
            memo[key] = exact_point(key[0], key[1]) if size == 0 else exact_disc(key[0], key[1], size)
        out.append(memo[key])
    return out


# ---------------------------------------------------------------- prt's outputs

def read_ply_positions(path):
    with open(path, 'rb') as f:
        data = f.read()
    end = data.index(b'end_header\n') + len(b'end_header\n')
    header = data[:end].decode().split('\n')
    if 'format binary_little_endian 1.0' not in header:
        raise SystemExit('%s: expected a binary little-endian PLY' % path)
    count, props = 0, []
    in_vertex = False
    for line in header:
        w = line.split()
        if w[:2] == ['element', 'vertex']:
            count, in_vertex = int(w[2]), True
        elif w[:1] == ['element']:
            in_vertex = False
        elif w[:1] == ['property'] and in_vertex:
            if w[1] != 'float':
                raise SystemExit('%s: vertex property %s is not a float' % (path, w[2]))
            props.append(w[2])
    stride = 4 * len(props)
    ix, iy, iz = props.index('x'), props.index('y'), props.index('z')
    pos = []
    for v in range(count):
        vals = struct.unpack_from('<%df' % len(props), data, end + v * stride)
        pos.append((vals[ix], vals[iy], vals[iz]))
    return pos


def read_radiance(path):
    with open(path) as f:
        return [c[0] for c in json.load(f)['radiance']]


# ---------------------------------------------------------------- measures

def rel_l2(vals, ref):
    num = sum((a - b) ** 2 for a, b in zip(vals, ref))
    den = sum(b * b for b in ref)
    return math.sqrt(num / den)


def penumbra_width(xs, vals):
    """10-90% width of the shadow's edge on x >= 0 of the centre line, between the profile's
    minimum and its value at the plane's edge, found walking in from the edge."""
    pts = sorted((x, v) for x, v in zip(xs, vals) if x >= -1e-9)
    lo, hi = min(v for _, v in pts), pts[-1][1]
    if hi - lo < 1e-6:
        return float('nan')

    def crossing(level):
        for k in range(len(pts) - 1, 0, -1):
            (x0, v0), (x1, v1) = pts[k - 1], pts[k]
            if v0 < level <= v1:
                return x0 + (level - v0) / (v1 - v0) * (x1 - x0)
        return pts[0][0]
    return crossing(lo + 0.9 * (hi - lo)) - crossing(lo + 0.1 * (hi - lo))


# ---------------------------------------------------------------- PNG

FONT = {   # 5 x 7, rows top down, for the panel labels
    'A': '01110 10001 10001 11111 10001 10001 10001', 'C': '01110 10001 10000 10000 10000 10001 01110',
    'D': '11110 10001 10001 10001 10001 10001 11110', 'E': '11111 10000 10000 11110 10000 10000 11111',
    'G': '01110 10001 10000 10111 10001 10001 01111', 'H': '10001 10001 10001 11111 10001 10001 10001',
    'I': '01110 00100 00100 00100 00100 00100 01110', 'L': '10000 10000 10000 10000 10000 10000 11111',
    'N': '10001 11001 10101 10011 10001 10001 10001', 'O': '01110 10001 10001 10001 10001 10001 01110',
    'P': '11110 10001 10001 11110 10000 10000 10000', 'R': '11110 10001 10001 11110 10100 10010 10001',
    'S': '01111 10000 10000 01110 00001 00001 11110', 'T': '11111 00100 00100 00100 00100 00100 00100',
    'V': '10001 10001 10001 10001 10001 01010 00100', 'W': '10001 10001 10001 10101 10101 10101 01010',
    'X': '10001 10001 01010 00100 01010 10001 10001', '0': '01110 10001 10011 10101 11001 10001 01110',
    '1': '00100 01100 00100 00100 00100 00100 01110', '2': '01110 10001 00001 00010 00100 01000 11111',
    '3': '11110 00001 00001 01110 00001 00001 11110', '4': '00010 00110 01010 10010 11111 00010 00010',
    '5': '11111 10000 11110 00001 00001 10001 01110', '6': '00110 01000 10000 11110 10001 10001 01110',
    '7': '11111 00001 00010 00100 01000 01000 01000', '8': '01110 10001 10001 01110 10001 10001 01110',
    '9': '01110 10001 10001 01111 00001 00010 01100', ' ': '00000 00000 00000 00000 00000 00000 00000',
    '.': '00000 00000 00000 00000 00000 01100 01100', '-': '00000 00000 00000 11111 00000 00000 00000',
    '=': '00000 00000 11111 00000 11111 00000 00000', ';': '00000 01100 01100 00000 01100 00100 01000',
    ':': '00000 01100 01100 00000 01100 01100 00000', 'B': '11110 10001 10001 11110 10001 10001 11110',
    'F': '11111 10000 10000 11110 10000 10000 10000', 'K': '10001 10010 10100 11000 10100 10010 10001',
    'M': '10001 11011 10101 10101 10001 10001 10001', 'U': '10001 10001 10001 10001 10001 10001 01110',
    'Y': '10001 10001 01010 00100 00100 00100 00100', 'Z': '11111 00001 00010 00100 01000 10000 11111',
}


def srgb(v):
    v = min(max(v, 0.0), 1.0)
    v = 12.92 * v if v <= 0.0031308 else 1.055 * v ** (1 / 2.4) - 0.055
    return int(round(255 * v))


class Canvas:
    def __init__(self, w, h, bg=(255, 255, 255)):
        self.w, self.h = w, h
        self.px = [list(bg) * w for _ in range(h)]

    def put(self, x, y, rgb):
        if 0 <= x < self.w and 0 <= y < self.h:
            self.px[y][3 * x:3 * x + 3] = rgb

    def text(self, x, y, s, scale=2, rgb=(0, 0, 0)):
        for ch in s.upper():
            rows = FONT.get(ch, FONT[' ']).split()
            for r, row in enumerate(rows):
                for c, bit in enumerate(row):
                    if bit == '1':
                        for dy in range(scale):
                            for dx in range(scale):
                                self.put(x + c * scale + dx, y + r * scale + dy, rgb)
            x += 6 * scale

    def save(self, path):
        raw = b''.join(b'\x00' + bytes(row) for row in self.px)

        def chunk(kind, body):
            return struct.pack('>I', len(body)) + kind + body + struct.pack('>I', zlib.crc32(kind + body))
        with open(path, 'wb') as f:
            f.write(b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', self.w, self.h, 8, 2, 0, 0, 0))
                    + chunk(b'IDAT', zlib.compress(raw, 9)) + chunk(b'IEND', b''))


def draw_panel(cv, ox, oy, size, grid, n):
    """The plane's radiance over [-VIEW, VIEW]^2 seen from above (x right, z down), bilinear
    between the vertices, negative values (SH ringing) in blue, the blocker's outline dotted red."""
    for py in range(size):
        z = -VIEW + 2 * VIEW * (py + 0.5) / size
        for px in range(size):
            x = -VIEW + 2 * VIEW * (px + 0.5) / size
            fi, fj = (x + PLANE) / (2 * PLANE) * n, (z + PLANE) / (2 * PLANE) * n
            i, j = min(int(fi), n - 1), min(int(fj), n - 1)
            u, v = fi - i, fj - j
            val = ((1 - u) * (1 - v) * grid[j][i] + u * (1 - v) * grid[j][i + 1]
                   + (1 - u) * v * grid[j + 1][i] + u * v * grid[j + 1][i + 1])
            if val < 0:
                rgb = (0, 0, srgb(-val))
            else:
                k = srgb(val)
                rgb = (k, k, k)
            cv.put(ox + px, oy + py, rgb)
    edge = [int(round((c + VIEW) / (2 * VIEW) * size)) for c in (-HALF, HALF)]
    for t in range(edge[0], edge[1] + 1, 4):
        for a, b in ((t, edge[0]), (t, edge[1]), (edge[0], t), (edge[1], t)):
            cv.put(ox + a, oy + b, (220, 40, 40))


# ---------------------------------------------------------------- profile plot

def profile_plot(sizes, profiles, orders_shown):
    """The centre-line profiles as drawing primitives, for write_svg and draw_png."""
    w, h, pad = 300, 230, 40
    colours = ['#c6dbef', '#9ecae1', '#6baed6', '#3182bd', '#08519c', '#08306b']
    prims = []
    for k, size in enumerate(sizes):
        ox, oy = pad + k * (w + pad), pad
        xs, curves = profiles[size]

        def X(x, ox=ox):
            return ox + (x + VIEW) / (2 * VIEW) * w

        def Y(v, oy=oy):
            return oy + h - (v + 0.4) / 1.6 * h
        prims.append(('rect', ox, oy, w, h, '#888888'))
        for v in (0, 0.5, 1):
            prims.append(('line', ox, Y(v), ox + w, Y(v), '#dddddd', 1, False))
            prims.append(('text', ox - 4, Y(v) + 4, '%g' % v, 'end'))
        for x in (-0.5, 0, 0.5):
            prims.append(('text', X(x), oy + h + 14, '%g' % x, 'middle'))
        for x in (-HALF, HALF):
            prims.append(('line', X(x), oy, X(x), oy + h, '#dd3333', 1, True))
        prims.append(('text', ox + w / 2, oy - 10, 'point light' if size == 0 else '%g degree source' % size, 'middle'))
        keep = [i for i, x in enumerate(xs) if abs(x) <= VIEW + 1e-9]
        series = [(curves['sh%d' % o], colours[m % len(colours)], 1, False) for m, o in enumerate(orders_shown)]
        series += [(curves['wavelet'], '#d62728', 2, True), (curves['exact'], '#000000', 2, False)]
        for vals, col, sw, dash in series:
            prims.append(('poly', [(X(xs[i]), Y(max(min(vals[i], 1.2), -0.4))) for i in keep], col, sw, dash))
    ly = h + 2 * pad + 10
    legend = [('SH %d' % o, colours[m % len(colours)]) for m, o in enumerate(orders_shown)]
    legend += [('wavelet', '#d62728'), ('exact', '#000000')]
    for m, (name, col) in enumerate(legend):
        lx = pad + m * 80
        prims.append(('line', lx, ly, lx + 20, ly, col, 2, False))
        prims.append(('text', lx + 24, ly + 4, name, 'start'))
    prims.append(('text', pad, ly + 24, 'exit radiance along the centre line z = 0; red: the blocker edges', 'start'))
    return pad + len(sizes) * (w + pad), ly + 36, prims


def write_svg(path, width, height, prims):
    out = ['<svg xmlns="http://www.w3.org/2000/svg" width="%d" height="%d" font-family="sans-serif" font-size="11">'
           % (width, height), '<rect width="100%" height="100%" fill="white"/>']
    for p in prims:
        if p[0] == 'rect':
            out.append('<rect x="%.1f" y="%.1f" width="%.1f" height="%.1f" fill="none" stroke="%s"/>' % p[1:])
        elif p[0] == 'line':
            out.append('<line x1="%.1f" y1="%.1f" x2="%.1f" y2="%.1f" stroke="%s" stroke-width="%d"%s/>'
                       % (p[1:7] + (' stroke-dasharray="5,3"' if p[7] else '',)))
        elif p[0] == 'poly':
            out.append('<polyline points="%s" fill="none" stroke="%s" stroke-width="%d"%s/>'
                       % (' '.join('%.1f,%.1f' % q for q in p[1]), p[2], p[3], ' stroke-dasharray="5,3"' if p[4] else ''))
        else:
            out.append('<text x="%.1f" y="%.1f" text-anchor="%s">%s</text>' % (p[1], p[2], p[4], p[3]))
    out.append('</svg>')
    with open(path, 'w') as f:
        f.write('\n'.join(out) + '\n')


def draw_png(path, width, height, prims):
    cv = Canvas(width, height)

    def rgb(col):
        return tuple(int(col[i:i + 2], 16) for i in (1, 3, 5))

    def segment(x0, y0, x1, y1, col, sw, dash, phase=0.0):
        n = max(int(max(abs(x1 - x0), abs(y1 - y0)) * 2), 1)
        for t in range(n + 1):
            x, y = x0 + (x1 - x0) * t / n, y0 + (y1 - y0) * t / n
            if dash and int((phase + t / 2) / 4) % 2:
                continue
            for d in range(sw):
                cv.put(int(round(x)), int(round(y)) + d, col)
        return phase + n / 2
    for p in prims:
        if p[0] == 'rect':
            _, x, y, w, h, col = p
            for a, b, c, e in ((x, y, x + w, y), (x, y + h, x + w, y + h), (x, y, x, y + h), (x + w, y, x + w, y + h)):
                segment(a, b, c, e, rgb(col), 1, False)
        elif p[0] == 'line':
            segment(p[1], p[2], p[3], p[4], rgb(p[5]), p[6], p[7])
        elif p[0] == 'poly':
            phase = 0.0
            for (a, b), (c, e) in zip(p[1], p[1][1:]):
                phase = segment(a, b, c, e, rgb(p[2]), p[3], p[4], phase)
        else:
            _, x, y, text, anchor = p
            tw = 6 * len(text)
            x = x - tw if anchor == 'end' else x - tw / 2 if anchor == 'middle' else x
            cv.text(int(x), int(y) - 7, text, scale=1)
    cv.save(path)


# ---------------------------------------------------------------- analysis

def analyse(d, orders, sizes, figure_orders, check):
    geo = json.load(open(os.path.join(d, 'geometry.json')))
    n = geo['cells']
    pos = read_ply_positions(os.path.join(d, 'sh.ply'))
    if read_ply_positions(os.path.join(d, 'wavelet.ply')) != pos:
        raise SystemExit('the SH and wavelet bakes hold different vertices')
    # The plane's vertices on their grid (the blocker's vertices are left out).
    cell = 2 * PLANE / n
    where = {}
    for k, (x, y, z) in enumerate(pos):
        if abs(y) > 1e-6:
            continue
        i, j = round((x + PLANE) / cell), round((z + PLANE) / cell)
        if abs(i * cell - PLANE - x) < 1e-4 and abs(j * cell - PLANE - z) < 1e-4:
            where[(i, j)] = k
    if len(where) != (n + 1) ** 2:
        raise SystemExit('found %d of the plane\'s %d vertices' % (len(where), (n + 1) ** 2))
    keys = sorted(where, key=lambda ij: (ij[1], ij[0]))
    idx = [where[ij] for ij in keys]
    xs = [ij[0] * cell - PLANE for ij in keys]
    zs = [ij[1] * cell - PLANE for ij in keys]
    inside = [abs(x) <= MEASURE + 1e-9 and abs(z) <= MEASURE + 1e-9 for x, z in zip(xs, zs)]
    mid = n // 2
    line = [m for m, ij in enumerate(keys) if ij[1] == mid]
    results = {'cells': n, 'measured_region': MEASURE, 'sizes': {}}
    grids, profiles = {}, {}
    for size in sizes:
        tag = 'point' if size == 0 else '%g' % size
        exact = exact_grid(xs, zs, size)
        methods = {'sh%d' % o: read_radiance(os.path.join(d, 'sh_%s_o%d.json' % (tag, o))) for o in orders}
        methods['wavelet'] = read_radiance(os.path.join(d, 'wavelet_%s.json' % tag))
        row = {}
        for name, vals in list(methods.items()) + [('exact', None)]:
            v = exact if vals is None else [vals[k] for k in idx]
            entry = {'penumbra': penumbra_width([xs[m] for m in line], [v[m] for m in line])}
            if vals is not None:
                entry['rel_l2'] = rel_l2([a for a, s in zip(v, inside) if s], [b for b, s in zip(exact, inside) if s])
                entry['min'] = min(v)
            row[name] = entry
            grids[(size, name)] = [v[j * (n + 1):(j + 1) * (n + 1)] for j in range(n + 1)]
        ref_path = os.path.join(d, 'reference_%s.json' % tag)
        if os.path.exists(ref_path):
            # The path tracer's direct light (the blocker's underside bounces a little light
            # back, which the shadowed transfer leaves out) against the analytic answer: a
            # check of the scene, the probe and the exact shadow, good to its noise.
            ref = json.load(open(ref_path))
            direct = [ref['direct'][k][0] for k in idx]
            se = [ref['std_error'][k][0] for k in idx]
            sel = [m for m, s in enumerate(inside) if s]
            chi2 = sum((direct[m] - exact[m]) ** 2 / (se[m] ** 2 + 1e-12) for m in sel) / len(sel)
            row['reference'] = {'rel_l2': rel_l2([direct[m] for m in sel], [exact[m] for m in sel]), 'chi2': chi2}
        results['sizes'][tag] = row
        profiles[size] = ([xs[m] for m in line],
                          {name: [g[mid][i] for i in range(n + 1)] for (s, name), g in grids.items() if s == size})
    with open(os.path.join(d, 'results.json'), 'w') as f:
        json.dump(results, f, indent=1)

    # The table (markdown).
    head = ['light'] + ['SH %d' % o for o in orders] + ['wavelet']
    has_ref = all('reference' in results['sizes'][t] for t in results['sizes'])
    print('relative L2 of the exit radiance on the plane (|x|, |z| <= %g) against the exact shadow:' % MEASURE)
    print('| ' + ' | '.join(head + (['path tracer (direct)'] if has_ref else [])) + ' |')
    print('| --- |' + ' ---: |' * (len(head) - 1 + has_ref))
    for size in sizes:
        tag = 'point' if size == 0 else '%g' % size
        r = results['sizes'][tag]
        print('| %s | ' % ('point' if size == 0 else '%g deg' % size)
              + ' | '.join('%.3f' % r[k]['rel_l2'] for k in ['sh%d' % o for o in orders] + ['wavelet'])
              + (' | %.4f' % r['reference']['rel_l2'] if has_ref else '') + ' |')
    print()
    print('10-90%% penumbra width on the centre line (scene units; vertex spacing %.4f):' % cell)
    print('| ' + ' | '.join(head + ['exact']) + ' |')
    print('| --- |' + ' ---: |' * len(head))
    for size in sizes:
        tag = 'point' if size == 0 else '%g' % size
        r = results['sizes'][tag]
        print('| %s | ' % ('point' if size == 0 else '%g deg' % size)
              + ' | '.join('%.3f' % r[k]['penumbra'] for k in ['sh%d' % o for o in orders] + ['wavelet', 'exact']) + ' |')

    if figure_orders:
        panel, gap, left, top = 150, 6, 100, 30
        cols = ['sh%d' % o for o in figure_orders] + ['wavelet', 'exact']
        cv = Canvas(left + len(cols) * (panel + gap), top + len(sizes) * (panel + gap))
        for c, name in enumerate(cols):
            label = name.upper().replace('SH', 'SH ') if name.startswith('sh') else name
            cv.text(left + c * (panel + gap) + 4, 8, label)
        for r, size in enumerate(sizes):
            cv.text(6, top + r * (panel + gap) + panel // 2 - 7, 'POINT' if size == 0 else '%g DEG' % size)
            for c, name in enumerate(cols):
                draw_panel(cv, left + c * (panel + gap), top + r * (panel + gap), panel, grids[(size, name)], n)
        cv.save(os.path.join(d, 'sh_quality.png'))
        plot = profile_plot(sizes, profiles, [o for o in figure_orders if o in orders])
        write_svg(os.path.join(d, 'sh_quality_profile.svg'), *plot)
        draw_png(os.path.join(d, 'sh_quality_profile.png'), *plot)

    if check:
        failures = []
        big = max(s for s in sizes)
        r = results['sizes']['%g' % big]
        errs = [r['sh%d' % o]['rel_l2'] for o in orders]
        if not all(b < a for a, b in zip(errs, errs[1:])):
            failures.append('SH error does not fall with order for the %g degree source: %s' % (big, errs))
        low = min(orders)
        for size in sizes:
            if size >= big:
                continue
            tag = 'point' if size == 0 else '%g' % size
            r = results['sizes'][tag]
            if not r['wavelet']['rel_l2'] < r['sh%d' % low]['rel_l2']:
                failures.append('wavelet (%.3f) does not beat SH order %d (%.3f) for the %s source'
                                % (r['wavelet']['rel_l2'], low, r['sh%d' % low]['rel_l2'], tag))
            if not r['wavelet']['penumbra'] < r['sh%d' % low]['penumbra']:
                failures.append('wavelet penumbra (%.3f) is not narrower than SH order %d (%.3f) for the %s source'
                                % (r['wavelet']['penumbra'], low, r['sh%d' % low]['penumbra'], tag))
        for tag, r in results['sizes'].items():
            if 'reference' in r and not (r['reference']['chi2'] < 2 and r['reference']['rel_l2'] < 0.05):
                failures.append('the path tracer disagrees with the exact shadow for the %s source: '
                                'relative L2 %.4f, mean squared error over its variance %.2f'
                                % (tag, r['reference']['rel_l2'], r['reference']['chi2']))
        for f in failures:
            print('FAIL: ' + f, file=sys.stderr)
        if failures:
            sys.exit(1)


def main(argv):
    if len(argv) < 3 or argv[1] not in ('scene', 'env', 'analyse'):
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    opts = {'--cells': '96', '--orders': '2,3,4,5,6,7,8,9,10', '--sizes': '0,20,40', '--figure-orders': ''}
    flags = set()
    rest = argv[3:]
    while rest:
        a = rest.pop(0)
        if a == '--check':
            flags.add(a)
        elif a in opts and rest:
            opts[a] = rest.pop(0)
        else:
            print('unknown option %s' % a, file=sys.stderr)
            sys.exit(2)
    d = argv[2]
    if argv[1] == 'scene':
        write_scene(d, int(opts['--cells']))
        for s in parse_sizes(opts['--sizes']):
            if s > 0:
                write_disc_env(os.path.join(d, 'disc%g.pfm' % s), s)
    else:
        fig = [int(o) for o in opts['--figure-orders'].split(',')] if opts['--figure-orders'] else []
        analyse(d, [int(o) for o in opts['--orders'].split(',')], parse_sizes(opts['--sizes']), fig, '--check' in flags)


if __name__ == '__main__':
    main(sys.argv)
