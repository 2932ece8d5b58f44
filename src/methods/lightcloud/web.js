// prt export --web, light-cloud files (method.js): relight.c in the browser. Each point light's
// weights over the cloud: its nearest cloud lights (ties by index, as the k-d tree), each counted
// by the share of 9 short paths (the light to a point on a small sphere around it, then on to the
// cloud light) that the framework's ray caster finds clear, weighted (1 - d/r)^4 / d^2, r the
// distance to the next nearest; then per zone the weights summed into its merged lights and
// dotted with the responses (raw, or each clustered-PCA mean and basis vector once). The lights'
// direct light is the framework's, per pixel (unless the file stores it with the responses).
// Hash parameters: lights=X,Y,Z:R,G,B|..., neighbours=N.
'use strict';
PRT.method(function (api) {
    var p = api.meta, nv = api.vertexCount, K = p.lobes, n = p.cloud_count;
    var cloud = api.array('cloud'), members = api.array('members'), memberStart = api.array('member_start');
    var albedo = api.array('albedo'), fixed = p.emission ? api.array('fixed') : null;
    var zones = p.zones.map(function (z, i) {
        var o = {lights: z.lights, vertices: z.vertices, dim: z.dim, lightOf: api.array('z' + i + '_light_of')};
        if (!z.vertices) return o;
        if (z.raw) { o.raw = api.array('z' + i + '_raw'); return o; }
        o.clusters = z.clusters;
        o.vectors = z.vectors;
        o.means = api.array('z' + i + '_means');
        o.basis = api.array('z' + i + '_basis');
        o.counts = api.array('z' + i + '_counts');
        o.clusterOf = api.array('z' + i + '_cluster_of');
        o.weights = api.array('z' + i + '_weights');
        o.basisStart = new Uint32Array(o.clusters + 1);
        for (var c = 0; c < o.clusters; ++c) o.basisStart[c + 1] = o.basisStart[c] + o.counts[c];
        o.weightStart = new Uint32Array(z.vertices + 1);
        for (var r = 0; r < z.vertices; ++r) o.weightStart[r + 1] = o.weightStart[r] + o.counts[o.clusterOf[r]];
        return o;
    });
    var state = {neighbours: p.neighbours};
    var radiance = new Float32Array(nv * 3), note = null;

    var PATHS = [[0, 0, 0], [.577, .577, .577], [-.577, .577, .577], [.577, -.577, .577], [.577, .577, -.577],
                 [-.577, -.577, .577], [-.577, .577, -.577], [.577, -.577, -.577], [-.577, -.577, -.577]];
    function seen(rays, pos, q, radius) {
        var open = 0;
        for (var i = 0; i < PATHS.length; ++i) {
            var a = [pos[0] + radius * PATHS[i][0], pos[1] + radius * PATHS[i][1], pos[2] + radius * PATHS[i][2]];
            if ((i === 0 || rays.segmentClear(pos, a)) && rays.segmentClear(a, q)) open++;
        }
        return open / PATHS.length;
    }
    // prt__lightcloud_weights for point lights: [cloud light][lobe][colour].
    function weights(list) {
        var w = new Float32Array(n * K * 3), rays = api.raycaster(), radius = 0.25 * p.spacing, problems = [];
        var MAXK = p.neighbours_max + 1;
        list.forEach(function (L) {
            var byDistance = [];
            for (var j = 0; j < n; ++j)
                byDistance.push([Math.fround(Math.hypot(cloud[j * 3] - L.position[0], cloud[j * 3 + 1] - L.position[1], cloud[j * 3 + 2] - L.position[2])), j]);
            byDistance.sort(function (a, b) { return a[0] - b[0] || a[1] - b[1]; });
            var weight = [], sum = 0, found = 0, m = Math.max(1, Math.min(state.neighbours, MAXK - 1));
            for (; sum <= 0 && m < MAXK; m = m * 2 < MAXK ? m * 2 : MAXK) {
                found = Math.min(m + 1, n);
                if (!found) break;
                var r = found > m ? byDistance[m][0] : byDistance[found - 1][0] * 1.5 + 1e-20, use = found > m ? m : found;
                sum = 0;
                for (var i = 0; i < use; ++i) {
                    var d = byDistance[i][0], q = byDistance[i][1];
                    if (d <= 1e-6 * p.spacing) {   // on a cloud light: its solution
                        for (var k = 0; k < use; ++k) weight[k] = 0;
                        weight[i] = 1;
                        sum = 1;
                        break;
                    }
                    var vis = d < r ? seen(rays, L.position, [cloud[q * 3], cloud[q * 3 + 1], cloud[q * 3 + 2]], radius) : 0;
                    var a = 1 - d / r;
                    weight[i] = vis * a * a * a * a / (d * d);
                    sum += weight[i];
                }
                found = use;
            }
            if (sum <= 0) { problems.push('a light sees none of the cloud near it: it adds no indirect light'); return; }
            var beyond = 0;
            for (var c = 0; c < 3; ++c) beyond = Math.max(beyond, p.region[c] - L.position[c], L.position[c] - p.region[3 + c]);
            if (beyond > 0) problems.push('a light lies outside the region the cloud covers: its indirect light is the nearest cloud lights\' and will be wrong');
            for (i = 0; i < found; ++i)
                for (c = 0; c < 3; ++c) w[(byDistance[i][1] * K) * 3 + c] += Math.fround(weight[i] / sum) * L.intensity[c];   // lobe 0: isotropic
        });
        if (note) note.textContent = problems.join('; ');
        return w;
    }
    // prt__lightcloud_eval, diffuse blocks: adds to radiance.
    function evaluate(w) {
        zones.forEach(function (z, zi) {
            var cols = z.lights * K, W = new Float32Array(cols * 3), any = false, j, k, c;
            for (j = 0; j < n; ++j)
                for (k = 0; k < K; ++k)
                    for (c = 0; c < 3; ++c) {
                        var x = w[(j * K + k) * 3 + c];
                        W[(z.lightOf[j] * K + k) * 3 + c] += x;
                        any = any || x !== 0;
                    }
            if (!any || !z.vertices) return;
            var m0 = memberStart[zi], L = cols, r, l, sum;
            if (z.raw) {
                for (r = 0; r < z.vertices; ++r) {
                    var at = r * z.dim, o = members[m0 + r] * 3;
                    for (c = 0; c < 3; ++c) {
                        sum = 0;
                        for (l = 0; l < L; ++l) sum += z.raw[at + c * L + l] * W[l * 3 + c];
                        radiance[o + c] += sum;
                    }
                }
                return;
            }
            var vecs = z.clusters + z.vectors, proj = new Float32Array(vecs * 3);
            for (var v = 0; v < vecs; ++v) {
                var src = v < z.clusters ? z.means : z.basis, base = (v < z.clusters ? v : v - z.clusters) * z.dim;
                for (c = 0; c < 3; ++c) {
                    sum = 0;
                    for (l = 0; l < L; ++l) sum += src[base + c * L + l] * W[l * 3 + c];
                    proj[v * 3 + c] = sum;
                }
            }
            for (r = 0; r < z.vertices; ++r) {
                var cl = z.clusterOf[r], zs = z.weightStart[r], out = members[m0 + r] * 3;
                for (c = 0; c < 3; ++c) radiance[out + c] += proj[cl * 3 + c];
                for (j = 0; j < z.counts[cl]; ++j) {
                    var bv = (z.clusters + z.basisStart[cl] + j) * 3;
                    for (c = 0; c < 3; ++c) radiance[out + c] += z.weights[zs + j] * proj[bv + c];
                }
            }
        });
    }

    var lights = api.pointLights({albedo: albedo, lights: p.lights, perPixel: !p.store_direct});
    var ui = api.ui, sliders = {};
    ui.heading('Light cloud');
    ui.note(n + ' cloud lights; ' + (p.store_direct ? 'direct light baked with the responses' : 'direct light drawn per pixel with shadow maps'));
    sliders.neighbours = ui.slider({label: 'neighbours', min: 1, max: p.neighbours_max, step: 1, value: state.neighbours,
                                    input: function (v) { state.neighbours = v; api.relight(); }});
    note = ui.note('');

    return {
        relight: function () {
            radiance.fill(0);
            evaluate(weights(lights.list));
            if (fixed) for (var i = 0; i < nv * 3; ++i) radiance[i] += fixed[i];
            return radiance;
        },
        set: function (q) {
            if (q.neighbours !== undefined && +q.neighbours >= 1 && +q.neighbours <= p.neighbours_max) {
                state.neighbours = Math.round(+q.neighbours);
                sliders.neighbours.set(state.neighbours);
            }
        }
    };
});
