// prt export --web, wavelet files (method.js): the lighting built as methods/wavelet/lighting.c
// builds it - the environment over a 6 x 64 x 64 cube, rotated with exact areas as
// light/env_cube.c rotates it (each 2 x 2 block of its fine cube shared among the texels the
// rotated block covers), directional lights as deltas, each face Haar-transformed, the largest
// coefficients kept and quantized to 16 bits - then each vertex's sparse transport dotted with it
// (relight.c), times albedo / pi on Lambertian vertices; glossy ones meet the separable BRDF's view
// maps per pixel (render/draw.c's FS_S). Hash parameters: rotate=YAW[,PITCH[,ROLL]]
// (degrees), intensity=S, light-coefficients=N.
'use strict';
PRT.method(function (api) {
    var p = api.meta, FACE = 64, DIM = 6 * FACE * FACE, Q = 128, nv = api.vertexCount, n = p.coefficients;
    var AX = [];
    for (var f = 0; f < 6; ++f) AX.push([p.axes.slice(f * 9, f * 9 + 3), p.axes.slice(f * 9 + 3, f * 9 + 6), p.axes.slice(f * 9 + 6, f * 9 + 9)]);
    var omega = api.array('omega'), quads = p.environment ? api.array('quads') : null;
    var termCount = api.array('term_count'), index = api.array('index'), values = api.array('values'), scale = api.array('scale');
    var albedo = api.array('albedo');
    var vecStart = new Uint32Array(nv + 1);
    for (var v = 0; v < nv; ++v) vecStart[v + 1] = vecStart[v] + termCount[v];
    var state = {rotate: p.rotate.slice(), intensity: p.intensity, coefficients: p.light_coefficients};
    var radiance = new Float32Array(nv * 3);

    // ---- core/cubemap.h ----
    function cubeFace(d) {
        var x = d[0], y = d[1], z = d[2], ax = Math.abs(x), ay = Math.abs(y), az = Math.abs(z), r;
        if (ax >= ay && ax >= az) { r = 1 / x; return [x >= 0 ? 0 : 1, -z * r, y * Math.abs(r)]; }
        if (ay >= az) { r = 1 / y; return [y >= 0 ? 2 : 3, x * Math.abs(r), -z * r]; }
        r = 1 / z;
        return [z >= 0 ? 4 : 5, x * r, y * Math.abs(r)];
    }
    function cornerOf(d, size) { var c = cubeFace(d); return {u: (c[1] + 1) * 0.5 * size, v: (c[2] + 1) * 0.5 * size, face: c[0]}; }

    // ---- light/env_cube.c: exact-area deposits ----
    function clipHalf(inp, axis, c, sign) {
        var out = [], m = inp.length;
        for (var i = 0; i < m; ++i) {
            var P = inp[i], R = inp[i + 1 < m ? i + 1 : 0];
            var dp = sign * ((axis ? P.y : P.x) - c), dq = sign * ((axis ? R.y : R.x) - c);
            if (dp >= 0) out.push(P);
            if ((dp >= 0) !== (dq >= 0)) { var t = dp / (dp - dq); out.push({x: P.x + t * (R.x - P.x), y: P.y + t * (R.y - P.y)}); }
        }
        return out;
    }
    function moments(poly) {
        var ox = poly[0].x, oy = poly[0].y, s = 0, mx = 0, my = 0;
        for (var i = 1; i + 1 < poly.length; ++i) {
            var ax = poly[i].x - ox, ay = poly[i].y - oy, bx = poly[i + 1].x - ox, by = poly[i + 1].y - oy, c = ax * by - bx * ay;
            s += c; mx += (ax + bx) * c; my += (ay + by) * c;
        }
        return [s, mx, my];
    }
    function polyWeight(poly, size) {
        var m = moments(poly), s = m[0];
        if (s === 0) return 0;
        var k = 2 / size, ca = (poly[0].x + m[1] / (3 * s)) * k - 1, cb = (poly[0].y + m[2] / (3 * s)) * k - 1, r2 = 1 + ca * ca + cb * cb;
        return 0.5 * Math.abs(s) / (r2 * Math.sqrt(r2));
    }
    function polyWeightLin(poly, xr, yr, gx, gy) {
        var m = moments(poly), s = m[0];
        var w = 0.5 * s * (1 + gx * (poly[0].x - xr) + gy * (poly[0].y - yr)) + (gx * m[1] + gy * m[2]) / 6;
        return s < 0 ? -w : w;
    }
    function quadCells(q, size, out, g) {
        var x0 = q[0].x, x1 = x0, y0 = q[0].y, y1 = y0;
        for (var k = 1; k < 4; ++k) { x0 = Math.min(x0, q[k].x); x1 = Math.max(x1, q[k].x); y0 = Math.min(y0, q[k].y); y1 = Math.max(y1, q[k].y); }
        var cx0 = Math.max(Math.floor(x0), 0), cx1 = Math.min(Math.floor(x1), size - 1), cy0 = Math.max(Math.floor(y0), 0), cy1 = Math.min(Math.floor(y1), size - 1);
        var base = g * size * size;
        if (cx0 === cx1 && cy0 === cy1 && x0 >= cx0 && x1 <= cx0 + 1 && y0 >= cy0 && y1 <= cy0 + 1) { out(base + cy0 * size + cx0, polyWeight(q, size)); return; }
        for (var cx = cx0; cx <= cx1; ++cx) {
            var col = clipHalf(clipHalf(q, 0, cx, 1), 0, cx + 1, -1);
            if (col.length < 3) continue;
            for (var cy = cy0; cy <= cy1; ++cy) {
                var c = clipHalf(clipHalf(col, 1, cy, 1), 1, cy + 1, -1);
                if (c.length >= 3) out(base + cy * size + cx, polyWeight(c, size));
            }
        }
    }
    function quadOnFace(d, g, size) {
        var ax = AX[g], q = [];
        for (var k = 0; k < 4; ++k) {
            var m = d[k][0] * ax[0][0] + d[k][1] * ax[0][1] + d[k][2] * ax[0][2];
            if (m <= 1e-3) return null;
            q.push({x: ((d[k][0] * ax[1][0] + d[k][1] * ax[1][1] + d[k][2] * ax[1][2]) / m + 1) * 0.5 * size,
                    y: ((d[k][0] * ax[2][0] + d[k][1] * ax[2][1] + d[k][2] * ax[2][2]) / m + 1) * 0.5 * size});
        }
        return q;
    }
    function triSolidAngle(a, b, c) {
        var det = a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0]);
        var ab = a[0] * b[0] + a[1] * b[1] + a[2] * b[2], bc = b[0] * c[0] + b[1] * c[1] + b[2] * c[2], ca = c[0] * a[0] + c[1] * a[1] + c[2] * a[2];
        return 2 * Math.atan2(Math.abs(det), 1 + ab + bc + ca);
    }
    function unit(a) { var l = Math.hypot(a[0], a[1], a[2]); return [a[0] / l, a[1] / l, a[2] / l]; }
    // val shared among the texels of the size x size cube acc by the area the quad d (unit
    // corners) covers of each; wide quads or quads reaching behind a face are split in four.
    function deposit(acc, size, d, val, depth) {
        var faces = 0, split = false, k;
        for (k = 0; k < 4; ++k) {
            faces |= 1 << cubeFace(d[k])[0];
            var e = d[(k + 2) & 3];
            split = split || d[k][0] * e[0] + d[k][1] * e[1] + d[k][2] * e[2] < 0.98;
        }
        var q = [], use = 0;
        for (var g = 0; g < 6 && !split; ++g) {
            q[g] = quadOnFace(d, g, size);
            if (q[g]) use |= 1 << g;
            else split = (faces >> g & 1) === 1;
        }
        if (split && depth < 8) {
            var mid = [d[0], null, d[1], null, null, null, d[3], null, d[2]], i;
            var add = function (a, b) { return [a[0] + b[0], a[1] + b[1], a[2] + b[2]]; };
            mid[1] = unit(add(d[0], d[1])); mid[5] = unit(add(d[1], d[2])); mid[7] = unit(add(d[2], d[3])); mid[3] = unit(add(d[3], d[0]));
            mid[4] = unit(add(add(d[0], d[1]), add(d[2], d[3])));
            var sub = [[0, 1, 4, 3], [1, 2, 5, 4], [4, 5, 8, 7], [3, 4, 7, 6]], parts = [], total = 0, sd = [];
            for (var s = 0; s < 4; ++s) {
                sd[s] = sub[s].map(function (j) { return mid[j]; });
                parts[s] = triSolidAngle(sd[s][0], sd[s][1], sd[s][2]) + triSolidAngle(sd[s][0], sd[s][2], sd[s][3]);
                total += parts[s];
            }
            for (s = 0; s < 4; ++s) {
                var vs = [];
                for (i = 0; i < 3; ++i) vs[i] = total > 0 ? val[i] * parts[s] / total : 0.25 * val[i];
                deposit(acc, size, sd[s], vs, depth + 1);
            }
            return;
        }
        var area = 0;
        for (g = 0; g < 6; ++g)
            if (use >> g & 1) quadCells(q[g], size, function (cell, a) { area += a; }, g);
        if (!(area > 0)) return;
        for (g = 0; g < 6; ++g)
            if (use >> g & 1)
                quadCells(q[g], size, function (cell, a) { for (var c = 0; c < 3; ++c) acc[cell * 3 + c] += a / area * val[c]; }, g);
    }
    function depositFast(acc, size, d0, d1, d2, d3, c, val) {
        var f = c[0].face, ch;
        if (c[1].face === f && c[2].face === f && c[3].face === f) {
            var x0 = Math.min(c[0].u, c[1].u, c[2].u, c[3].u), x1 = Math.max(c[0].u, c[1].u, c[2].u, c[3].u);
            var y0 = Math.min(c[0].v, c[1].v, c[2].v, c[3].v), y1 = Math.max(c[0].v, c[1].v, c[2].v, c[3].v);
            var cx0 = Math.max(Math.floor(x0), 0), cx1 = Math.min(Math.floor(x1), size - 1), cy0 = Math.max(Math.floor(y0), 0), cy1 = Math.min(Math.floor(y1), size - 1);
            var base = f * size * size;
            if (cx0 === cx1 && cy0 === cy1) {
                var o = (base + cy0 * size + cx0) * 3;
                for (ch = 0; ch < 3; ++ch) acc[o + ch] += val[ch];
                return;
            }
            if (cx1 - cx0 <= 2 && cy1 - cy0 <= 2) {
                var q = [{x: c[0].u, y: c[0].v}, {x: c[1].u, y: c[1].v}, {x: c[2].u, y: c[2].v}, {x: c[3].u, y: c[3].v}];
                var kt = 2 / size, ra = c[0].u * kt - 1, rb = c[0].v * kt - 1, ff = -3 * kt / (1 + ra * ra + rb * rb), gx = ff * ra, gy = ff * rb;
                var areas = [], cells = [], total = 0;
                for (var cx = cx0; cx <= cx1; ++cx) {
                    var col = q;
                    if (cx > cx0) col = clipHalf(col, 0, cx, 1);
                    if (cx < cx1) col = clipHalf(col, 0, cx + 1, -1);
                    for (var cy = cy0; cy <= cy1 && col.length >= 3; ++cy) {
                        var poly = col;
                        if (cy > cy0) poly = clipHalf(poly, 1, cy, 1);
                        if (cy < cy1) poly = clipHalf(poly, 1, cy + 1, -1);
                        if (poly.length < 3) continue;
                        var a = polyWeightLin(poly, c[0].u, c[0].v, gx, gy);
                        areas.push(a);
                        total += a;
                        cells.push(cy * size + cx);
                    }
                }
                if (total > 0)
                    for (var i = 0; i < cells.length; ++i)
                        for (ch = 0; ch < 3; ++ch) acc[(base + cells[i]) * 3 + ch] += areas[i] / total * val[ch];
                return;
            }
        }
        deposit(acc, size, [unit(d0), unit(d1), unit(d2), unit(d3)], val, 0);
    }
    var perFace = new Float32Array(6 * DIM * 3), sum = new Float32Array(DIM * 3);
    // The environment's energy over the lighting cube under rotation R (prt__env_cube).
    function energy(R) {
        var identity = R[0] === 1 && R[4] === 1 && R[8] === 1 && !R[1] && !R[2] && !R[3] && !R[5] && !R[6] && !R[7], t, c;
        if (identity) {
            for (t = 0; t < DIM; ++t) {
                var face = Math.floor(t / (FACE * FACE)), y = Math.floor(t / FACE) % FACE, x = t % FACE;
                for (c = 0; c < 3; ++c) {
                    var e = 0;
                    for (var sy = 0; sy < 2; ++sy)
                        for (var sx = 0; sx < 2; ++sx) e += quads[((face * Q + 2 * y + sy) * Q + 2 * x + sx) * 3 + c];
                    sum[t * 3 + c] = e;
                }
            }
            return sum;
        }
        perFace.fill(0);
        var HALF = Q;
        for (var f = 0; f < 6; ++f) {
            var axis = AX[f][0], right = AX[f][1], up = AX[f][2], ra = [], rr = [], ru = [];
            for (var i = 0; i < 3; ++i) {
                ra[i] = R[3 * i] * axis[0] + R[3 * i + 1] * axis[1] + R[3 * i + 2] * axis[2];
                rr[i] = R[3 * i] * right[0] + R[3 * i + 1] * right[1] + R[3 * i + 2] * right[2];
                ru[i] = R[3 * i] * up[0] + R[3 * i + 1] * up[1] + R[3 * i + 2] * up[2];
            }
            var acc = perFace.subarray(f * DIM * 3, (f + 1) * DIM * 3), edge = [[], []], cn = [[], []];
            for (var yy = 0; yy < HALF; ++yy) {
                for (var r = 0; r < 2; ++r) {
                    var b = 2 * (yy + r) / HALF - 1;
                    for (var xx = 0; xx <= HALF; ++xx) {
                        var a = 2 * xx / HALF - 1, d = [ra[0] + a * rr[0] + b * ru[0], ra[1] + a * rr[1] + b * ru[1], ra[2] + a * rr[2] + b * ru[2]];
                        edge[r][xx] = d;
                        cn[r][xx] = cornerOf(d, FACE);
                    }
                }
                for (xx = 0; xx < HALF; ++xx) {
                    var at = ((f * Q + yy) * Q + xx) * 3, val = [quads[at], quads[at + 1], quads[at + 2]];
                    if (!val[0] && !val[1] && !val[2]) continue;
                    depositFast(acc, FACE, edge[0][xx], edge[0][xx + 1], edge[1][xx + 1], edge[1][xx], [cn[0][xx], cn[0][xx + 1], cn[1][xx + 1], cn[1][xx]], val);
                }
            }
        }
        for (t = 0; t < DIM * 3; ++t) {
            var s = 0;
            for (var g = 0; g < 6; ++g) s += perFace[g * DIM * 3 + t];
            sum[t] = s;
        }
        return sum;
    }

    // ---- core/haar.c ----
    var haarOut = new Float32Array(FACE * FACE);
    function haar(img) {
        for (var s = FACE; s >= 2; s >>= 1) {
            var h = s / 2;
            for (var y = 0; y < h; ++y)
                for (var x = 0; x < h; ++x) {
                    var a = img[2 * y * FACE + 2 * x], b = img[2 * y * FACE + 2 * x + 1], c = img[(2 * y + 1) * FACE + 2 * x], d = img[(2 * y + 1) * FACE + 2 * x + 1];
                    haarOut[y * s + x] = 0.5 * (a + b + c + d);
                    haarOut[y * s + h + x] = 0.5 * (a - b + c - d);
                    haarOut[(h + y) * s + x] = 0.5 * (a + b - c - d);
                    haarOut[(h + y) * s + h + x] = 0.5 * (a - b - c + d);
                }
            for (y = 0; y < s; ++y)
                for (x = 0; x < s; ++x) img[y * FACE + x] = haarOut[y * s + x];
        }
    }

    // ---- methods/wavelet/lighting.c ----
    var planes = new Float32Array(3 * DIM), mag = new Float32Array(DIM), L = new Float32Array(DIM * 4);
    function lighting() {
        var t, c, j;
        planes.fill(0);
        if (p.environment) {
            var e = energy(PRT.euler(state.rotate[0], state.rotate[1], state.rotate[2]));
            for (t = 0; t < DIM; ++t)
                for (c = 0; c < 3; ++c) planes[c * DIM + t] = Math.fround(e[t * 3 + c] / omega[t % (FACE * FACE)]) * state.intensity;
        }
        p.lights.forEach(function (l) {
            var fc = cubeFace(l.direction), x = Math.floor((fc[1] + 1) * 0.5 * FACE), y = Math.floor((fc[2] + 1) * 0.5 * FACE);
            x = x < 0 ? 0 : x >= FACE ? FACE - 1 : x;
            y = y < 0 ? 0 : y >= FACE ? FACE - 1 : y;
            var tt = (fc[0] * FACE + y) * FACE + x;
            for (var ch = 0; ch < 3; ++ch) planes[ch * DIM + tt] += l.irradiance[ch] / omega[tt % (FACE * FACE)];
        });
        for (c = 0; c < 3; ++c)
            for (var f = 0; f < 6; ++f) haar(planes.subarray(c * DIM + f * FACE * FACE, c * DIM + (f + 1) * FACE * FACE));
        for (j = 0; j < DIM; ++j) {
            var r = planes[j], g = planes[DIM + j], b = planes[2 * DIM + j];
            mag[j] = r * r + g * g + b * b;
        }
        var keep = state.coefficients, thr = -1;
        if (keep < DIM) thr = Float32Array.from(mag).sort()[DIM - keep];
        var above = 0, ties, maxabs = [0, 0, 0];
        for (j = 0; j < DIM; ++j) above += mag[j] > thr ? 1 : 0;
        ties = keep - above;
        L.fill(0);
        var kept = new Uint8Array(DIM);
        for (j = 0; j < DIM; ++j) {
            if (!(mag[j] > thr || (mag[j] === thr && ties-- > 0))) continue;
            kept[j] = 1;
            for (c = 0; c < 3; ++c) maxabs[c] = Math.max(maxabs[c], Math.abs(planes[c * DIM + j]));
        }
        for (j = 0; j < DIM; ++j) {
            if (!kept[j]) continue;
            for (c = 0; c < 3; ++c) {
                var val = planes[c * DIM + j];
                if (maxabs[c] > 0) { var s = Math.fround(maxabs[c] / 32767); val = Math.round(val / s) * s; }   // signed 16-bit, one scale per channel
                L[j * 4 + c] = val;
            }
        }
        return L;
    }

    // ---- glossy vertices: the view factor per pixel (render/draw.c's FS_S). WebGL2 has no
    // geometry shader to hand each fragment its triangle's corners, so the triangles are drawn
    // unindexed, every corner carrying the three corners' ids and its barycentric coordinates;
    // the K-vectors (rgb = g_k, a = the vertex's view-map set) and the radiance are textures. ----
    var Kt = p.terms, vertexSet = p.glossy ? api.array('vertex_set') : null, kvec = p.glossy ? new Float32Array(nv * Kt * 3) : null;
    var glossyPass = null;
    if (p.glossy) (function () {
        var gl = api.gl, idx = api.array('indices'), pos = api.array('positions'), nrm = api.array('normals'), nt = idx.length / 3;
        var P = new Float32Array(nt * 9), Nn = new Float32Array(nt * 9), B = new Float32Array(nt * 9), I = new Uint32Array(nt * 9);
        for (var t = 0; t < nt; ++t)
            for (var k = 0; k < 3; ++k) {
                var v = idx[t * 3 + k], o = (t * 3 + k) * 3;
                for (var c = 0; c < 3; ++c) { P[o + c] = pos[v * 3 + c]; Nn[o + c] = nrm[v * 3 + c]; B[o + c] = k === c ? 1 : 0; I[o + c] = idx[t * 3 + c]; }
            }
        var vao = gl.createVertexArray();
        gl.bindVertexArray(vao);
        [P, Nn, B].forEach(function (a, loc) {
            var buf = gl.createBuffer();
            gl.bindBuffer(gl.ARRAY_BUFFER, buf);
            gl.bufferData(gl.ARRAY_BUFFER, a, gl.STATIC_DRAW);
            gl.enableVertexAttribArray(loc);
            gl.vertexAttribPointer(loc, 3, gl.FLOAT, false, 0, 0);
        });
        var ibuf = gl.createBuffer();
        gl.bindBuffer(gl.ARRAY_BUFFER, ibuf);
        gl.bufferData(gl.ARRAY_BUFFER, I, gl.STATIC_DRAW);
        gl.enableVertexAttribArray(3);
        gl.vertexAttribIPointer(3, 3, gl.UNSIGNED_INT, 0, 0);
        gl.bindVertexArray(null);
        var TW = 2048;
        function dataTexture(texels) {
            var tex = gl.createTexture();
            gl.bindTexture(gl.TEXTURE_2D, tex);
            gl.texStorage2D(gl.TEXTURE_2D, 1, gl.RGBA32F, TW, Math.ceil(texels / TW));
            return {tex: tex, h: Math.ceil(texels / TW), data: new Float32Array(TW * Math.ceil(texels / TW) * 4)};
        }
        var kt = dataTexture(nv * Kt), rt = dataTexture(nv);
        // [set][term][channel][res][res] -> one RGB(A) layer per (set, term), filtered as draw.c's.
        var R = p.view_resolution, layers = p.view_sets * Kt, vm = api.array('view_maps'), rgba = new Float32Array(layers * R * R * 4);
        for (var layer = 0; layer < layers; ++layer)
            for (var i = 0; i < R * R; ++i) {
                for (c = 0; c < 3; ++c) rgba[(layer * R * R + i) * 4 + c] = vm[(layer * 3 + c) * R * R + i];
                rgba[(layer * R * R + i) * 4 + 3] = 1;
            }
        var maps = gl.createTexture();
        gl.bindTexture(gl.TEXTURE_2D_ARRAY, maps);
        gl.texStorage3D(gl.TEXTURE_2D_ARRAY, 1, api.floatLinear ? gl.RGBA32F : gl.RGBA16F, R, R, layers);
        gl.texSubImage3D(gl.TEXTURE_2D_ARRAY, 0, 0, 0, 0, R, R, layers, gl.RGBA, gl.FLOAT, rgba);
        gl.texParameteri(gl.TEXTURE_2D_ARRAY, gl.TEXTURE_MIN_FILTER, gl.LINEAR);
        gl.texParameteri(gl.TEXTURE_2D_ARRAY, gl.TEXTURE_MAG_FILTER, gl.LINEAR);
        gl.texParameteri(gl.TEXTURE_2D_ARRAY, gl.TEXTURE_WRAP_S, p.polar ? gl.REPEAT : gl.CLAMP_TO_EDGE);
        gl.texParameteri(gl.TEXTURE_2D_ARRAY, gl.TEXTURE_WRAP_T, gl.CLAMP_TO_EDGE);
        var program = api.compile('#version 300 es\n' +
            'layout(location = 0) in vec3 pos; layout(location = 1) in vec3 nrm; layout(location = 2) in vec3 bary; layout(location = 3) in uvec3 ids;\n' +
            'uniform mat4 mvp; out vec3 f_pos; out vec3 f_nrm; out vec3 f_bary; flat out ivec3 f_ids;\n' +
            'void main() { f_pos = pos; f_nrm = nrm; f_bary = bary; f_ids = ivec3(ids); gl_Position = mvp * vec4(pos, 1.0); }\n',
            '#version 300 es\nprecision highp float; precision highp int; precision highp sampler2DArray;\n' +
            'in vec3 f_pos; in vec3 f_nrm; in vec3 f_bary; flat in ivec3 f_ids;\n' +
            'uniform highp sampler2D kvec, rad; uniform sampler2DArray maps; uniform int terms, polar; uniform vec3 eye;\n' +
            'out vec4 color;\n' +
            'vec4 fetch(highp sampler2D t, int i) { return texelFetch(t, ivec2(i % ' + TW + ', i / ' + TW + '), 0); }\n' +
            'void main() {\n' +
            '  vec3 n = normalize(f_nrm);\n' +
            '  float ny1 = n.y + 1.0;\n' +
            '  vec3 s = vec3(ny1 * ny1 + n.z * n.z - n.x * n.x, -2.0 * ny1 * n.x, -2.0 * n.x * n.z);\n' +
            '  s = length(s) < 1e-6 ? vec3(1.0, 0.0, 0.0) : normalize(s);\n' +
            '  vec3 t = normalize(cross(n, s));\n' +
            '  vec3 wo = normalize(eye - f_pos);\n' +
            '  vec3 l = vec3(dot(wo, s), dot(wo, t), dot(wo, n));\n' +
            '  if (l.z < 0.02) { float r = length(l.xy); l.xy *= r > 0.0 ? sqrt(1.0 - 0.0004) / r : 0.0; l.z = 0.02; }\n' +
            '  vec2 uv = polar != 0 ? vec2(fract(atan(l.y, l.x) / 6.28318530718), sqrt(max(0.0, 1.0 - l.z))) : 0.5 * (l.xy + 1.0);\n' +
            '  vec3 acc = vec3(0.0);\n' +
            '  for (int c = 0; c < 3; ++c) {\n' +
            '    int id = f_ids[c];\n' +
            '    int set = int(fetch(kvec, id * terms).a + 0.5);\n' +
            '    if (set == 0) continue;\n' +
            '    vec3 sum = vec3(0.0);\n' +
            '    for (int k = 0; k < terms; ++k)\n' +
            '      sum += texture(maps, vec3(uv, float((set - 1) * terms + k))).rgb * fetch(kvec, id * terms + k).rgb;\n' +
            '    acc += f_bary[c] * sum;\n' +
            '  }\n' +
            '  vec3 f_rad = f_bary.x * fetch(rad, f_ids.x).rgb + f_bary.y * fetch(rad, f_ids.y).rgb + f_bary.z * fetch(rad, f_ids.z).rgb;\n' +
            '  color = vec4(max(f_rad + acc, vec3(0.0)), 1.0);\n' +
            '}\n');
        glossyPass = function (radiance) {
            for (var v = 0; v < nv; ++v) {
                for (var k = 0; k < Kt; ++k) {
                    var o = (v * Kt + k) * 4;
                    kt.data[o] = kvec[(v * Kt + k) * 3]; kt.data[o + 1] = kvec[(v * Kt + k) * 3 + 1]; kt.data[o + 2] = kvec[(v * Kt + k) * 3 + 2];
                    kt.data[o + 3] = vertexSet[v];
                }
                rt.data[v * 4] = radiance[v * 3]; rt.data[v * 4 + 1] = radiance[v * 3 + 1]; rt.data[v * 4 + 2] = radiance[v * 3 + 2];
            }
            gl.bindTexture(gl.TEXTURE_2D, kt.tex);
            gl.texSubImage2D(gl.TEXTURE_2D, 0, 0, 0, TW, kt.h, gl.RGBA, gl.FLOAT, kt.data);
            gl.bindTexture(gl.TEXTURE_2D, rt.tex);
            gl.texSubImage2D(gl.TEXTURE_2D, 0, 0, 0, TW, rt.h, gl.RGBA, gl.FLOAT, rt.data);
        };
        api.meshPass(function (mvp, eye) {
            gl.useProgram(program);
            gl.uniformMatrix4fv(gl.getUniformLocation(program, 'mvp'), false, mvp);
            gl.uniform3fv(gl.getUniformLocation(program, 'eye'), eye);
            gl.uniform1i(gl.getUniformLocation(program, 'terms'), Kt);
            gl.uniform1i(gl.getUniformLocation(program, 'polar'), p.polar ? 1 : 0);
            [kt.tex, rt.tex].forEach(function (tex, unit) {
                gl.activeTexture(gl.TEXTURE0 + unit);
                gl.bindTexture(gl.TEXTURE_2D, tex);
            });
            gl.activeTexture(gl.TEXTURE2);
            gl.bindTexture(gl.TEXTURE_2D_ARRAY, maps);
            gl.activeTexture(gl.TEXTURE0);
            gl.uniform1i(gl.getUniformLocation(program, 'kvec'), 0);
            gl.uniform1i(gl.getUniformLocation(program, 'rad'), 1);
            gl.uniform1i(gl.getUniformLocation(program, 'maps'), 2);
            gl.bindVertexArray(vao);
            gl.drawArrays(gl.TRIANGLES, 0, nt * 3);
            gl.bindVertexArray(null);
        });
    })();

    var ui = api.ui, sliders = {};
    var environment = ui.environment(state);
    sliders.coefficients = ui.slider({label: 'lighting coefficients kept', min: p.light_coefficients_min, max: p.light_coefficients_max, step: 64,
                                      value: state.coefficients, input: function (v) { state.coefficients = v; api.relight(); }});
    if (p.lights.length) ui.note(p.lights.length + ' directional light(s), fixed.');

    return {
        relight: function () {
            var Lw = lighting(), PI = Math.fround(Math.PI);
            for (var v = 0; v < nv; ++v) {
                // Each term's g_k = T_k . L (prt_relight_wavelet); Lambertian vertices: the first
                // term's times albedo / pi (prt_wavelet_shade), glossy ones per pixel.
                var glossyVertex = vertexSet && vertexSet[v] > 0;
                for (var k = 0; k < (glossyVertex ? termCount[v] : 1); ++k) {
                    var vec = vecStart[v] + k, at = vec * n, a0 = 0, a1 = 0, a2 = 0;
                    for (var i = 0; i < n; ++i) {
                        var l = index[at + i] * 4, q = (at + i) * 3;
                        a0 += values[q] * Lw[l];
                        a1 += values[q + 1] * Lw[l + 1];
                        a2 += values[q + 2] * Lw[l + 2];
                    }
                    var g0 = a0 * scale[vec * 3], g1 = a1 * scale[vec * 3 + 1], g2 = a2 * scale[vec * 3 + 2];
                    if (kvec) { kvec[(v * Kt + k) * 3] = g0; kvec[(v * Kt + k) * 3 + 1] = g1; kvec[(v * Kt + k) * 3 + 2] = g2; }
                    if (glossyVertex) continue;
                    radiance[v * 3] = albedo[v * 3] / PI * g0;
                    radiance[v * 3 + 1] = albedo[v * 3 + 1] / PI * g1;
                    radiance[v * 3 + 2] = albedo[v * 3 + 2] / PI * g2;
                }
                if (glossyVertex) radiance[v * 3] = radiance[v * 3 + 1] = radiance[v * 3 + 2] = 0;
            }
            if (glossyPass) glossyPass(radiance);
            return radiance;
        },
        set: function (q) {
            environment.set(q);
            var k = q['light-coefficients'];
            if (k !== undefined && +k >= p.light_coefficients_min && +k <= p.light_coefficients_max) {
                state.coefficients = Math.round(+k);
                sliders.coefficients.set(state.coefficients);
            }
        }
    };
});
