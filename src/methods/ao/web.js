// prt export --web, ao files (method.js): relight.c in the browser. The environment's SH (order
// 3; rotated, scaled) convolved with the clamped cosine over pi (p.zh: each band's factor) is E(n) / pi; a vertex reflects
// albedo x accessibility x max(E(n) / pi, 0), its normal's SH basis values baked into the page.
// Hash parameters: rotate=YAW[,PITCH[,ROLL]] (degrees), intensity=S.
'use strict';
PRT.method(function (api) {
    var p = api.meta, N = p.order, n = N * N, nv = api.vertexCount;
    var env = api.array('env'), basis = api.array('basis'), reflect = api.array('reflect');
    var state = {rotate: p.rotate.slice(), intensity: p.intensity};
    var radiance = new Float32Array(nv * 3);
    var ui = api.ui;
    var environment = ui.environment(state);
    return {
        relight: function () {
            var L = PRT.shRotate(N, 3, env, state.rotate[0], state.rotate[1], state.rotate[2]), c, l, k, v;
            for (c = 0; c < 3; ++c)
                for (l = 0; l < N; ++l)
                    for (k = l * l; k < (l + 1) * (l + 1); ++k) L[c * n + k] = Math.fround(L[c * n + k]) * state.intensity * p.zh[l];
            for (v = 0; v < nv; ++v)
                for (c = 0; c < 3; ++c) {
                    var e = 0;
                    for (k = 0; k < n; ++k) e += L[c * n + k] * basis[v * n + k];
                    radiance[v * 3 + c] = reflect[v * 3 + c] * (e > 0 ? e : 0);   // order 3 rings below zero opposite a bright sun
                }
            return radiance;
        },
        set: function (q) {
            environment.set(q);
        }
    };
});
