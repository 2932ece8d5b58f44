// prt export --web: the page's framework (prt.js). It draws the mesh with per-vertex linear
// radiance, holds the camera (prt render's matrix), tone-maps as prt render's PNGs do (exposure,
// Reinhard on luminance or clamp, sRGB) and builds the panel; the method's script (method.js)
// registers with PRT.method(function (api) { ... return {relight: ..., set: ...}; }) and hands
// back per-vertex radiance whenever the lighting changes. Plain classic script: pages opened from
// the file system may use neither fetch nor modules.
//
// URL hash parameters (#rotate=90,0,0&intensity=2) set the state at load and on change; the
// framework's are eye=X,Y,Z target=X,Y,Z fov=DEG exposure=STOPS, the rest go to the method.
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
    function cameraMatrix(eye, target, upIn, fovDeg, aspect) {
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
        var fov = (fovDeg > 0 ? fovDeg : 40) * Math.PI / 180, n = dist * 0.01, fa = dist * 100, t = 1 / Math.tan(fov * 0.5);
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
    var POST_VS = '#version 300 es\n' +
        'void main() { vec2 p = vec2(gl_VertexID == 1 ? 3.0 : -1.0, gl_VertexID == 2 ? 3.0 : -1.0); gl_Position = vec4(p, 0.0, 1.0); }\n';
    var POST_FS = '#version 300 es\nprecision highp float;\n' + TONEMAP +
        'uniform sampler2D hdr; out vec4 color;\n' +
        'void main() { vec3 c = texelFetch(hdr, ivec2(gl_FragCoord.xy), 0).rgb; color = tonemap(max(c, vec3(0.0))); }\n';

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

        var api = {
            gl: gl, meta: meta.params, vertexCount: nv, array: array, ui: ui, numbers: numbers,
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
                gl.bindBuffer(gl.ARRAY_BUFFER, radBuf);
                gl.bufferSubData(gl.ARRAY_BUFFER, 0, radiance);
                stats.relightMs = performance.now() - t;
            }
            var mvp = cameraMatrix(cam.eye, cam.target, cam.up, cam.fov, view.width / view.height);
            var scale = Math.pow(2, exposure), bg = view.background;
            gl.bindFramebuffer(gl.FRAMEBUFFER, msFbo);
            gl.viewport(0, 0, W, H);
            gl.enable(gl.DEPTH_TEST);
            gl.disable(gl.CULL_FACE);   // one-sided walls show from both sides, as in prt render
            gl.useProgram(meshProgram);
            gl.uniformMatrix4fv(gl.getUniformLocation(meshProgram, 'mvp'), false, mvp);
            if (floatTargets) {
                gl.clearBufferfv(gl.COLOR, 0, [bg[0], bg[1], bg[2], 1]);
            } else {
                // The background tone-mapped as any radiance is.
                var c = bg.map(function (x) { return x * scale; }), lum = 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
                var k = view.clamp || !(lum > 0) ? 1 : 1 / (1 + lum);
                c = c.map(function (x) { x = Math.min(Math.max(x * k, 0), 1); return x <= 0.0031308 ? 12.92 * x : 1.055 * Math.pow(x, 1 / 2.4) - 0.055; });
                gl.clearColor(c[0], c[1], c[2], 1);
                gl.clear(gl.COLOR_BUFFER_BIT);
                gl.uniform1f(gl.getUniformLocation(meshProgram, 'u_scale'), scale);
                gl.uniform1i(gl.getUniformLocation(meshProgram, 'u_clamp'), view.clamp ? 1 : 0);
            }
            gl.clear(gl.DEPTH_BUFFER_BIT);
            gl.bindVertexArray(vao);
            gl.drawElements(gl.TRIANGLES, indices.length, gl.UNSIGNED_INT, 0);
            gl.bindVertexArray(null);
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
            var rest = {};
            for (var k in params)
                if (['eye', 'target', 'fov', 'exposure'].indexOf(k) < 0) rest[k] = params[k];
            if (m.set) m.set(rest);
            relightNeeded = true;
        }

        // ---- orbit, pan and zoom about the target ----
        var drag = null;
        canvas.addEventListener('pointerdown', function (e) {
            drag = {x: e.clientX, y: e.clientY, pan: e.shiftKey || e.button === 2};
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

    return { method: method, start: start };
})();
