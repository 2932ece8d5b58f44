// prt export --web, SH files (method.js): per-vertex diffuse transfer T dotted with the distant
// lighting's SH, L = intensity * R(yaw, pitch, roll) E + D, as sh_relight does: E the
// environment's SH (unrotated, intensity 1), R the Ivanic-Ruedenberg rotation of core/sh_rotate.c
// built from prt's yaw-pitch-roll (core/sh.c; PRT.shRotate in prt.js), D the directional lights' SH at the order used.
// Hash parameters: rotate=YAW[,PITCH[,ROLL]] (degrees), intensity=S, order=N.
'use strict';
PRT.method(function (api) {
    var p = api.meta, N = p.order, n = N * N, ch = p.channels, nv = api.vertexCount;
    var T = api.array('transfer'), albedo = ch === 1 ? api.array('albedo') : null;
    var E = api.array('environment'), D = api.array('directional');
    var state = {rotate: p.rotate.slice(), intensity: p.intensity, order: p.order_default};
    var radiance = new Float32Array(nv * 3);

    // The lighting's SH, 3 channels of n (zero past the order used).
    function lighting() {
        var L = new Float32Array(3 * n), o = state.order;
        if (p.environment) {
            var R = PRT.shRotate(N, 3, E, state.rotate[0], state.rotate[1], state.rotate[2]);
            for (var c = 0; c < 3; ++c)
                for (var k0 = 0; k0 < o * o; ++k0) L[c * n + k0] = Math.fround(R[c * n + k0]) * state.intensity;
        }
        for (var c2 = 0; c2 < 3; ++c2)
            for (var k = 0; k < o * o; ++k) L[c2 * n + k] += D[((o - 1) * 3 + c2) * n + k];
        return L;
    }

    var ui = api.ui, sliders = {};
    var environment = ui.environment(state);
    if (!p.environment) {
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
            environment.set(q);
            if (q.order !== undefined && +q.order >= 1 && +q.order <= N) { state.order = Math.round(+q.order); if (sliders.order) sliders.order.set(state.order); }
        }
    };
});
