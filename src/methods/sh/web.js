// prt export --web, SH files (method.js): per-vertex diffuse transfer T dotted with the distant
// lighting's SH, L = intensity * R(yaw, pitch, roll) E + D, as sh_relight does: E the
// environment's SH (unrotated, intensity 1), R the Ivanic-Ruedenberg rotation of core/sh_rotate.c
// built from prt's yaw-pitch-roll (core/sh.c), D the directional lights' SH at the order used.
// Hash parameters: rotate=YAW[,PITCH[,ROLL]] (degrees), intensity=S, order=N.
'use strict';
PRT.method(function (api) {
    var p = api.meta, N = p.order, n = N * N, ch = p.channels, nv = api.vertexCount;
    var T = api.array('transfer'), albedo = ch === 1 ? api.array('albedo') : null;
    var E = api.array('environment'), D = api.array('directional');
    var state = {rotate: p.rotate.slice(), intensity: p.intensity, order: p.order_default};
    var radiance = new Float32Array(nv * 3);

    // R = Ry(yaw) Rx(pitch) Rz(roll), row-major (prt_rotation_from_euler_deg).
    function euler(yaw, pitch, roll) {
        var a = yaw * Math.PI / 180, b = pitch * Math.PI / 180, c = roll * Math.PI / 180;
        var ry = [Math.cos(a), 0, Math.sin(a), 0, 1, 0, -Math.sin(a), 0, Math.cos(a)];
        var rx = [1, 0, 0, 0, Math.cos(b), -Math.sin(b), 0, Math.sin(b), Math.cos(b)];
        var rz = [Math.cos(c), -Math.sin(c), 0, Math.sin(c), Math.cos(c), 0, 0, 0, 1];
        function mul(x, y) {
            var o = [];
            for (var i = 0; i < 3; ++i)
                for (var j = 0; j < 3; ++j) o[i * 3 + j] = x[i * 3] * y[j] + x[i * 3 + 1] * y[3 + j] + x[i * 3 + 2] * y[6 + j];
            return o;
        }
        return mul(ry, mul(rx, rz));
    }

    // Band l's (2l+1)^2 matrix, bands[l][(a + l) * (2l + 1) + (b + l)].
    function rotation(order, rot) {
        var bands = [[1]];
        function B(l, a, b) { return bands[l][(a + l) * (2 * l + 1) + (b + l)]; }
        function P(i, l, a, b) {
            var ri1 = B(1, i, 1), rim1 = B(1, i, -1), ri0 = B(1, i, 0);
            if (b === l) return ri1 * B(l - 1, a, l - 1) - rim1 * B(l - 1, a, -l + 1);
            if (b === -l) return ri1 * B(l - 1, a, -l + 1) + rim1 * B(l - 1, a, l - 1);
            return ri0 * B(l - 1, a, b);
        }
        if (order > 1) {
            var axis = [1, 2, 0], b1 = [];   // band 1 is (y, z, x) for m = -1, 0, 1
            for (var a = -1; a <= 1; ++a)
                for (var b = -1; b <= 1; ++b) b1[(a + 1) * 3 + (b + 1)] = rot[axis[a + 1] * 3 + axis[b + 1]];
            bands[1] = b1;
        }
        for (var l = 2; l < order; ++l) {
            var band = bands[l] = new Array((2 * l + 1) * (2 * l + 1));
            for (var m = -l; m <= l; ++m)
                for (var nn = -l; nn <= l; ++nn) {
                    var am = Math.abs(m), d = m === 0 ? 1 : 0;
                    var denom = Math.abs(nn) < l ? (l + nn) * (l - nn) : (2 * l) * (2 * l - 1);
                    var u = Math.sqrt((l + m) * (l - m) / denom);
                    var v = 0.5 * Math.sqrt((1 + d) * (l + am - 1) * (l + am) / denom) * (1 - 2 * d);
                    var w = -0.5 * Math.sqrt((l - am - 1) * (l - am) / denom) * (1 - d);
                    var val = 0;
                    if (u !== 0) val += u * P(0, l, m, nn);
                    if (v !== 0) {
                        var vv;
                        if (m === 0) vv = P(1, l, 1, nn) + P(-1, l, -1, nn);
                        else if (m > 0) vv = P(1, l, m - 1, nn) * Math.sqrt(m === 1 ? 2 : 1) - (m === 1 ? 0 : P(-1, l, -m + 1, nn));
                        else vv = (m === -1 ? 0 : P(1, l, m + 1, nn)) + P(-1, l, -m - 1, nn) * Math.sqrt(m === -1 ? 2 : 1);
                        val += v * vv;
                    }
                    if (w !== 0) val += w * (m > 0 ? P(1, l, m + 1, nn) + P(-1, l, -m - 1, nn) : P(1, l, m - 1, nn) - P(-1, l, -m + 1, nn));
                    band[(m + l) * (2 * l + 1) + (nn + l)] = val;
                }
        }
        return bands;
    }

    // The lighting's SH, 3 channels of n (zero past the order used).
    function lighting() {
        var L = new Float32Array(3 * n), o = state.order;
        if (p.environment) {
            var bands = rotation(N, euler(state.rotate[0], state.rotate[1], state.rotate[2]));
            for (var c = 0; c < 3; ++c)
                for (var l = 0; l < o; ++l)
                    for (var a = -l; a <= l; ++a) {
                        var s = 0;
                        for (var b = -l; b <= l; ++b) s += bands[l][(a + l) * (2 * l + 1) + (b + l)] * E[c * n + l * l + b + l];
                        L[c * n + l * l + a + l] = Math.fround(s) * state.intensity;
                    }
        }
        for (var c2 = 0; c2 < 3; ++c2)
            for (var k = 0; k < o * o; ++k) L[c2 * n + k] += D[((o - 1) * 3 + c2) * n + k];
        return L;
    }

    var ui = api.ui, sliders = {};
    if (p.environment) {
        ui.heading('Environment');
        ['yaw', 'pitch', 'roll'].forEach(function (name, i) {
            sliders[name] = ui.slider({label: name + ' (degrees)', min: -180, max: 180, step: 1, value: state.rotate[i],
                                       input: function (v) { state.rotate[i] = v; api.relight(); }});
        });
        sliders.intensity = ui.slider({label: 'intensity', min: 0, max: 4, step: 0.05, value: state.intensity,
                                       input: function (v) { state.intensity = v; api.relight(); }});
    } else {
        ui.note('No environment: the page relights the directional lights.');
    }
    if (N > 1)
        sliders.order = ui.slider({label: 'SH order', min: 1, max: N, step: 1, value: state.order,
                                   input: function (v) { state.order = v; api.relight(); }});
    if (p.directional_lights) ui.note(p.directional_lights + ' directional light(s) as baked into the lighting.');

    return {
        relight: function () {
            var L = lighting(), o2 = state.order * state.order;
            for (var v = 0; v < nv; ++v) {
                var t = v * ch * n;
                if (ch === 1) {
                    var r = 0, g = 0, b = 0;
                    for (var i = 0; i < o2; ++i) { var x = T[t + i]; r += x * L[i]; g += x * L[n + i]; b += x * L[2 * n + i]; }
                    radiance[v * 3] = r * albedo[v * 3];
                    radiance[v * 3 + 1] = g * albedo[v * 3 + 1];
                    radiance[v * 3 + 2] = b * albedo[v * 3 + 2];
                } else {
                    for (var c = 0; c < 3; ++c) {
                        var sum = 0, tc = t + c * n, lc = c * n;
                        for (var j = 0; j < o2; ++j) sum += T[tc + j] * L[lc + j];
                        radiance[v * 3 + c] = sum;
                    }
                }
            }
            return radiance;
        },
        set: function (q) {
            var r;
            if (q.rotate && (r = api.numbers(q.rotate, 3))) {
                state.rotate = r;
                if (sliders.yaw) { sliders.yaw.set(r[0]); sliders.pitch.set(r[1]); sliders.roll.set(r[2]); }
            }
            if (q.intensity !== undefined && +q.intensity >= 0) { state.intensity = +q.intensity; if (sliders.intensity) sliders.intensity.set(state.intensity); }
            if (q.order !== undefined && +q.order >= 1 && +q.order <= N) { state.order = Math.round(+q.order); if (sliders.order) sliders.order.set(state.order); }
        }
    };
});
