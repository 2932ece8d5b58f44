// prt export --web, offset files (method.js): relight.c in the browser, over the light map's
// covered texels. First-order light: the point lights at each texel's 4 shadow-ray points (the
// framework's shadow cubes, one tap a point, as the CPU's shadow rays), the emitters' baked
// irradiance, the environment's SH (order 3, rotated, scaled) through each texel's shadowed
// transfer; then subsurface scattering and inter-reflection as modulate-shift-accumulate passes
// over it (eq. 9), the bounce maps reading a prefiltered pyramid of the light (prefilter.c); the
// map is drawn per texel, and the point lights' direct light on top per pixel, as prt render.
// Hash parameters: lights=X,Y,Z:R,G,B|..., rotate=YAW[,PITCH[,ROLL]], intensity=S, bounces=N.
'use strict';
PRT.method(function (api) {
    var p = api.meta, W = p.width, H = p.height, nc = p.covered, K = p.count, S = p.samples, PI = Math.fround(Math.PI);
    var texel = api.array('texel'), source = new Int32Array(api.array('source').buffer), alb = api.array('texel_albedo');
    var envT = api.array('texel_env'), env = api.array('env'), offsets = p.offsets;
    var emit = p.emits ? api.array('emit') : null, emitIn = p.emits ? api.array('emit_in') : null;
    var radiosity = p.radiosity ? api.array('radiosity') : null, subsurface = p.subsurface ? api.array('subsurface') : null;
    var medium = p.subsurface ? api.array('medium') : null;
    var chart = p.radiosity ? new Int32Array(api.array('chart').buffer) : null, level = p.radiosity ? api.array('level') : null;
    var area = p.radiosity ? api.array('area') : null, tnrm = p.radiosity ? api.array('texel_nrm') : null;
    var state = {rotate: p.rotate.slice(), intensity: p.intensity, bounces: p.bounces};
    var xs = new Int32Array(nc), ys = new Int32Array(nc);
    for (var i = 0; i < nc; ++i) { xs[i] = texel[i] % W; ys[i] = Math.floor(texel[i] / W); }

    // out[i] = sum_k in[levels[k]](source(texel i + offset k)) maps[k][i] (relight.c's apply;
    // levels null: every map reads inputs[0]).
    function apply(maps, inputs, levels, out) {
        out.fill(0);
        for (var k = 0; k < K; ++k) {
            var ox = offsets[k * 2], oy = offsets[k * 2 + 1], shift = oy * W + ox, src = inputs[levels ? levels[k] : 0], m = k * nc * 3;
            for (var i = 0; i < nc; ++i) {
                if (xs[i] + ox < 0 || xs[i] + ox >= W || ys[i] + oy < 0 || ys[i] + oy >= H) continue;
                var f = source[texel[i] + shift];
                if (f < 0) continue;
                f *= 3;
                out[i * 3] += src[f] * maps[m + i * 3];
                out[i * 3 + 1] += src[f + 1] * maps[m + i * 3 + 1];
                out[i * 3 + 2] += src[f + 2] * maps[m + i * 3 + 2];
            }
        }
    }
    // The light each covered texel stands for at levels 0..levels (prefilter.c).
    var MIXED = -1, EMPTY = -2;
    function filter(light) {
        var out = [light], L = p.levels;
        if (!L) return out;
        var pyr = [], l, x, y, j, c;
        var w0 = W, h0 = H, q0 = new Float32Array(W * H * 5);
        for (i = 0; i < W * H; ++i) q0[i * 5 + 4] = EMPTY;
        for (i = 0; i < nc; ++i) {
            var at = texel[i] * 5;
            for (c = 0; c < 3; ++c) q0[at + c] = area[i] * light[i * 3 + c];
            q0[at + 3] = area[i];
            q0[at + 4] = chart[i] < 0 ? MIXED : chart[i];
        }
        pyr[0] = {w: w0, h: h0, q: q0};
        for (l = 1; l <= L; ++l) {
            var pw = pyr[l - 1].w, ph = pyr[l - 1].h, w = (pw + 1) >> 1, h = (ph + 1) >> 1, q = new Float32Array(w * h * 5), below = pyr[l - 1].q;
            for (y = 0; y < h; ++y)
                for (x = 0; x < w; ++x) {
                    var o = (y * w + x) * 5;
                    q[o + 4] = EMPTY;
                    for (j = 0; j < 4; ++j) {
                        var cx = x * 2 + (j & 1), cy = y * 2 + (j >> 1);
                        if (cx >= pw || cy >= ph) continue;
                        var b = (cy * pw + cx) * 5;
                        for (var k = 0; k < 4; ++k) q[o + k] += below[b + k];
                        if (below[b + 4] === EMPTY) continue;
                        q[o + 4] = q[o + 4] === EMPTY ? below[b + 4] : q[o + 4] === below[b + 4] ? q[o + 4] : MIXED;
                    }
                }
            pyr[l] = {w: w, h: h, q: q};
        }
        for (l = 1; l <= L; ++l) {
            var res = new Float32Array(nc * 3), P = pyr[l], inv = 1 / (1 << l), prev = out[l - 1];
            for (i = 0; i < nc; ++i) {
                var fx = (xs[i] + 0.5) * inv - 0.5, fy = (ys[i] + 0.5) * inv - 0.5, x0 = Math.floor(fx), y0 = Math.floor(fy);
                var ax = fx - x0, ay = fy - y0, own = chart[i];
                for (j = 0; j < 4; ++j) {
                    var bx = x0 + (j & 1), by = y0 + (j >> 1), wt = ((j & 1) ? ax : 1 - ax) * ((j >> 1) ? ay : 1 - ay);
                    var qi = bx >= 0 && by >= 0 && bx < P.w && by < P.h ? (by * P.w + bx) * 5 : -1;
                    if (qi >= 0 && P.q[qi + 4] === own && P.q[qi + 3] > 0)
                        for (c = 0; c < 3; ++c) res[i * 3 + c] += wt * (P.q[qi + c] / P.q[qi + 3]);
                    else
                        for (c = 0; c < 3; ++c) res[i * 3 + c] += wt * prev[i * 3 + c];
                }
            }
            out[l] = res;
        }
        return out;
    }

    // The bounced light over each texel's chart around it (smooth.c): a tent of smooth_radius
    // texels, weighted by texel area and max(0, n . n')^32; a texel without a chart keeps its own.
    var at = new Int32Array(W * H).fill(-1);
    for (var t = 0; t < nc; ++t) at[texel[t]] = t;
    function smooth(light, out) {
        var R = p.smooth_radius;
        for (var i = 0; i < nc; ++i) {
            var own = chart[i], acc = [0, 0, 0], sum = 0, c;
            if (own < 0) { for (c = 0; c < 3; ++c) out[i * 3 + c] = light[i * 3 + c]; continue; }
            for (var dy = -R; dy <= R; ++dy)
                for (var dx = -R; dx <= R; ++dx) {
                    var X = xs[i] + dx, Y = ys[i] + dy;
                    if (X < 0 || Y < 0 || X >= W || Y >= H) continue;
                    var j = at[Y * W + X];
                    if (j < 0 || chart[j] !== own) continue;
                    var f = Math.max(tnrm[i * 3] * tnrm[j * 3] + tnrm[i * 3 + 1] * tnrm[j * 3 + 1] + tnrm[i * 3 + 2] * tnrm[j * 3 + 2], 0);
                    for (var k = 0; k < 5; ++k) f *= f;
                    var w = (R + 1 - Math.abs(dx)) * (R + 1 - Math.abs(dy)) * area[j] * f;
                    if (!(w > 0)) continue;
                    for (c = 0; c < 3; ++c) acc[c] += w * light[j * 3 + c];
                    sum += w;
                }
            for (c = 0; c < 3; ++c) out[i * 3 + c] = sum > 0 ? acc[c] / sum : light[i * 3 + c];
        }
    }

    var lights = api.pointLights({albedo: api.array('albedo'), lights: p.lights});
    var points = lights.points(api.array('sample_pos'), api.array('sample_nrm'));
    api.lightMap(W, H);
    var ui = api.ui, sliders = {};
    var environment = ui.environment(state);
    if (p.radiosity && p.bounces_max > 0) {
        ui.heading('Inter-reflection');
        sliders.bounces = ui.slider({label: p.bounces_max === 1 ? 'bounces (the maps hold them all: 0 or 1 pass)' : 'bounces', min: 0, max: p.bounces_max,
                                     step: 1, value: state.bounces, input: function (v) { state.bounces = v; api.relight(); }});
    }

    var E = new Float32Array(nc * 3), a = new Float32Array(nc * 3), first = new Float32Array(nc * 3), hide = new Float32Array(nc * 3);
    var b = new Float32Array(nc * 3), indirect = new Float32Array(nc * 3), map = new Float32Array(W * H * 3);
    return {
        relight: function () {
            var i, c, k;
            E.fill(0);
            for (var l = 0; l < lights.list.length; ++l) {
                var at = lights.atPoints(l, points);
                for (i = 0; i < nc; ++i)
                    for (k = 0; k < S; ++k)
                        for (c = 0; c < 3; ++c) E[i * 3 + c] += at[(i * S + k) * 4 + c] / S;
            }
            var L = new Float32Array(27);
            if (p.environment) {
                var R = PRT.shRotate(3, 3, env, state.rotate[0], state.rotate[1], state.rotate[2]);
                for (i = 0; i < 27; ++i) L[i] = Math.fround(R[i]) * state.intensity;
            }
            for (i = 0; i < nc; ++i)
                for (c = 0; c < 3; ++c) {
                    var e = (E[i * 3 + c] + (emitIn ? p.emission * emitIn[i * 3 + c] : 0)) / PI;
                    for (k = 0; k < 9; ++k) e += envT[i * 9 + k] * L[c * 9 + k];
                    a[i * 3 + c] = e > 0 ? e : 0;
                    first[i * 3 + c] = alb[i * 3 + c] * a[i * 3 + c];
                    // The point lights' direct light is drawn per pixel: the map leaves it out.
                    var own = subsurface && medium[i] ? subsurface[i * 3 + c] : alb[i * 3 + c];
                    hide[i * 3 + c] = lights.list.length ? own * E[i * 3 + c] / PI : 0;
                }
            if (subsurface) {
                apply(subsurface, [a], null, b);
                for (i = 0; i < nc; ++i)
                    if (medium[i]) for (c = 0; c < 3; ++c) first[i * 3 + c] = b[i * 3 + c];
            }
            indirect.fill(0);
            if (radiosity) {
                var cur = Float32Array.from(first), next = new Float32Array(nc * 3);
                for (k = 0; k < state.bounces; ++k) {
                    apply(radiosity, filter(cur), level, next);
                    for (i = 0; i < nc * 3; ++i) indirect[i] += next[i];
                    var tmp = cur; cur = next; next = tmp;
                }
                if (p.levels && p.smooth_radius && state.bounces > 0) { smooth(indirect, next); indirect.set(next); }
            }
            if (emit) for (i = 0; i < nc * 3; ++i) first[i] += p.emission * emit[i];
            for (i = 0; i < nc * 3; ++i) b[i] = Math.max(first[i] - hide[i], 0) + indirect[i];
            // Gutters as the GPU path fills them: each texel its source's value.
            for (i = 0; i < W * H; ++i) {
                var s = source[i];
                for (c = 0; c < 3; ++c) map[i * 3 + c] = s >= 0 ? b[s * 3 + c] : 0;
            }
            return map;
        },
        set: function (q) {
            environment.set(q);
            if (q.bounces !== undefined && +q.bounces >= 0 && +q.bounces <= p.bounces_max) {
                state.bounces = Math.round(+q.bounces);
                if (sliders.bounces) sliders.bounces.set(state.bounces);
            }
        }
    };
});
