// prt export --web, spectral files (method.js): spectral_relight in the browser. Direct
// irradiance at the vertices - the environment's SH (rotated, scaled) through each vertex's baked
// shadowed transfer, the emitters' baked irradiance, and the point lights, which the framework
// evaluates on the GPU with its shadow cubes (one tap a vertex, as the CPU's one shadow ray) -
// then the bounces through the spectral basis (relight.c: project, gather each vertex's row,
// albedo / pi) and the geometric tail (add_tail). The point lights' own direct light is drawn per
// pixel by the framework, as prt render draws it; the radiance handed back holds the rest.
// Hash parameters: lights=X,Y,Z:R,G,B|..., rotate=YAW[,PITCH[,ROLL]], intensity=S, bounces=N, tail=0|1.
'use strict';
PRT.method(function (api) {
    var p = api.meta, nv = api.vertexCount, nc = p.env_order * p.env_order;
    var partOf = api.array('part_of'), first = api.array('first'), offset = api.array('basis_start'), basis = api.array('basis');
    var rowStart = api.array('row_start'), index = api.array('index'), value = api.array('value'), rowScale = api.array('row_scale');
    var albedo = api.array('albedo'), indices = api.array('indices'), positions = api.array('positions');
    var env = nc ? api.array('env') : null, envT = nc ? api.array('env_transfer') : null;
    var emit = p.emission ? api.array('emit') : null, own = p.emission ? api.array('own') : null;
    var state = {rotate: p.rotate.slice(), intensity: p.intensity, bounces: p.bounces, tail: p.tail};
    var radiance = new Float32Array(nv * 3), coeffs = new Float32Array(p.functions * 3), PI = Math.fround(Math.PI);

    // A third of each triangle's area to each corner (add_tail's weights).
    var area = new Float32Array(nv);
    for (var i = 0; i < indices.length; i += 3) {
        var a = indices[i] * 3, b = indices[i + 1] * 3, c = indices[i + 2] * 3;
        var u = [positions[b] - positions[a], positions[b + 1] - positions[a + 1], positions[b + 2] - positions[a + 2]];
        var w = [positions[c] - positions[a], positions[c + 1] - positions[a + 1], positions[c + 2] - positions[a + 2]];
        var cx = u[1] * w[2] - u[2] * w[1], cy = u[2] * w[0] - u[0] * w[2], cz = u[0] * w[1] - u[1] * w[0];
        var third = Math.sqrt(cx * cx + cy * cy + cz * cz) / 6;
        area[indices[i]] += third; area[indices[i + 1]] += third; area[indices[i + 2]] += third;
    }

    function project(signal) {
        coeffs.fill(0);
        for (var v = 0; v < nv; ++v) {
            var q = partOf[v], k = first[q + 1] - first[q], s = offset[v], cf = first[q] * 3;
            var x0 = signal[v * 3], x1 = signal[v * 3 + 1], x2 = signal[v * 3 + 2];
            for (var j = 0; j < k; ++j) {
                var sj = basis[s + j];
                coeffs[cf + j * 3] += sj * x0;
                coeffs[cf + j * 3 + 1] += sj * x1;
                coeffs[cf + j * 3 + 2] += sj * x2;
            }
        }
    }
    function power(x) {
        var o = [0, 0, 0];
        for (var v = 0; v < nv; ++v)
            for (var c = 0; c < 3; ++c) o[c] += area[v] * x[v * 3 + c];
        return o;
    }
    function addTail(before, last, out) {
        var pb = power(before), pl = power(last), f = [], c, v, maxq = p.tail_max_ratio;
        for (c = 0; c < 3; ++c) {
            var q = pb[c] > 0 ? pl[c] / pb[c] : 0;
            q = q > maxq ? maxq : q > 0 ? q : 0;
            f[c] = q / (1 - q);
        }
        var wt = new Float32Array(nv * 3);
        for (var i = 0; i < nv * 3; ++i) {
            var r = before[i] > 0 ? Math.min(last[i] / before[i], maxq) : 0;
            wt[i] = last[i] * Math.sqrt(r);
        }
        var pw = power(wt), cap = maxq / (1 - maxq);
        for (c = 0; c < 3; ++c) f[c] = pw[c] > 0 ? Math.min(f[c] * pl[c] / pw[c], cap) : 0;
        for (v = 0; v < nv; ++v)
            for (c = 0; c < 3; ++c) out[v * 3 + c] += f[c] * wt[v * 3 + c];
    }
    function bounces(direct, out) {
        out.fill(0);
        if (state.bounces <= 0) return;
        var cur = new Float32Array(nv * 3), prev = null, from = direct;
        for (var bounce = 0; bounce < state.bounces; ++bounce) {
            project(from);
            if (state.tail && bounce === state.bounces - 1) prev = Float32Array.from(from);
            var next = new Float32Array(nv * 3);
            for (var v = 0; v < nv; ++v) {
                var e0 = 0, e1 = 0, e2 = 0;
                for (var i = rowStart[v]; i < rowStart[v + 1]; ++i) {
                    var q = value[i], at = index[i] * 3;
                    e0 += q * coeffs[at]; e1 += q * coeffs[at + 1]; e2 += q * coeffs[at + 2];
                }
                var k = rowScale[v] / PI;
                next[v * 3] = albedo[v * 3] * k * (e0 > 0 ? e0 : 0);
                next[v * 3 + 1] = albedo[v * 3 + 1] * k * (e1 > 0 ? e1 : 0);
                next[v * 3 + 2] = albedo[v * 3 + 2] * k * (e2 > 0 ? e2 : 0);
            }
            for (var j = 0; j < nv * 3; ++j) out[j] += next[j];
            cur = next;
            from = cur;
        }
        if (state.tail) addTail(prev, cur, out);
    }

    var lights = api.pointLights({albedo: albedo, lights: p.lights});
    var ui = api.ui, sliders = {};
    var environment = ui.environment(state, nc > 0);
    ui.heading('Bounces');
    sliders.bounces = ui.slider({label: 'bounces', min: 0, max: 16, step: 1, value: state.bounces, input: function (v) { state.bounces = v; api.relight(); }});
    sliders.tail = ui.checkbox('the rest of the series as a geometric tail', !!state.tail, function (v) { state.tail = v ? 1 : 0; api.relight(); });

    var E = new Float32Array(nv * 3), Ep = new Float32Array(nv * 3), direct = new Float32Array(nv * 3), indirect = new Float32Array(nv * 3);
    return {
        relight: function () {
            var v, c, i;
            E.fill(0);
            if (nc && state.intensity > 0) {
                var L = PRT.shRotate(p.env_order, 3, env, state.rotate[0], state.rotate[1], state.rotate[2]);
                for (i = 0; i < 3 * nc; ++i) L[i] = Math.fround(L[i]) * state.intensity;
                for (v = 0; v < nv; ++v)
                    for (c = 0; c < 3; ++c) {
                        var sum = 0;
                        for (i = 0; i < nc; ++i) sum += L[c * nc + i] * envT[v * nc + i];
                        E[v * 3 + c] = sum > 0 ? sum : 0;   // ringing of the truncated SH can dip below zero
                    }
            }
            if (emit) for (i = 0; i < nv * 3; ++i) E[i] += emit[i];
            Ep.fill(0);
            for (var l = 0; l < lights.list.length; ++l) {
                var at = lights.atVertices(l);
                for (v = 0; v < nv; ++v)
                    for (c = 0; c < 3; ++c) Ep[v * 3 + c] += at[v * 4 + c];
            }
            for (i = 0; i < nv * 3; ++i) direct[i] = albedo[i] / PI * (E[i] + Ep[i]);
            bounces(direct, indirect);
            // The point lights' direct light is the framework's, per pixel.
            for (i = 0; i < nv * 3; ++i) radiance[i] = (own ? own[i] : 0) + albedo[i] / PI * E[i] + indirect[i];
            return radiance;
        },
        set: function (q) {
            environment.set(q);
            if (q.bounces !== undefined && +q.bounces >= 0 && +q.bounces <= p.bounces_max) { state.bounces = Math.round(+q.bounces); sliders.bounces.set(state.bounces); }
            if (q.tail !== undefined) { state.tail = +q.tail ? 1 : 0; sliders.tail.set(!!state.tail); }
        }
    };
});
