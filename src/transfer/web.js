// prt export --web: the page's framework (prt.js). It draws the mesh with per-vertex linear
// radiance, holds the camera (prt render's matrix), tone-maps as prt render's PNGs do (exposure,
// Reinhard on luminance or clamp, sRGB) and builds the panel; the method's script (method.js)
// registers with PRT.method(function (api) { ... return {relight: ..., set: ...}; }) and hands
// back per-vertex radiance whenever the lighting changes. Plain classic script: pages opened from
// the file system may use neither fetch nor modules.
//
// URL hash parameters (#rotate=90,0,0&intensity=2) set the state at load and on change; the
// framework's are eye=X,Y,Z target=X,Y,Z fov=DEG exposure=STOPS, lights=X,Y,Z:R,G,B|... and
// markers=0 (point lights without their markers, as prt render draws them), the rest go to the
// method.
// window.prtPage.set({...}) does the same from a script and draws at once.
'use strict';
var PRT = (function () {
    var factory = null;

    function method(f) { factory = f; }

    function decode(entry) {
        var bin = atob(entry[1]), bytes = new Uint8Array(bin.length);
        for (var i = 0; i < bin.length; ++i) bytes[i] = bin.charCodeAt(i);
        var Type = {f32: Float32Array, u32: Uint32Array, u16: Uint16Array, i16: Int16Array, u8: Uint8Array, i8: Int8Array}[entry[0]];
        return new Type(bytes.buffer);
    }

    function numbers(text, count) {
        var parts = String(text).split(',').map(Number);
        if (parts.length < 1 || parts.length > count || parts.some(function (x) { return !isFinite(x); })) return null;
        while (parts.length < count) parts.push(0);
        return parts;
    }

    function parseHash() {
        var out = {}, h = location.hash.replace(/^#/, '');
        if (!h) return out;
        h.split('&').forEach(function (kv) {
            var at = kv.indexOf('=');
            if (at > 0) out[decodeURIComponent(kv.slice(0, at))] = decodeURIComponent(kv.slice(at + 1));
        });
        return out;
    }

    // prt render's camera (render/draw.c prt__camera_matrix): column-major, near and far at
    // 1/100 and 100 times the eye's distance to the target.
    function cameraMatrix(eye, target, upIn, fovDeg, aspect, nearFar) {
        function sub(a, b) { return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]; }
        function cross(a, b) { return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]; }
        function dot(a, b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
        function norm(a) { var l = Math.sqrt(dot(a, a)); return l > 0 ? [a[0] / l, a[1] / l, a[2] / l] : null; }
        var up = upIn[0] || upIn[1] || upIn[2] ? upIn : [0, 1, 0];
        var f = sub(target, eye), dist = Math.sqrt(dot(f, f));
        f = norm(f) || [0, 0, -1];
        var s = norm(cross(f, up)) || norm(cross(f, [0, 0, 1]));
        var u = cross(s, f);
        var view = [s[0], u[0], -f[0], 0, s[1], u[1], -f[1], 0, s[2], u[2], -f[2], 0, -dot(s, eye), -dot(u, eye), dot(f, eye), 1];
        var fov = (fovDeg > 0 ? fovDeg : 40) * Math.PI / 180, n = nearFar ? nearFar[0] : dist * 0.01, fa = nearFar ? nearFar[1] : dist * 100;
        var t = 1 / Math.tan(fov * 0.5);
        var proj = [t / aspect, 0, 0, 0, 0, t, 0, 0, 0, 0, (fa + n) / (n - fa), -1, 0, 0, 2 * fa * n / (n - fa), 0];
        var out = new Float32Array(16);
        for (var c = 0; c < 4; ++c)
            for (var r = 0; r < 4; ++r) {
                var acc = 0;
                for (var k = 0; k < 4; ++k) acc += proj[k * 4 + r] * view[c * 4 + k];
                out[c * 4 + r] = acc;
            }
        return out;
    }

    // ---- SH maths every SH-lit method shares (core/sh.c, core/sh_rotate.c) ----
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
    // The Ivanic-Ruedenberg rotation of real SH of `order` by row-major rot: band l's
    // (2l+1)^2 matrix, bands[l][(a + l) * (2l + 1) + (b + l)].
    function shRotation(order, rot) {
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
    // SH vectors (channels of n = order^2, channel-major) rotated: prt_sh_light_rotate.
    function shRotate(order, channels, input, yaw, pitch, roll) {
        var n = order * order, out = new Float32Array(channels * n), bands = shRotation(order, euler(yaw, pitch, roll));
        for (var c = 0; c < channels; ++c)
            for (var l = 0; l < order; ++l)
                for (var a = -l; a <= l; ++a) {
                    var s = 0;
                    for (var b = -l; b <= l; ++b) s += bands[l][(a + l) * (2 * l + 1) + (b + l)] * input[c * n + l * l + b + l];
                    out[c * n + l * l + a + l] = s;
                }
        return out;
    }

    function compile(gl, vs, fs) {
        function shader(type, src) {
            var sh = gl.createShader(type);
            gl.shaderSource(sh, src);
            gl.compileShader(sh);
            if (!gl.getShaderParameter(sh, gl.COMPILE_STATUS)) throw new Error('shader: ' + gl.getShaderInfoLog(sh));
            return sh;
        }
        var p = gl.createProgram();
        gl.attachShader(p, shader(gl.VERTEX_SHADER, vs));
        gl.attachShader(p, shader(gl.FRAGMENT_SHADER, fs));
        gl.linkProgram(p);
        if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error('program: ' + gl.getProgramInfoLog(p));
        return p;
    }

    // Exposure, Reinhard on luminance (or clamp), sRGB: image.c's encode_png.
    var TONEMAP =
        'uniform float u_scale; uniform int u_clamp;\n' +
        'float srgb(float c) { return c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1.0 / 2.4) - 0.055; }\n' +
        'vec4 tonemap(vec3 c) {\n' +
        '  c *= u_scale;\n' +
        '  if (u_clamp == 0) { float lum = dot(c, vec3(0.2126, 0.7152, 0.0722)); c *= lum > 0.0 ? 1.0 / (1.0 + lum) : 1.0; }\n' +
        '  c = clamp(c, 0.0, 1.0);\n' +
        '  return vec4(srgb(c.r), srgb(c.g), srgb(c.b), 1.0);\n' +
        '}\n';

    var MESH_VS = '#version 300 es\n' +
        'layout(location = 0) in vec3 pos; layout(location = 1) in vec3 radiance;\n' +
        'uniform mat4 mvp; out vec3 v_radiance;\n' +
        'void main() { v_radiance = radiance; gl_Position = mvp * vec4(pos, 1.0); }\n';
    function meshFs(inline) {
        return '#version 300 es\nprecision highp float;\n' + TONEMAP +
            'in vec3 v_radiance; out vec4 color;\n' +
            'void main() { color = ' + (inline ? 'tonemap(v_radiance)' : 'vec4(v_radiance, 1.0)') + '; }\n';
    }
    // Per texel: radiance from a light map over the UV layout (render/draw.c's VS_T, FS_T).
    var TEX_VS = '#version 300 es\n' +
        'layout(location = 0) in vec3 pos; layout(location = 3) in vec2 uv;\n' +
        'uniform mat4 mvp; out vec2 v_uv;\n' +
        'void main() { v_uv = uv; gl_Position = mvp * vec4(pos, 1.0); }\n';
    function texFs(inline) {
        return '#version 300 es\nprecision highp float;\n' + TONEMAP +
            'in vec2 v_uv; uniform highp sampler2D map; out vec4 color;\n' +
            'void main() { vec3 r = texture(map, v_uv).rgb; color = ' + (inline ? 'tonemap(r)' : 'vec4(r, 1.0)') + '; }\n';
    }
    var POST_VS = '#version 300 es\n' +
        'void main() { vec2 p = vec2(gl_VertexID == 1 ? 3.0 : -1.0, gl_VertexID == 2 ? 3.0 : -1.0); gl_Position = vec4(p, 0.0, 1.0); }\n';
    var POST_FS = '#version 300 es\nprecision highp float;\n' + TONEMAP +
        'uniform sampler2D hdr; out vec4 color;\n' +
        'void main() { vec3 c = texelFetch(hdr, ivec2(gl_FragCoord.xy), 0).rgb; color = tonemap(max(c, vec3(0.0))); }\n';

    // ---- point lights per pixel with cube shadow maps: render/pixel_lights.c, point lights ----
    var CUBE_RES = 1024;
    var DEPTH_VS = '#version 300 es\n' +
        'layout(location = 0) in vec3 pos; uniform mat4 vp; out vec3 w;\n' +
        'void main() { w = pos; gl_Position = vp * vec4(pos, 1.0); }\n';
    // Distance from the light; faces turned towards it pushed back by two texels plus their slope.
    var CUBE_FS = '#version 300 es\nprecision highp float;\n' +
        'in vec3 w; uniform vec3 light; uniform float texel; out vec4 dist;\n' +
        'void main() {\n' +
        '  float d = length(w - light);\n' +
        '  vec3 ng = normalize(cross(dFdx(w), dFdy(w)));\n' +
        '  float c = abs(dot(ng, (w - light) / d)), t = sqrt(max(0.0, 1.0 - c * c)) / max(c, 0.1);\n' +
        '  dist = vec4(d + (gl_FrontFacing ? (2.0 + 8.0 * t) * d * texel : 0.0));\n' +
        '}\n';
    var LIGHT_COMMON =
        'uniform vec3 lpos, colour; uniform highp samplerCube cube; uniform float texel, bias;\n' +
        'const float PI = 3.14159265358979;\n' +
        'float cube_lit(vec3 d, float dist, float step, int n) {\n' +
        '  vec3 w = normalize(d);\n' +
        '  vec3 t = normalize(abs(w.x) < 0.6 ? cross(w, vec3(1.0, 0.0, 0.0)) : cross(w, vec3(0.0, 1.0, 0.0)));\n' +
        '  vec3 b = cross(w, t);\n' +
        '  float lit = 0.0, h = 0.5 * float(n - 1), eps = 0.25 * dist * texel + bias;\n' +
        '  for (int i = 0; i < n; ++i) for (int j = 0; j < n; ++j) {\n' +
        '    vec3 q = d + ((float(i) - h) * t + (float(j) - h) * b) * step;\n' +
        '    lit += dist - eps <= texture(cube, q).r ? 1.0 : 0.0;\n' +
        '  }\n' +
        '  return lit / float(n * n);\n' +
        '}\n' +
        // Irradiance from the point light at p (normal n) and the share of the taps that see it.
        'vec4 point_light(vec3 p, vec3 n, int taps) {\n' +
        '  vec3 d0 = lpos - p;\n' +
        '  float r2 = dot(d0, d0), r = sqrt(r2);\n' +
        '  if (r <= 0.0) return vec4(0.0);\n' +
        '  float c = dot(n, d0 / r);\n' +
        '  float lit = cube_lit(p + n * 4.0 * r * texel - lpos, r, r * texel, taps);\n' +
        '  return vec4(c > 0.0 ? colour * c / r2 : vec3(0.0), lit);\n' +
        '}\n';
    var ADD_VS = '#version 300 es\n' +
        'layout(location = 0) in vec3 pos; layout(location = 2) in vec3 normal; layout(location = 4) in vec3 albedo;\n' +
        'layout(location = 5) in float visibility;\n' +
        'uniform mat4 mvp;\n' +
        'centroid out vec3 f_pos; centroid out vec3 f_nrm; centroid out vec3 f_alb; centroid out float f_vis;\n' +
        'void main() { f_pos = pos; f_nrm = normal; f_alb = albedo; f_vis = visibility; gl_Position = mvp * vec4(pos, 1.0); }\n';
    var ADD_FS = '#version 300 es\nprecision highp float;\n' + LIGHT_COMMON +
        'centroid in vec3 f_pos; centroid in vec3 f_nrm; centroid in vec3 f_alb; centroid in float f_vis; out vec4 color;\n' +
        'void main() {\n' +
        '  if (f_vis <= 0.0) discard;   // no vertex of the triangle sees the light: nothing leaks along seams\n' +
        '  vec4 e = point_light(f_pos, normalize(f_nrm), 3);\n' +
        '  if (e.r + e.g + e.b <= 0.0) discard;\n' +
        '  color = vec4(f_alb / PI * e.rgb * e.a, 1.0);\n' +
        '}\n';
    // Per vertex, into texel gl_VertexID of a float target: the irradiance the light gives the
    // vertex through one shadow-map tap (the CPU's one shadow ray), and whether it sees the light.
    var VERT_VS = '#version 300 es\n' +
        'layout(location = 0) in vec3 pos; layout(location = 2) in vec3 normal; uniform int width, height;\n' +
        'out vec3 v_pos; out vec3 v_nrm;\n' +
        'void main() {\n' +
        '  v_pos = pos; v_nrm = normal;\n' +
        '  vec2 t = (vec2(float(gl_VertexID % width), float(gl_VertexID / width)) + 0.5) / vec2(float(width), float(height));\n' +
        '  gl_Position = vec4(t * 2.0 - 1.0, 0.0, 1.0); gl_PointSize = 1.0;\n' +
        '}\n';
    var VERT_FS = '#version 300 es\nprecision highp float;\n' + LIGHT_COMMON +
        'in vec3 v_pos; in vec3 v_nrm; out vec4 color;\n' +
        'void main() { vec4 e = point_light(v_pos, normalize(v_nrm), 1); color = vec4(e.rgb * e.a, e.a); }\n';

    // ---- rays against the mesh in JavaScript (for what the CPU run times test with shadow
    // rays): a bounding-volume hierarchy of the triangles, split at the median of the longest
    // axis, and segment tests as geom/raycast.c's prt__raycaster_segment_clear (hits from t = 0
    // to the segment's length). ----
    function raycaster(positions, indices) {
        var nt = indices.length / 3, order = new Uint32Array(nt), cen = new Float32Array(nt * 3), i, k;
        for (i = 0; i < nt; ++i) {
            order[i] = i;
            for (k = 0; k < 3; ++k) cen[i * 3 + k] = (positions[indices[i * 3] * 3 + k] + positions[indices[i * 3 + 1] * 3 + k] + positions[indices[i * 3 + 2] * 3 + k]) / 3;
        }
        var boxes = [], kids = [], first = [], count = [];   // node: box [6], children or a range of `order`
        function build(lo, hi) {
            var node = boxes.length, b = [Infinity, Infinity, Infinity, -Infinity, -Infinity, -Infinity], c = [Infinity, Infinity, Infinity, -Infinity, -Infinity, -Infinity];
            for (var j = lo; j < hi; ++j) {
                var t = order[j];
                for (var v = 0; v < 3; ++v)
                    for (var a = 0; a < 3; ++a) {
                        var x = positions[indices[t * 3 + v] * 3 + a];
                        if (x < b[a]) b[a] = x;
                        if (x > b[3 + a]) b[3 + a] = x;
                    }
                for (a = 0; a < 3; ++a) { c[a] = Math.min(c[a], cen[t * 3 + a]); c[3 + a] = Math.max(c[3 + a], cen[t * 3 + a]); }
            }
            boxes.push(b); kids.push(null); first.push(lo); count.push(hi - lo);
            if (hi - lo <= 4) return node;
            var axis = 0;
            for (a = 1; a < 3; ++a) if (c[3 + a] - c[a] > c[3 + axis] - c[axis]) axis = a;
            var part = Array.prototype.slice.call(order.subarray(lo, hi)).sort(function (p, q) { return cen[p * 3 + axis] - cen[q * 3 + axis]; });
            order.set(part, lo);
            var mid = (lo + hi) >> 1;
            kids[node] = [build(lo, mid), build(mid, hi)];
            return node;
        }
        build(0, nt);
        function slab(b, o, inv, len) {
            var t0 = 0, t1 = len;
            for (var a = 0; a < 3; ++a) {
                var ta = (b[a] - o[a]) * inv[a], tb = (b[3 + a] - o[a]) * inv[a];
                if (ta > tb) { var s = ta; ta = tb; tb = s; }
                if (ta > t0) t0 = ta;
                if (tb < t1) t1 = tb;
                if (t0 > t1) return false;
            }
            return true;
        }
        function hits(t, o, d, len) {   // Moller-Trumbore, t in [0, len]
            var a = indices[t * 3] * 3, b = indices[t * 3 + 1] * 3, c = indices[t * 3 + 2] * 3;
            var e1 = [positions[b] - positions[a], positions[b + 1] - positions[a + 1], positions[b + 2] - positions[a + 2]];
            var e2 = [positions[c] - positions[a], positions[c + 1] - positions[a + 1], positions[c + 2] - positions[a + 2]];
            var pv = [d[1] * e2[2] - d[2] * e2[1], d[2] * e2[0] - d[0] * e2[2], d[0] * e2[1] - d[1] * e2[0]];
            var det = e1[0] * pv[0] + e1[1] * pv[1] + e1[2] * pv[2];
            if (det === 0) return false;
            var inv = 1 / det, tv = [o[0] - positions[a], o[1] - positions[a + 1], o[2] - positions[a + 2]];
            var u = (tv[0] * pv[0] + tv[1] * pv[1] + tv[2] * pv[2]) * inv;
            if (u < 0 || u > 1) return false;
            var qv = [tv[1] * e1[2] - tv[2] * e1[1], tv[2] * e1[0] - tv[0] * e1[2], tv[0] * e1[1] - tv[1] * e1[0]];
            var v = (d[0] * qv[0] + d[1] * qv[1] + d[2] * qv[2]) * inv;
            if (v < 0 || u + v > 1) return false;
            var tt = (e2[0] * qv[0] + e2[1] * qv[1] + e2[2] * qv[2]) * inv;
            return tt >= 0 && tt <= len;
        }
        return {
            segmentClear: function (a, b) {
                var d = [b[0] - a[0], b[1] - a[1], b[2] - a[2]], len = Math.hypot(d[0], d[1], d[2]);
                if (!(len > 0)) return true;
                d = [d[0] / len, d[1] / len, d[2] / len];
                var inv = [1 / d[0], 1 / d[1], 1 / d[2]], stack = [0];
                while (stack.length) {
                    var node = stack.pop();
                    if (!slab(boxes[node], a, inv, len)) continue;
                    if (kids[node]) { stack.push(kids[node][0], kids[node][1]); continue; }
                    for (var j = first[node]; j < first[node] + count[node]; ++j)
                        if (hits(order[j], a, d, len)) return false;
                }
                return true;
            }
        };
    }

    // The point lights' markers, drawn over the tone-mapped image (not part of prt render's).
    var MARK_VS = '#version 300 es\n' +
        'layout(location = 0) in vec3 pos; layout(location = 1) in float selected; uniform mat4 mvp; out float f_sel;\n' +
        'void main() { f_sel = selected; gl_Position = mvp * vec4(pos, 1.0); gl_PointSize = 11.0; }\n';
    var MARK_FS = '#version 300 es\nprecision highp float;\n' +
        'in float f_sel; out vec4 color;\n' +
        'void main() {\n' +
        '  float r = length(gl_PointCoord - 0.5) * 2.0;\n' +
        '  if (r > 1.0) discard;\n' +
        '  color = r > 0.6 ? vec4(0.0, 0.0, 0.0, 1.0) : f_sel > 0.5 ? vec4(1.0, 0.85, 0.2, 1.0) : vec4(1.0);\n' +
        '}\n';

    function parseLights(text) {
        var out = [];
        String(text).split('|').forEach(function (spec) {
            var parts = spec.replace(/^point:/, '').split(':'), pos = numbers(parts[0], 3), rgb = parts[1] ? numbers(parts[1], 3) : null;
            if (pos && rgb && parts.length === 2) out.push({position: pos, intensity: rgb});
        });
        return out;
    }

    function fail(text) {
        var m = document.getElementById('message');
        m.textContent = text;
        m.hidden = false;
        document.title = 'prt: ' + text;
    }

    function start() {
        var t0 = performance.now();
        var canvas = document.getElementById('view'), panel = document.getElementById('panel');
        var meta = PRT_DATA.meta, view = meta.view;
        var gl = canvas.getContext('webgl2', {antialias: false, alpha: false, depth: true, preserveDrawingBuffer: true});
        if (!gl) {
            fail('This page relights the scene with WebGL2, which this browser does not offer (or has turned off). ' +
                 'Open it in a current Firefox, Chrome, Edge or Safari with hardware acceleration on.');
            return;
        }
        if (!factory) { fail('method.js registered no relighting (PRT.method).'); return; }
        var dpr = window.devicePixelRatio || 1, W = Math.round(view.width * dpr), H = Math.round(view.height * dpr);
        canvas.width = W;
        canvas.height = H;

        var cache = {};
        function array(name) {
            if (!(name in cache)) {
                if (!PRT_DATA.arrays[name]) throw new Error('data.js holds no array ' + name);
                cache[name] = decode(PRT_DATA.arrays[name]);
            }
            return cache[name];
        }
        var positions = array('positions'), indices = array('indices'), nv = positions.length / 3;

        // Linear radiance into a multisampled half-float target, resolved and tone-mapped per
        // pixel, as prt render does (4 samples, RGBA16F); without float targets, tone-mapped per
        // fragment into the canvas.
        var floatTargets = !!gl.getExtension('EXT_color_buffer_float');
        var samples = Math.min(4, gl.getParameter(gl.MAX_SAMPLES));
        var meshProgram = compile(gl, MESH_VS, meshFs(!floatTargets)), postProgram = compile(gl, POST_VS, POST_FS);
        var msFbo = null, resolveFbo = null, resolveTex = null;
        if (floatTargets) {
            msFbo = gl.createFramebuffer();
            gl.bindFramebuffer(gl.FRAMEBUFFER, msFbo);
            var colour = gl.createRenderbuffer(), depthRb = gl.createRenderbuffer();
            gl.bindRenderbuffer(gl.RENDERBUFFER, colour);
            gl.renderbufferStorageMultisample(gl.RENDERBUFFER, samples, gl.RGBA16F, W, H);
            gl.framebufferRenderbuffer(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.RENDERBUFFER, colour);
            gl.bindRenderbuffer(gl.RENDERBUFFER, depthRb);
            gl.renderbufferStorageMultisample(gl.RENDERBUFFER, samples, gl.DEPTH24_STENCIL8, W, H);
            gl.framebufferRenderbuffer(gl.FRAMEBUFFER, gl.DEPTH_STENCIL_ATTACHMENT, gl.RENDERBUFFER, depthRb);
            resolveFbo = gl.createFramebuffer();
            resolveTex = gl.createTexture();
            gl.bindTexture(gl.TEXTURE_2D, resolveTex);
            gl.texStorage2D(gl.TEXTURE_2D, 1, gl.RGBA16F, W, H);
            gl.bindFramebuffer(gl.FRAMEBUFFER, resolveFbo);
            gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, resolveTex, 0);
            gl.bindFramebuffer(gl.FRAMEBUFFER, null);
        }

        var vao = gl.createVertexArray();
        gl.bindVertexArray(vao);
        var posBuf = gl.createBuffer();
        gl.bindBuffer(gl.ARRAY_BUFFER, posBuf);
        gl.bufferData(gl.ARRAY_BUFFER, positions, gl.STATIC_DRAW);
        gl.enableVertexAttribArray(0);
        gl.vertexAttribPointer(0, 3, gl.FLOAT, false, 0, 0);
        var nrmBuf = gl.createBuffer();
        gl.bindBuffer(gl.ARRAY_BUFFER, nrmBuf);
        gl.bufferData(gl.ARRAY_BUFFER, array('normals'), gl.STATIC_DRAW);
        gl.enableVertexAttribArray(2);
        gl.vertexAttribPointer(2, 3, gl.FLOAT, false, 0, 0);
        var radBuf = gl.createBuffer();
        gl.bindBuffer(gl.ARRAY_BUFFER, radBuf);
        gl.bufferData(gl.ARRAY_BUFFER, nv * 12, gl.DYNAMIC_DRAW);
        gl.enableVertexAttribArray(1);
        gl.vertexAttribPointer(1, 3, gl.FLOAT, false, 0, 0);
        var idxBuf = gl.createBuffer();
        gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, idxBuf);
        gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, indices, gl.STATIC_DRAW);
        gl.bindVertexArray(null);
        var postVao = gl.createVertexArray();

        var cam = {eye: view.eye.slice(), target: view.target.slice(), up: view.up.slice(), fov: view.fov};
        var exposure = view.exposure;
        var stats = {loadMs: 0, relightMs: 0, drawMs: 0, frames: 0};
        var relightNeeded = true, drawQueued = false, m = null;

        // ---- the panel ----
        function el(tag, text, parent) {
            var e = document.createElement(tag);
            if (text) e.textContent = text;
            (parent || panel).appendChild(e);
            return e;
        }
        var ui = {
            heading: function (text) { return el('h1', text); },
            note: function (text) { var e = el('div', text); e.className = 'note'; return e; },
            // A slider: o = {label, min, max, step, value, format(v), input(v)}; returns {set(v), get()}.
            slider: function (o) {
                var label = el('label'), input = document.createElement('input');
                input.type = 'range';
                input.min = o.min; input.max = o.max; input.step = o.step; input.value = o.value;
                function show() { label.textContent = o.label + ': ' + (o.format ? o.format(+input.value) : input.value); }
                input.addEventListener('input', function () { show(); o.input(+input.value); });
                panel.appendChild(input);
                show();
                return { set: function (v) { input.value = v; show(); }, get: function () { return +input.value; } };
            },
            button: function (text, click) { var b = el('button', text); b.addEventListener('click', click); return b; },
            // The environment's panel when the file has one (or when shown is true): yaw, pitch,
            // roll and intensity sliders bound to state.rotate and state.intensity (relighting as
            // they move). Returns {set(q)}: the hash's rotate=Y,P,R and intensity=K applied.
            environment: function (state, shown) {
                var sliders = {};
                if (shown === undefined ? meta.params.environment : shown) {
                    ui.heading('Environment');
                    ['yaw', 'pitch', 'roll'].forEach(function (name, k) {
                        sliders[name] = ui.slider({label: name + ' (degrees)', min: -180, max: 180, step: 1, value: state.rotate[k],
                                                   input: function (v) { state.rotate[k] = v; relightNeeded = true; redraw(); }});
                    });
                    sliders.intensity = ui.slider({label: 'intensity', min: 0, max: 4, step: 0.05, value: state.intensity,
                                                   input: function (v) { state.intensity = v; relightNeeded = true; redraw(); }});
                }
                return {
                    set: function (q) {
                        var r;
                        if (q.rotate && (r = numbers(q.rotate, 3))) {
                            state.rotate = r;
                            if (sliders.yaw) { sliders.yaw.set(r[0]); sliders.pitch.set(r[1]); sliders.roll.set(r[2]); }
                        }
                        if (q.intensity !== undefined && +q.intensity >= 0) {
                            state.intensity = +q.intensity;
                            if (sliders.intensity) sliders.intensity.set(state.intensity);
                        }
                    }
                };
            },
            checkbox: function (text, value, change) {
                var label = el('label'), box = document.createElement('input');
                box.type = 'checkbox';
                box.checked = value;
                label.appendChild(box);
                label.appendChild(document.createTextNode(' ' + text));
                box.addEventListener('change', function () { change(box.checked); });
                return { set: function (v) { box.checked = v; } };
            }
        };
        ui.heading(meta.source);
        ui.note(meta.title + ' (' + meta.method + '), ' + meta.kind + '; ' + meta.vertices + ' vertices, ' + meta.triangles + ' triangles');
        ui.note('Drag: orbit. Shift-drag: pan. Wheel: zoom.');
        var statsLine = ui.note('');
        var exposureSlider = ui.slider({label: 'exposure (stops)', min: -6, max: 6, step: 0.1, value: exposure,
                                        input: function (v) { exposure = v; redraw(); }});
        ui.button('reset view', function () {
            cam = {eye: view.eye.slice(), target: view.target.slice(), up: view.up.slice(), fov: view.fov};
            redraw();
        });

        // ---- point lights (api.pointLights): shadow cubes, the per-pixel pass, per-vertex irradiance ----
        // ---- a light map (api.lightMap): relight() then returns width x height x 3 texels ----
        var lightMapTex = null, lightMapW = 0, lightMapH = 0, texProgram = null, texUpload = null;
        function lightMap(w, h) {
            var linear = !!gl.getExtension('OES_texture_float_linear');
            lightMapW = w;
            lightMapH = h;
            lightMapTex = gl.createTexture();
            gl.bindTexture(gl.TEXTURE_2D, lightMapTex);
            // Filtered as prt render's per-texel path samples its map (RGBA32F, linear); halves
            // where the browser cannot filter floats.
            gl.texStorage2D(gl.TEXTURE_2D, 1, linear ? gl.RGBA32F : gl.RGBA16F, w, h);
            gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.LINEAR);
            gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.LINEAR);
            gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_S, gl.CLAMP_TO_EDGE);
            gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_T, gl.CLAMP_TO_EDGE);
            texUpload = new Float32Array(w * h * 4);
            texProgram = compile(gl, TEX_VS, texFs(!floatTargets));
            gl.bindVertexArray(vao);
            var uvBuf = gl.createBuffer();
            gl.bindBuffer(gl.ARRAY_BUFFER, uvBuf);
            gl.bufferData(gl.ARRAY_BUFFER, array('uv'), gl.STATIC_DRAW);
            gl.enableVertexAttribArray(3);
            gl.vertexAttribPointer(3, 2, gl.FLOAT, false, 0, 0);
            gl.bindVertexArray(null);
        }

        var lights = null, rays = null, customPass = null;
        function pointLights(o) {
            if (!floatTargets) throw new Error('point lights need float render targets (EXT_color_buffer_float), which this browser does not offer');
            var lo = meta.lo, hi = meta.hi, diag = Math.max(Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]), 1e-6);
            var L = {list: [], albedoBuf: gl.createBuffer(), visBuf: [], cube: [], dirty: [], selected: 0,
                     diag: diag, panel: null};
            gl.bindBuffer(gl.ARRAY_BUFFER, L.albedoBuf);
            gl.bufferData(gl.ARRAY_BUFFER, o.albedo, gl.STATIC_DRAW);
            L.cubeProgram = compile(gl, DEPTH_VS, CUBE_FS);
            L.addProgram = compile(gl, ADD_VS, ADD_FS);
            L.vertProgram = compile(gl, VERT_VS, VERT_FS);
            L.fbo = gl.createFramebuffer();
            L.depth = gl.createRenderbuffer();
            gl.bindRenderbuffer(gl.RENDERBUFFER, L.depth);
            gl.renderbufferStorage(gl.RENDERBUFFER, gl.DEPTH_COMPONENT24, CUBE_RES, CUBE_RES);
            // A set of points (positions, normals) the lights are evaluated at, on the GPU: the
            // mesh's vertices, or a method's own (light-map texels' shadow samples).
            L.points = function (pos, nrm) {
                var P = {count: pos.length / 3, vao: gl.createVertexArray(), cache: []};
                gl.bindVertexArray(P.vao);
                [pos, nrm].forEach(function (a, k) {
                    var buf = gl.createBuffer();
                    gl.bindBuffer(gl.ARRAY_BUFFER, buf);
                    gl.bufferData(gl.ARRAY_BUFFER, a, gl.STATIC_DRAW);
                    gl.enableVertexAttribArray(k * 2);   // locations 0 and 2, as the mesh's
                    gl.vertexAttribPointer(k * 2, 3, gl.FLOAT, false, 0, 0);
                });
                gl.bindVertexArray(null);
                P.w = Math.min(P.count, 2048);
                P.h = Math.ceil(P.count / P.w);
                P.tex = gl.createTexture();
                gl.bindTexture(gl.TEXTURE_2D, P.tex);
                gl.texStorage2D(gl.TEXTURE_2D, 1, gl.RGBA32F, P.w, P.h);
                if (pos !== positions) L.sets.push(P);
                P.fbo = gl.createFramebuffer();
                gl.bindFramebuffer(gl.FRAMEBUFFER, P.fbo);
                gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, P.tex, 0);
                gl.bindFramebuffer(gl.FRAMEBUFFER, null);
                return P;
            };
            L.meshPoints = null;
            L.set = function (list) {
                list = list.slice(0, view.max_pixel_lights);   // prt render draws at most this many per pixel
                L.list = list.map(function (l) { return {position: l.position.slice(), intensity: l.intensity.slice()}; });
                L.dirty = L.list.map(function () { return true; });
                L.sets.concat(L.meshPoints ? [L.meshPoints] : []).forEach(function (P) { P.cache = []; });
                L.selected = Math.min(L.selected, Math.max(0, L.list.length - 1));
                L.buildPanel();
                relightNeeded = true;
            };
            L.moved = function (i) { L.dirty[i] = true; L.forget(i); relightNeeded = true; redraw(); };
            // The shadow cube of light i (render/pixel_lights.c: R32F distances, 6 faces of 90 degrees).
            L.shadow = function (i) {
                if (!L.dirty[i] && L.cube[i]) return;
                var pos = L.list[i].position;
                if (!L.cube[i]) {
                    L.cube[i] = gl.createTexture();
                    gl.bindTexture(gl.TEXTURE_CUBE_MAP, L.cube[i]);
                    gl.texStorage2D(gl.TEXTURE_CUBE_MAP, 1, gl.R32F, CUBE_RES, CUBE_RES);
                    gl.texParameteri(gl.TEXTURE_CUBE_MAP, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
                    gl.texParameteri(gl.TEXTURE_CUBE_MAP, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
                    gl.texParameteri(gl.TEXTURE_CUBE_MAP, gl.TEXTURE_WRAP_S, gl.CLAMP_TO_EDGE);
                    gl.texParameteri(gl.TEXTURE_CUBE_MAP, gl.TEXTURE_WRAP_T, gl.CLAMP_TO_EDGE);
                }
                var far = 0;
                for (var corner = 0; corner < 8; ++corner) {
                    var q = [corner & 1 ? hi[0] : lo[0], corner & 2 ? hi[1] : lo[1], corner & 4 ? hi[2] : lo[2]];
                    far = Math.max(far, Math.hypot(q[0] - pos[0], q[1] - pos[1], q[2] - pos[2]));
                }
                var nf = [diag * 1e-4, far * 1.01 + diag * 1e-3];
                var look = [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]];
                var ups = [[0, -1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1], [0, -1, 0], [0, -1, 0]];
                gl.bindFramebuffer(gl.FRAMEBUFFER, L.fbo);
                gl.framebufferRenderbuffer(gl.FRAMEBUFFER, gl.DEPTH_ATTACHMENT, gl.RENDERBUFFER, L.depth);
                gl.viewport(0, 0, CUBE_RES, CUBE_RES);
                gl.enable(gl.DEPTH_TEST);
                gl.depthFunc(gl.LESS);
                gl.disable(gl.BLEND);
                gl.useProgram(L.cubeProgram);
                gl.uniform3fv(gl.getUniformLocation(L.cubeProgram, 'light'), pos);
                gl.uniform1f(gl.getUniformLocation(L.cubeProgram, 'texel'), 2 / CUBE_RES);
                gl.bindVertexArray(vao);
                for (var f = 0; f < 6; ++f) {
                    gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_CUBE_MAP_POSITIVE_X + f, L.cube[i], 0);
                    gl.clearBufferfv(gl.COLOR, 0, [1e30, 1e30, 1e30, 1e30]);
                    gl.clear(gl.DEPTH_BUFFER_BIT);
                    var target = [pos[0] + look[f][0], pos[1] + look[f][1], pos[2] + look[f][2]];
                    gl.uniformMatrix4fv(gl.getUniformLocation(L.cubeProgram, 'vp'), false, cameraMatrix(pos, target, ups[f], 90, 1, nf));
                    gl.drawElements(gl.TRIANGLES, indices.length, gl.UNSIGNED_INT, 0);
                }
                gl.bindVertexArray(null);
                gl.bindFramebuffer(gl.FRAMEBUFFER, null);
                L.dirty[i] = false;
            };
            function lightUniforms(program, i) {
                var l = L.list[i];
                gl.uniform3fv(gl.getUniformLocation(program, 'lpos'), l.position);
                gl.uniform3fv(gl.getUniformLocation(program, 'colour'), l.intensity);
                gl.uniform1f(gl.getUniformLocation(program, 'texel'), 2 / CUBE_RES);
                gl.uniform1f(gl.getUniformLocation(program, 'bias'), diag * 2e-5);
                gl.activeTexture(gl.TEXTURE0);
                gl.bindTexture(gl.TEXTURE_CUBE_MAP, L.cube[i]);
                gl.uniform1i(gl.getUniformLocation(program, 'cube'), 0);
            }
            // Light i at every point of set P: Float32Array of count x (E r, g, b, visible), cached
            // until the light changes.
            L.atPoints = function (i, P) {
                if (P.cache[i]) return P.cache[i];
                L.shadow(i);
                gl.bindFramebuffer(gl.FRAMEBUFFER, P.fbo);
                gl.viewport(0, 0, P.w, P.h);
                gl.disable(gl.DEPTH_TEST);
                gl.disable(gl.BLEND);
                gl.clearBufferfv(gl.COLOR, 0, [0, 0, 0, 0]);
                gl.useProgram(L.vertProgram);
                lightUniforms(L.vertProgram, i);
                gl.uniform1i(gl.getUniformLocation(L.vertProgram, 'width'), P.w);
                gl.uniform1i(gl.getUniformLocation(L.vertProgram, 'height'), P.h);
                gl.bindVertexArray(P.vao);
                gl.drawArrays(gl.POINTS, 0, P.count);
                gl.bindVertexArray(null);
                var px = new Float32Array(P.w * P.h * 4);
                gl.readPixels(0, 0, P.w, P.h, gl.RGBA, gl.FLOAT, px);
                gl.bindFramebuffer(gl.FRAMEBUFFER, null);
                return (P.cache[i] = px.subarray(0, P.count * 4));
            };
            // Light i at every vertex; also the per-pixel pass's gate (which vertices see it).
            L.atVertices = function (i) {
                if (!L.meshPoints) L.meshPoints = L.points(positions, array('normals'));
                var fresh = !L.meshPoints.cache[i], px = L.atPoints(i, L.meshPoints);
                if (fresh || !L.visBuf[i]) {
                    var vis = new Float32Array(nv);
                    for (var v = 0; v < nv; ++v) vis[v] = px[v * 4 + 3];
                    if (!L.visBuf[i]) L.visBuf[i] = gl.createBuffer();
                    gl.bindBuffer(gl.ARRAY_BUFFER, L.visBuf[i]);
                    gl.bufferData(gl.ARRAY_BUFFER, vis, gl.DYNAMIC_DRAW);
                }
                return px;
            };
            L.sets = [];
            L.forget = function (i) { L.sets.concat(L.meshPoints ? [L.meshPoints] : []).forEach(function (P) { P.cache[i] = null; }); };
            // Added per pixel on top of the mesh (drawn into the bound target, depth kept).
            L.draw = function (mvp) {
                if (!L.list.length || o.perPixel === false) return;
                for (var k = 0; k < L.list.length; ++k) L.atVertices(k);   // the gates' visibility and the shadow cubes, first
                gl.bindFramebuffer(gl.FRAMEBUFFER, msFbo);
                gl.viewport(0, 0, W, H);
                gl.enable(gl.BLEND);
                gl.blendFunc(gl.ONE, gl.ONE);
                gl.depthFunc(gl.LEQUAL);
                gl.depthMask(false);
                gl.enable(gl.POLYGON_OFFSET_FILL);
                gl.polygonOffset(-1, -4);
                gl.enable(gl.STENCIL_TEST);   // each sample takes a light once: coincident faces pass together
                gl.stencilFunc(gl.EQUAL, 0, 0xff);
                gl.stencilOp(gl.KEEP, gl.KEEP, gl.INCR);
                gl.useProgram(L.addProgram);
                gl.uniformMatrix4fv(gl.getUniformLocation(L.addProgram, 'mvp'), false, mvp);
                gl.bindVertexArray(vao);
                gl.bindBuffer(gl.ARRAY_BUFFER, L.albedoBuf);
                gl.enableVertexAttribArray(4);
                gl.vertexAttribPointer(4, 3, gl.FLOAT, false, 0, 0);
                gl.enableVertexAttribArray(5);
                for (var i = 0; i < L.list.length; ++i) {
                    gl.clear(gl.STENCIL_BUFFER_BIT);
                    gl.bindBuffer(gl.ARRAY_BUFFER, L.visBuf[i]);
                    gl.vertexAttribPointer(5, 1, gl.FLOAT, false, 0, 0);
                    lightUniforms(L.addProgram, i);
                    gl.drawElements(gl.TRIANGLES, indices.length, gl.UNSIGNED_INT, 0);
                }
                gl.disableVertexAttribArray(4);
                gl.disableVertexAttribArray(5);
                gl.bindVertexArray(null);
                gl.disable(gl.STENCIL_TEST);
                gl.disable(gl.POLYGON_OFFSET_FILL);
                gl.disable(gl.BLEND);
                gl.depthMask(true);
                gl.depthFunc(gl.LESS);
            };
            // The panel: each light's position and intensity, add and remove; ctrl-drag moves the
            // selected light across the view.
            L.buildPanel = function () {
                if (!L.panel) {
                    ui.heading('Point lights');
                    ui.note('Ctrl-drag (or alt-drag) moves the selected light across the view; the wheel with ctrl moves it nearer or farther.');
                    ui.checkbox('show the lights (markers, not part of the image)', true, function (v) { L.markers = v; redraw(); });
                    ui.button('add a light', function () {
                        if (L.list.length >= view.max_pixel_lights) return;
                        var c = [(lo[0] + hi[0]) / 2, lo[1] + 0.8 * (hi[1] - lo[1]), (lo[2] + hi[2]) / 2];
                        var k = L.list.length ? L.list[L.list.length - 1].intensity.slice() : [diag * diag / 4, diag * diag / 4, diag * diag / 4];
                        L.set(L.list.concat([{position: c, intensity: k}]));
                        L.selected = L.list.length - 1;
                        L.buildPanel();
                        redraw();
                    });
                    L.panel = el('div');
                }
                L.panel.textContent = '';
                L.list.forEach(function (l, i) {
                    var box = el('div', null, L.panel);
                    box.style.borderTop = '1px solid #444';
                    box.style.marginTop = '6px';
                    var head = el('label', 'light ' + (i + 1) + (i === L.selected ? ' (selected)' : ''), box);
                    head.style.cursor = 'pointer';
                    head.addEventListener('click', function () { L.selected = i; L.buildPanel(); });
                    ['x', 'y', 'z'].forEach(function (axis, k) {
                        var pad = 0.5 * (hi[k] - lo[k]) + 0.1 * diag;
                        sliderIn(box, {label: axis, min: lo[k] - pad, max: hi[k] + pad, step: diag / 1000, value: l.position[k],
                                       format: function (v) { return v.toFixed(3); },
                                       input: function (v) { l.position[k] = v; L.selected = i; L.moved(i); }});
                    });
                    var base = l.intensity.slice(), peak = Math.max(base[0], base[1], base[2]) || 1;
                    sliderIn(box, {label: 'intensity (W/sr, brightest channel)', min: 0, max: 4 * peak, step: peak / 100, value: peak,
                                   format: function (v) { return v.toFixed(2); },
                                   input: function (v) { for (var c = 0; c < 3; ++c) l.intensity[c] = base[c] / peak * v; L.forget(i); relightNeeded = true; redraw(); }});
                    var rm = el('button', 'remove', box);
                    rm.addEventListener('click', function () { L.set(L.list.filter(function (x, j) { return j !== i; })); redraw(); });
                });
            };
            L.markers = true;
            L.markProgram = compile(gl, MARK_VS, MARK_FS);
            L.markVao = gl.createVertexArray();
            L.markBuf = gl.createBuffer();
            L.drawMarkers = function (mvp) {
                if (!L.markers || !L.list.length) return;
                var data = new Float32Array(L.list.length * 4);
                L.list.forEach(function (l, i) { data.set([l.position[0], l.position[1], l.position[2], i === L.selected ? 1 : 0], i * 4); });
                gl.bindVertexArray(L.markVao);
                gl.bindBuffer(gl.ARRAY_BUFFER, L.markBuf);
                gl.bufferData(gl.ARRAY_BUFFER, data, gl.DYNAMIC_DRAW);
                gl.enableVertexAttribArray(0);
                gl.vertexAttribPointer(0, 3, gl.FLOAT, false, 16, 0);
                gl.enableVertexAttribArray(1);
                gl.vertexAttribPointer(1, 1, gl.FLOAT, false, 16, 12);
                gl.disable(gl.DEPTH_TEST);
                gl.useProgram(L.markProgram);
                gl.uniformMatrix4fv(gl.getUniformLocation(L.markProgram, 'mvp'), false, mvp);
                gl.drawArrays(gl.POINTS, 0, L.list.length);
                gl.bindVertexArray(null);
            };
            L.set(o.lights);
            lights = L;
            return L;
        }
        function sliderIn(parent, o) {
            var label = el('label', null, parent), input = document.createElement('input');
            input.type = 'range';
            input.min = o.min; input.max = o.max; input.step = o.step; input.value = o.value;
            function show() { label.textContent = o.label + ': ' + (o.format ? o.format(+input.value) : input.value); }
            input.addEventListener('input', function () { show(); o.input(+input.value); });
            parent.appendChild(input);
            show();
        }

        var api = {
            gl: gl, meta: meta.params, vertexCount: nv, array: array, ui: ui, numbers: numbers,
            // Point lights drawn per pixel with shadow maps on top of the method's radiance, which
            // then holds everything else (o = {albedo, lights: [{position, intensity}], perPixel: false when
            // the method's radiance holds their direct light too}, at most view.max_pixel_lights); returns
            // {list, atVertices(i)}. Hash: lights=X,Y,Z:R,G,B|X,Y,Z:R,G,B.
            pointLights: pointLights,
            // Segment tests against the mesh ({segmentClear(a, b)}), built on first use.
            raycaster: function () { return rays || (rays = raycaster(positions, indices)); },
            // Drawing from a light map over the mesh's UVs (data.js array 'uv'): relight() then
            // returns width x height x 3 texels (row 0 at v = 0) instead of per-vertex radiance.
            lightMap: lightMap,
            // A mesh pass of the method's own instead of the framework's (per-pixel view factors):
            // fn(mvp, eye) draws into the bound linear target, depth test on; float targets only.
            meshPass: function (fn) {
                if (!floatTargets) throw new Error('this page draws per pixel into float render targets (EXT_color_buffer_float), which this browser does not offer');
                customPass = fn;
            },
            compile: function (vs, fs) { return compile(gl, vs, fs); },
            floatLinear: !!gl.getExtension('OES_texture_float_linear'),
            // The method calls this when its lighting changed (a control moved).
            relight: function () { relightNeeded = true; redraw(); }
        };
        try {
            m = factory(api);
        } catch (e) { fail('The method\'s script failed: ' + e.message); throw e; }

        function draw() {
            drawQueued = false;
            var t = performance.now();
            if (relightNeeded) {
                relightNeeded = false;
                var radiance = m.relight();
                if (lightMapTex) {
                    for (var i = 0; i < lightMapW * lightMapH; ++i) {
                        texUpload[i * 4] = radiance[i * 3];
                        texUpload[i * 4 + 1] = radiance[i * 3 + 1];
                        texUpload[i * 4 + 2] = radiance[i * 3 + 2];
                        texUpload[i * 4 + 3] = 1;
                    }
                    gl.bindTexture(gl.TEXTURE_2D, lightMapTex);
                    gl.texSubImage2D(gl.TEXTURE_2D, 0, 0, 0, lightMapW, lightMapH, gl.RGBA, gl.FLOAT, texUpload);
                } else {
                    gl.bindBuffer(gl.ARRAY_BUFFER, radBuf);
                    gl.bufferSubData(gl.ARRAY_BUFFER, 0, radiance);
                }
                stats.relightMs = performance.now() - t;
            }
            var mvp = cameraMatrix(cam.eye, cam.target, cam.up, cam.fov, view.width / view.height);
            var scale = Math.pow(2, exposure), bg = view.background;
            gl.bindFramebuffer(gl.FRAMEBUFFER, msFbo);
            gl.viewport(0, 0, W, H);
            gl.enable(gl.DEPTH_TEST);
            gl.disable(gl.CULL_FACE);   // one-sided walls show from both sides, as in prt render
            var program = lightMapTex ? texProgram : meshProgram;
            gl.useProgram(program);
            gl.uniformMatrix4fv(gl.getUniformLocation(program, 'mvp'), false, mvp);
            if (lightMapTex) {
                gl.activeTexture(gl.TEXTURE0);
                gl.bindTexture(gl.TEXTURE_2D, lightMapTex);
                gl.uniform1i(gl.getUniformLocation(program, 'map'), 0);
            }
            if (floatTargets) {
                gl.clearBufferfv(gl.COLOR, 0, [bg[0], bg[1], bg[2], 1]);
            } else {
                // The background tone-mapped as any radiance is.
                var c = bg.map(function (x) { return x * scale; }), lum = 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
                var k = view.clamp || !(lum > 0) ? 1 : 1 / (1 + lum);
                c = c.map(function (x) { x = Math.min(Math.max(x * k, 0), 1); return x <= 0.0031308 ? 12.92 * x : 1.055 * Math.pow(x, 1 / 2.4) - 0.055; });
                gl.clearColor(c[0], c[1], c[2], 1);
                gl.clear(gl.COLOR_BUFFER_BIT);
                gl.uniform1f(gl.getUniformLocation(program, 'u_scale'), scale);
                gl.uniform1i(gl.getUniformLocation(program, 'u_clamp'), view.clamp ? 1 : 0);
            }
            gl.clear(gl.DEPTH_BUFFER_BIT);
            if (customPass) {
                customPass(mvp, cam.eye);
            } else {
                gl.bindVertexArray(vao);
                gl.drawElements(gl.TRIANGLES, indices.length, gl.UNSIGNED_INT, 0);
                gl.bindVertexArray(null);
            }
            if (lights && floatTargets) lights.draw(mvp);
            if (floatTargets) {
                gl.bindFramebuffer(gl.READ_FRAMEBUFFER, msFbo);
                gl.bindFramebuffer(gl.DRAW_FRAMEBUFFER, resolveFbo);
                gl.blitFramebuffer(0, 0, W, H, 0, 0, W, H, gl.COLOR_BUFFER_BIT, gl.NEAREST);
                gl.bindFramebuffer(gl.FRAMEBUFFER, null);
                gl.disable(gl.DEPTH_TEST);
                gl.useProgram(postProgram);
                gl.activeTexture(gl.TEXTURE0);
                gl.bindTexture(gl.TEXTURE_2D, resolveTex);
                gl.uniform1i(gl.getUniformLocation(postProgram, 'hdr'), 0);
                gl.uniform1f(gl.getUniformLocation(postProgram, 'u_scale'), scale);
                gl.uniform1i(gl.getUniformLocation(postProgram, 'u_clamp'), view.clamp ? 1 : 0);
                gl.bindVertexArray(postVao);
                gl.drawArrays(gl.TRIANGLES, 0, 3);
                gl.bindVertexArray(null);
            }
            if (lights) {
                gl.bindFramebuffer(gl.FRAMEBUFFER, null);
                gl.viewport(0, 0, W, H);
                lights.drawMarkers(mvp);
            }
            stats.drawMs = performance.now() - t;
            stats.frames++;
            statsLine.textContent = 'loaded in ' + stats.loadMs.toFixed(0) + ' ms; relit in ' + stats.relightMs.toFixed(1) + ' ms' +
                (floatTargets ? '' : ' (no float render targets: tone-mapped per fragment)');
        }
        function redraw() {
            if (!drawQueued) { drawQueued = true; requestAnimationFrame(draw); }
        }

        function apply(params) {
            var v;
            if (params.eye && (v = numbers(params.eye, 3))) cam.eye = v;
            if (params.target && (v = numbers(params.target, 3))) cam.target = v;
            if (params.fov && isFinite(+params.fov)) cam.fov = +params.fov;
            if (params.exposure !== undefined && isFinite(+params.exposure)) { exposure = +params.exposure; exposureSlider.set(exposure); }
            if (params.lights !== undefined && lights) lights.set(parseLights(params.lights));
            if (params.markers !== undefined && lights) lights.markers = params.markers !== '0';
            var rest = {};
            for (var k in params)
                if (['eye', 'target', 'fov', 'exposure', 'lights', 'markers'].indexOf(k) < 0) rest[k] = params[k];
            if (m.set) m.set(rest);
            relightNeeded = true;
        }

        // ---- orbit, pan and zoom about the target ----
        var drag = null;
        canvas.addEventListener('pointerdown', function (e) {
            drag = {x: e.clientX, y: e.clientY, pan: e.shiftKey || e.button === 2, light: (e.ctrlKey || e.altKey) && lights && lights.list.length > 0};
            canvas.setPointerCapture(e.pointerId);
        });
        canvas.addEventListener('pointerup', function () { drag = null; });
        canvas.addEventListener('contextmenu', function (e) { e.preventDefault(); });
        canvas.addEventListener('pointermove', function (e) {
            if (!drag) return;
            var dx = e.clientX - drag.x, dy = e.clientY - drag.y;
            drag.x = e.clientX;
            drag.y = e.clientY;
            var o = [cam.eye[0] - cam.target[0], cam.eye[1] - cam.target[1], cam.eye[2] - cam.target[2]];
            var r = Math.hypot(o[0], o[1], o[2]);
            if (drag.light) {
                // Across the view plane through the light, a pixel's worth at its distance per pixel.
                var l = lights.list[lights.selected], fw = [cam.target[0] - cam.eye[0], cam.target[1] - cam.eye[1], cam.target[2] - cam.eye[2]];
                var fl = Math.hypot(fw[0], fw[1], fw[2]);
                fw = [fw[0] / fl, fw[1] / fl, fw[2] / fl];
                var sx = [fw[1] * 0 - fw[2] * 1, fw[2] * 0 - fw[0] * 0, fw[0] * 1 - fw[1] * 0], sxl = Math.hypot(sx[0], sx[1], sx[2]) || 1;
                sx = [sx[0] / sxl, sx[1] / sxl, sx[2] / sxl];
                var uy = [sx[1] * fw[2] - sx[2] * fw[1], sx[2] * fw[0] - sx[0] * fw[2], sx[0] * fw[1] - sx[1] * fw[0]];
                var dl = Math.hypot(l.position[0] - cam.eye[0], l.position[1] - cam.eye[1], l.position[2] - cam.eye[2]);
                var kk = dl * Math.tan(cam.fov * Math.PI / 360) * 2 / view.height;
                for (var j = 0; j < 3; ++j) l.position[j] += (dx * sx[j] - dy * uy[j]) * kk;
                lights.moved(lights.selected);
                lights.buildPanel();
                return;
            }
            if (drag.pan) {
                var f = [-o[0] / r, -o[1] / r, -o[2] / r], s = [f[2], 0, -f[0]], sl = Math.hypot(s[0], s[2]) || 1;
                s = [-s[0] / sl, 0, -s[2] / sl];
                var u = [s[1] * f[2] - s[2] * f[1], s[2] * f[0] - s[0] * f[2], s[0] * f[1] - s[1] * f[0]];
                var k = r * Math.tan(cam.fov * Math.PI / 360) * 2 / view.height;
                for (var i = 0; i < 3; ++i) {
                    var d = -dx * k * s[i] + dy * k * u[i];
                    cam.eye[i] += d;
                    cam.target[i] += d;
                }
            } else {
                var yaw = Math.atan2(o[0], o[2]) - dx * 0.008, pitch = Math.asin(Math.max(-1, Math.min(1, o[1] / r))) + dy * 0.008;
                pitch = Math.max(-1.55, Math.min(1.55, pitch));
                cam.eye = [cam.target[0] + r * Math.cos(pitch) * Math.sin(yaw), cam.target[1] + r * Math.sin(pitch),
                           cam.target[2] + r * Math.cos(pitch) * Math.cos(yaw)];
            }
            redraw();
        });
        canvas.addEventListener('wheel', function (e) {
            e.preventDefault();
            var k = Math.exp(Math.max(-1, Math.min(1, e.deltaY * 0.001)));
            if ((e.ctrlKey || e.altKey) && lights && lights.list.length) {
                var l = lights.list[lights.selected];
                for (var j = 0; j < 3; ++j) l.position[j] = cam.eye[j] + (l.position[j] - cam.eye[j]) * k;
                lights.moved(lights.selected);
                lights.buildPanel();
                return;
            }
            for (var i = 0; i < 3; ++i) cam.eye[i] = cam.target[i] + (cam.eye[i] - cam.target[i]) * k;
            redraw();
        }, {passive: false});
        window.addEventListener('hashchange', function () { apply(parseHash()); redraw(); });

        apply(parseHash());
        draw();   // at once: a screenshot taken at the load event has the first frame
        gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, new Uint8Array(4));   // waits for it
        stats.loadMs = performance.now();   // since the page was asked for: data.js's parsing counts
        stats.setupMs = stats.loadMs - t0;
        draw();
        window.prtPage = {
            set: function (params) { apply(params); draw(); },
            stats: stats
        };
        document.body.setAttribute('data-prt-ready', stats.loadMs.toFixed(1));
    }

    return { method: method, start: start, euler: euler, shRotate: shRotate };
})();
