// rrcache's WebGL2 runtime: the original shader and its cached variant side by side.
//
// The same cache as rrcache.runtime.CacheRuntime (Python, moderngl), written for WebGL2: two
// ping-pong payload and inverse-depth targets, one depth buffer shared by the passes, the refresh
// rule's uniforms (rrcache.runtime.refresh), the passes in the algorithm's order with the depth
// tests of rrcache/runtime/cache.py's docstring. The scene (meshes, per-frame uniforms, textures)
// is baked into the page (rrcache.webgl.scene); nothing is fetched.
//
// window.rrcache is the page's interface for tests and for a console: step(frame) renders one
// session frame with both and returns their times, pixels(which) reads a target back (RGBA8),
// setPeriod(n), play(), pause(), stats().
(function () {
  "use strict";
  var data = JSON.parse(document.getElementById("rr-data").textContent);
  var api = window.rrcache = {ready: false, errors: [], notes: [], frames: 0};
  var errorBox = document.getElementById("errors");
  function fail(text) {
    api.errors.push(text);
    errorBox.textContent += text + "\n";
    errorBox.style.display = "block";
  }
  function note(text) {
    api.notes.push(text);
    document.getElementById("notes").textContent += text + "\n";
  }
  var params = new URLSearchParams(window.location.search);
  var size = data.scene.size.slice();
  if (params.get("size")) {
    var parts = params.get("size").split("x").map(Number);
    if (parts.length === 2 && parts[0] > 0 && parts[1] > 0) size = parts;
  }
  var W = size[0], H = size[1];
  var canvas = document.getElementById("view");
  canvas.width = 2 * W;
  canvas.height = H;
  canvas.style.width = Math.min(2 * W, 1280) + "px";
  var gl = canvas.getContext("webgl2", {antialias: false, alpha: false, depth: false, preserveDrawingBuffer: true});
  if (!gl) {
    fail("This browser gives no WebGL2 context: the page needs WebGL2.");
    return;
  }
  if (!gl.getExtension("EXT_color_buffer_float")) {
    fail("EXT_color_buffer_float is missing: the cache needs floating-point render targets.");
    return;
  }
  var floatLinear = !!gl.getExtension("OES_texture_float_linear");
  var timer = gl.getExtension("EXT_disjoint_timer_query_webgl2");
  var variant = data.variant;
  var payloadFormat = variant.payload_dtype === "f2" || !floatLinear ? gl.RGBA16F : gl.RGBA32F;
  if (!floatLinear) {
    note("This GPU cannot filter 32-bit float textures (no OES_texture_float_linear): the payload is kept in " +
         "16-bit floats and the inverse depth is read without filtering; hits and errors differ from the profile's.");
  }

  // ------------------------------------------------------------------ programs
  function compile(name, vertexSource, fragmentSource) {
    var program = gl.createProgram();
    var ok = true;
    [[gl.VERTEX_SHADER, vertexSource, "vertex"], [gl.FRAGMENT_SHADER, fragmentSource, "fragment"]].forEach(function (s) {
      var shader = gl.createShader(s[0]);
      gl.shaderSource(shader, s[1]);
      gl.compileShader(shader);
      if (!gl.getShaderParameter(shader, gl.COMPILE_STATUS)) {
        fail("the " + name + " " + s[2] + " shader did not compile:\n" + gl.getShaderInfoLog(shader));
        ok = false;
      }
      gl.attachShader(program, shader);
    });
    if (!ok) return null;
    gl.linkProgram(program);
    if (!gl.getProgramParameter(program, gl.LINK_STATUS)) {
      fail("the " + name + " program did not link:\n" + gl.getProgramInfoLog(program));
      return null;
    }
    var uniforms = [];
    var count = gl.getProgramParameter(program, gl.ACTIVE_UNIFORMS);
    for (var i = 0; i < count; i++) {
      var info = gl.getActiveUniform(program, i);
      uniforms.push({name: info.name, key: info.name.replace(/\[0\]$/, ""), type: info.type, size: info.size,
                     loc: gl.getUniformLocation(program, info.name)});
    }
    return {name: name, program: program, uniforms: uniforms, vaos: null};
  }

  var original = compile("original", data.original.vertex, data.original.fragment);
  var passes = {};
  variant.order.forEach(function (name) {
    passes[name] = compile(name + " pass", variant.passes[name].vertex, variant.passes[name].fragment);
  });
  if (api.errors.length) return;

  var SETTERS = {};
  SETTERS[gl.FLOAT] = function (l, v) { gl.uniform1fv(l, v); };
  SETTERS[gl.FLOAT_VEC2] = function (l, v) { gl.uniform2fv(l, v); };
  SETTERS[gl.FLOAT_VEC3] = function (l, v) { gl.uniform3fv(l, v); };
  SETTERS[gl.FLOAT_VEC4] = function (l, v) { gl.uniform4fv(l, v); };
  [gl.INT, gl.BOOL, gl.SAMPLER_2D, gl.SAMPLER_CUBE, gl.SAMPLER_3D].forEach(function (t) {
    SETTERS[t] = function (l, v) { gl.uniform1iv(l, v); };
  });
  [gl.INT_VEC2, gl.BOOL_VEC2].forEach(function (t) { SETTERS[t] = function (l, v) { gl.uniform2iv(l, v); }; });
  [gl.INT_VEC3, gl.BOOL_VEC3].forEach(function (t) { SETTERS[t] = function (l, v) { gl.uniform3iv(l, v); }; });
  [gl.INT_VEC4, gl.BOOL_VEC4].forEach(function (t) { SETTERS[t] = function (l, v) { gl.uniform4iv(l, v); }; });
  SETTERS[gl.UNSIGNED_INT] = function (l, v) { gl.uniform1uiv(l, v); };
  SETTERS[gl.UNSIGNED_INT_VEC2] = function (l, v) { gl.uniform2uiv(l, v); };
  SETTERS[gl.UNSIGNED_INT_VEC3] = function (l, v) { gl.uniform3uiv(l, v); };
  SETTERS[gl.UNSIGNED_INT_VEC4] = function (l, v) { gl.uniform4uiv(l, v); };
  SETTERS[gl.FLOAT_MAT2] = function (l, v) { gl.uniformMatrix2fv(l, false, v); };
  SETTERS[gl.FLOAT_MAT3] = function (l, v) { gl.uniformMatrix3fv(l, false, v); };
  SETTERS[gl.FLOAT_MAT4] = function (l, v) { gl.uniformMatrix4fv(l, false, v); };
  SETTERS[gl.FLOAT_MAT2x3] = function (l, v) { gl.uniformMatrix2x3fv(l, false, v); };
  SETTERS[gl.FLOAT_MAT2x4] = function (l, v) { gl.uniformMatrix2x4fv(l, false, v); };
  SETTERS[gl.FLOAT_MAT3x2] = function (l, v) { gl.uniformMatrix3x2fv(l, false, v); };
  SETTERS[gl.FLOAT_MAT3x4] = function (l, v) { gl.uniformMatrix3x4fv(l, false, v); };
  SETTERS[gl.FLOAT_MAT4x2] = function (l, v) { gl.uniformMatrix4x2fv(l, false, v); };
  SETTERS[gl.FLOAT_MAT4x3] = function (l, v) { gl.uniformMatrix4x3fv(l, false, v); };
  function set(prog, values) {
    prog.uniforms.forEach(function (u) {
      var v = values[u.key];
      if (v === undefined) v = values[u.name];
      if (v !== undefined && u.loc !== null) SETTERS[u.type](u.loc, typeof v === "number" ? [v] : v);
    });
  }

  // ------------------------------------------------------------------ the scene
  function decode(text, Type) {
    var bytes = Uint8Array.from(atob(text), function (c) { return c.charCodeAt(0); });
    return new Type(bytes.buffer);
  }
  var scene = data.scene;
  var meshes = scene.objects.map(function (o) {
    var attributes = {};
    Object.keys(o.attributes).forEach(function (name) {
      var buffer = gl.createBuffer();
      gl.bindBuffer(gl.ARRAY_BUFFER, buffer);
      gl.bufferData(gl.ARRAY_BUFFER, decode(o.attributes[name].data, Float32Array), gl.STATIC_DRAW);
      attributes[name] = {buffer: buffer, size: o.attributes[name].size};
    });
    var indices = gl.createBuffer();
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, indices);
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, decode(o.indices, Uint32Array), gl.STATIC_DRAW);
    return {attributes: attributes, indices: indices, count: o.count};
  });
  function vertexArrays(prog) {
    return meshes.map(function (mesh) {
      var vao = gl.createVertexArray();
      gl.bindVertexArray(vao);
      Object.keys(mesh.attributes).forEach(function (name) {
        var location = gl.getAttribLocation(prog.program, name);
        if (location < 0) return;
        gl.bindBuffer(gl.ARRAY_BUFFER, mesh.attributes[name].buffer);
        gl.enableVertexAttribArray(location);
        gl.vertexAttribPointer(location, mesh.attributes[name].size, gl.FLOAT, false, 0, 0);
      });
      gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, mesh.indices);
      gl.bindVertexArray(null);
      return vao;
    });
  }
  [original].concat(variant.order.map(function (n) { return passes[n]; })).forEach(function (p) {
    p.vaos = vertexArrays(p);
  });

  var FORMATS = {  // [internal format, format, type, array] by bytes and channels
    u8: [[gl.R8, gl.RED], [gl.RG8, gl.RG], [gl.RGB8, gl.RGB], [gl.RGBA8, gl.RGBA], gl.UNSIGNED_BYTE, Uint8Array],
    f2: [[gl.R16F, gl.RED], [gl.RG16F, gl.RG], [gl.RGB16F, gl.RGB], [gl.RGBA16F, gl.RGBA], gl.HALF_FLOAT, Uint16Array],
    f4: [[gl.R32F, gl.RED], [gl.RG32F, gl.RG], [gl.RGB32F, gl.RGB], [gl.RGBA32F, gl.RGBA], gl.FLOAT, Float32Array]
  };
  var textures = {}, unit = 0;
  gl.pixelStorei(gl.UNPACK_ALIGNMENT, 1);
  Object.keys(scene.textures).forEach(function (name) {
    var t = scene.textures[name];
    var f = FORMATS[t.format], pixels = decode(t.data, f[5]);
    var linear = t.filter !== "nearest";
    if (t.format === "f4" && linear && !floatLinear) {
      note("texture " + name + " is sampled without filtering (no OES_texture_float_linear)");
      linear = false;
    }
    var target = t.kind === "cube" ? gl.TEXTURE_CUBE_MAP : gl.TEXTURE_2D;
    var tex = gl.createTexture();
    gl.bindTexture(target, tex);
    var fmt = f[t.channels - 1];
    if (t.kind === "cube") {
      var face = t.width * t.height * t.channels;
      for (var i = 0; i < 6; i++) {
        gl.texImage2D(gl.TEXTURE_CUBE_MAP_POSITIVE_X + i, 0, fmt[0], t.width, t.height, 0, fmt[1], f[4],
                      pixels.subarray(i * face, (i + 1) * face));
      }
    } else {
      gl.texImage2D(gl.TEXTURE_2D, 0, fmt[0], t.width, t.height, 0, fmt[1], f[4], pixels);
    }
    var mipmaps = t.filter === "mipmap" && linear;
    if (mipmaps) gl.generateMipmap(target);
    gl.texParameteri(target, gl.TEXTURE_MIN_FILTER, mipmaps ? gl.LINEAR_MIPMAP_LINEAR : linear ? gl.LINEAR : gl.NEAREST);
    gl.texParameteri(target, gl.TEXTURE_MAG_FILTER, linear ? gl.LINEAR : gl.NEAREST);
    var wrap = {repeat: gl.REPEAT, clamp: gl.CLAMP_TO_EDGE, mirror: gl.MIRRORED_REPEAT}[t.wrap] || gl.REPEAT;
    gl.texParameteri(target, gl.TEXTURE_WRAP_S, t.kind === "cube" ? gl.CLAMP_TO_EDGE : wrap);
    gl.texParameteri(target, gl.TEXTURE_WRAP_T, t.kind === "cube" ? gl.CLAMP_TO_EDGE : wrap);
    textures[name] = {texture: tex, target: target, unit: unit++};
    var error = gl.getError();
    if (error !== gl.NO_ERROR) fail("texture " + name + " (" + t.width + "×" + t.height + ", " + t.format + ") could not be set up: GL error 0x" + error.toString(16));
  });

  // ------------------------------------------------------------------ targets
  function texture2d(internal, format, type, filter) {
    var tex = gl.createTexture();
    gl.bindTexture(gl.TEXTURE_2D, tex);
    gl.texStorage2D(gl.TEXTURE_2D, 1, internal, W, H);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, filter);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, filter);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_S, gl.CLAMP_TO_EDGE);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_T, gl.CLAMP_TO_EDGE);
    return tex;
  }
  function framebuffer(colors, depth, label) {
    var fbo = gl.createFramebuffer();
    gl.bindFramebuffer(gl.FRAMEBUFFER, fbo);
    var buffers = colors.map(function (tex, i) {
      gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0 + i, gl.TEXTURE_2D, tex, 0);
      return gl.COLOR_ATTACHMENT0 + i;
    });
    if (depth) gl.framebufferRenderbuffer(gl.FRAMEBUFFER, gl.DEPTH_ATTACHMENT, gl.RENDERBUFFER, depth);
    gl.drawBuffers(buffers);
    var status = gl.checkFramebufferStatus(gl.FRAMEBUFFER);
    if (status !== gl.FRAMEBUFFER_COMPLETE) fail("the " + label + " framebuffer is incomplete (0x" + status.toString(16) + ")");
    return fbo;
  }
  function depthBuffer() {
    var rb = gl.createRenderbuffer();
    gl.bindRenderbuffer(gl.RENDERBUFFER, rb);
    gl.renderbufferStorage(gl.RENDERBUFFER, gl.DEPTH_COMPONENT24, W, H);
    return rb;
  }
  var originalColor = texture2d(gl.RGBA8, gl.RGBA, gl.UNSIGNED_BYTE, gl.NEAREST);
  var originalFbo = framebuffer([originalColor], depthBuffer(), "original");
  var depth = depthBuffer();
  var color = texture2d(gl.RGBA8, gl.RGBA, gl.UNSIGNED_BYTE, gl.NEAREST);
  var filter = floatLinear || payloadFormat === gl.RGBA16F ? gl.LINEAR : gl.NEAREST;
  var payload = [0, 1].map(function () { return texture2d(payloadFormat, gl.RGBA, gl.FLOAT, filter); });
  var invDepth = [0, 1].map(function () { return texture2d(gl.R32F, gl.RED, gl.FLOAT, floatLinear ? gl.LINEAR : gl.NEAREST); });
  var three = variant.algorithm === "three-pass";
  var cacheFbos = [0, 1].map(function (i) {
    return framebuffer((three ? [] : [color]).concat([payload[i], invDepth[i]]), depth, "cache");
  });
  var clearFbos = [0, 1].map(function (i) { return framebuffer([invDepth[i]], depth, "cache clear"); });
  var outFbo = framebuffer([color], depth, "colour");
  var colorOnlyFbo = framebuffer([color], null, "colour");
  gl.bindFramebuffer(gl.FRAMEBUFFER, null);
  if (api.errors.length) return;

  // ------------------------------------------------------------------ the cache (rrcache.runtime.cache)
  var UNIT_PREV_PAYLOAD = 12, UNIT_PREV_INVDEPTH = 13, UNIT_CUR_PAYLOAD = 15;
  var cache = {index: 0, valid: false, clock: 0, period: variant.period, options: variant.options};
  var period = Number(params.get("period")) || variant.period;
  cache.period = Math.max(1, Math.min(1000, Math.round(period)));

  function seedWord(seed) { return (Math.imul(seed, 0x9E3779B9) + 0x7F4A7C15) >>> 0; }
  function refreshUniforms() {  // rrcache.runtime.refresh.refresh_uniforms
    var block = cache.options.block, cols = Math.floor((W + block - 1) / block), rows = Math.floor((H + block - 1) / block);
    var p = cache.period;
    var scale = cache.options.refresh === "random" ? Math.fround(Math.fround(p) * Math.fround(Math.pow(2, -24)))
      : Math.fround(p / (cols * rows));
    return {rr_period: p, rr_refreshPhase: ((-cache.clock % p) + p) % p, rr_blockShift: Math.round(Math.log2(block)),
            rr_tiled: cache.options.refresh === "tiled" ? 1 : 0, rr_seed: seedWord(cache.options.seed || 0),
            rr_refreshScale: scale, rr_blockColumns: cols};
  }

  var frameIndex = 0;
  function sessionValues(frame) {
    var values = {};
    Object.keys(scene.uniforms).forEach(function (name) {
      var track = scene.uniforms[name];
      values[name] = track.constant !== undefined ? track.constant : track.frames[frame];
    });
    Object.keys(textures).forEach(function (name) { values[name] = textures[name].unit; });
    var builtins = scene.builtins[frame];
    Object.keys(builtins).forEach(function (name) { values[name] = builtins[name]; });
    values.u_resolution = [W, H];
    return values;
  }
  function draw(prog, extra) {
    gl.useProgram(prog.program);
    Object.keys(textures).forEach(function (name) {
      gl.activeTexture(gl.TEXTURE0 + textures[name].unit);
      gl.bindTexture(textures[name].target, textures[name].texture);
    });
    set(prog, sessionValues(frameIndex));
    if (extra) set(prog, extra);
    scene.object_builtins[frameIndex].forEach(function (o, i) {
      if (o.cull) { gl.enable(gl.CULL_FACE); gl.cullFace(gl.BACK); } else gl.disable(gl.CULL_FACE);
      set(prog, o);
      gl.bindVertexArray(prog.vaos[i]);
      gl.drawElements(gl.TRIANGLES, meshes[i].count, gl.UNSIGNED_INT, 0);
    });
    gl.bindVertexArray(null);
  }
  function runPass(name, refresh) {
    var prev = 1 - cache.index;
    gl.activeTexture(gl.TEXTURE0 + UNIT_PREV_PAYLOAD);
    gl.bindTexture(gl.TEXTURE_2D, payload[prev]);
    gl.activeTexture(gl.TEXTURE0 + UNIT_PREV_INVDEPTH);
    gl.bindTexture(gl.TEXTURE_2D, invDepth[prev]);
    gl.activeTexture(gl.TEXTURE0 + UNIT_CUR_PAYLOAD);
    gl.bindTexture(gl.TEXTURE_2D, three ? payload[cache.index] : null);
    var extra = Object.assign({rr_prevPayload: UNIT_PREV_PAYLOAD, rr_prevInvDepth: UNIT_PREV_INVDEPTH,
                               rr_curPayload: UNIT_CUR_PAYLOAD, rr_valid: cache.valid ? 1 : 0,
                               rr_depthEpsilon: cache.options.depth_epsilon, rr_amortFrame: cache.clock,
                               rr_lambda: 0}, refresh);
    draw(passes[name], extra);
  }
  function bindTarget(fbo, buffers) {
    gl.bindFramebuffer(gl.FRAMEBUFFER, fbo);
    gl.viewport(0, 0, W, H);
  }
  function cachedFrame() {
    var bg = scene.background;
    gl.enable(gl.DEPTH_TEST);
    bindTarget(colorOnlyFbo);
    gl.clearColor(bg[0], bg[1], bg[2], bg[3]);
    gl.clear(gl.COLOR_BUFFER_BIT);
    bindTarget(clearFbos[cache.index]);
    gl.depthMask(true);
    gl.clearColor(0, 0, 0, 0);
    gl.clearDepth(1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    bindTarget(cacheFbos[cache.index]);
    gl.depthFunc(gl.LESS);
    var refresh = refreshUniforms();
    if (three) {
      runPass("reproject", refresh);
      runPass("payload", refresh);
      bindTarget(outFbo);
      gl.depthMask(false);
      gl.depthFunc(gl.EQUAL);
      runPass("shade", refresh);
      gl.depthMask(true);
    } else {
      variant.order.forEach(function (name) { runPass(name, refresh); });
    }
    gl.depthFunc(gl.LESS);
    cache.index = 1 - cache.index;
    cache.valid = true;
    cache.clock += 1;
  }
  function originalFrame() {
    var bg = scene.background;
    gl.enable(gl.DEPTH_TEST);
    gl.depthFunc(gl.LESS);
    gl.depthMask(true);
    bindTarget(originalFbo);
    gl.clearColor(bg[0], bg[1], bg[2], bg[3]);
    gl.clearDepth(1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    draw(original, null);
  }

  // ------------------------------------------------------------------ timing
  var times = {original: [], cached: []}, pending = [], sync = new Uint8Array(4);
  var method = timer ? "GPU timer queries" : "wall clock around each draw and a one-pixel read-back";
  function timed(which, render, fbo) {
    if (timer) {
      var q = gl.createQuery();
      gl.beginQuery(timer.TIME_ELAPSED_EXT, q);
      render();
      gl.endQuery(timer.TIME_ELAPSED_EXT);
      pending.push({which: which, query: q});
      return null;
    }
    var t0 = performance.now();
    render();
    gl.bindFramebuffer(gl.FRAMEBUFFER, fbo);
    gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, sync);
    var ms = performance.now() - t0;
    record(which, ms);
    return ms;
  }
  function record(which, ms) {
    times[which].push(ms);
    if (times[which].length > 60) times[which].shift();
  }
  function poll() {
    if (!timer) return;
    var disjoint = gl.getParameter(timer.GPU_DISJOINT_EXT);
    pending = pending.filter(function (p) {
      if (!gl.getQueryParameter(p.query, gl.QUERY_RESULT_AVAILABLE)) return true;
      if (!disjoint) record(p.which, gl.getQueryParameter(p.query, gl.QUERY_RESULT) / 1e6);
      gl.deleteQuery(p.query);
      return false;
    });
  }
  function median(list) {
    if (!list.length) return null;
    var s = list.slice().sort(function (a, b) { return a - b; });
    return s.length % 2 ? s[(s.length - 1) / 2] : (s[s.length / 2 - 1] + s[s.length / 2]) / 2;
  }
  api.stats = function () {
    var o = median(times.original), c = median(times.cached);
    return {original_ms: o, cached_ms: c, speedup: o && c ? o / c : null, frames: times.cached.length, method: method,
            period: cache.period};
  };

  // ------------------------------------------------------------------ frames
  var last = -1;
  function present() {
    gl.bindFramebuffer(gl.READ_FRAMEBUFFER, originalFbo);
    gl.bindFramebuffer(gl.DRAW_FRAMEBUFFER, null);
    gl.blitFramebuffer(0, 0, W, H, 0, 0, W, H, gl.COLOR_BUFFER_BIT, gl.NEAREST);
    gl.bindFramebuffer(gl.READ_FRAMEBUFFER, colorOnlyFbo);
    gl.blitFramebuffer(0, 0, W, H, W, 0, 2 * W, H, gl.COLOR_BUFFER_BIT, gl.NEAREST);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
  }
  api.step = function (frame) {
    frame = ((frame % scene.frames) + scene.frames) % scene.frames;
    if (frame !== last + 1) {  // a jump (or the loop back to frame 0) is a cut: the cache starts empty
      cache.valid = false;
      cache.clock = 0;
    }
    frameIndex = frame;
    var order = api.frames % 2 ? ["cached", "original"] : ["original", "cached"];
    var out = {};
    order.forEach(function (which) {
      out[which + "_ms"] = which === "original" ? timed("original", originalFrame, originalFbo)
        : timed("cached", cachedFrame, colorOnlyFbo);
    });
    poll();
    present();
    last = frame;
    api.frames += 1;
    if (!playing) show();  // stepped by hand (a test, the console): show what it did
    return out;
  };
  api.pixels = function (which) {
    var out = new Uint8Array(W * H * 4);
    gl.bindFramebuffer(gl.FRAMEBUFFER, which === "original" ? originalFbo : colorOnlyFbo);
    gl.readPixels(0, 0, W, H, gl.RGBA, gl.UNSIGNED_BYTE, out);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    return Array.from(out);
  };
  api.setPeriod = function (n) {
    cache.period = Math.max(1, Math.min(1000, Math.round(n)));
    times = {original: [], cached: []};
    document.getElementById("period").value = Math.min(cache.period, 50);
    document.getElementById("periodText").textContent = cache.period;
  };
  api.size = [W, H];

  // ------------------------------------------------------------------ the page
  var playing = params.get("autoplay") !== "0", shown = 0;
  function show() {
    var s = api.stats();
    var f = function (v) { return v === null ? "…" : v.toFixed(2) + " ms"; };
    document.getElementById("times").textContent =
      "original " + f(s.original_ms) + " · cached " + f(s.cached_ms) +
      (s.speedup ? " · speed-up " + s.speedup.toFixed(2) + "×" : "") +
      " (median of the last " + s.frames + " frames; " + s.method + ")";
    document.getElementById("frame").textContent = "frame " + frameIndex + " of " + scene.frames;
  }
  function tick() {
    if (!playing) return;
    api.step(last + 1);
    var now = performance.now();
    if (now - shown > 250) { show(); shown = now; }
    window.requestAnimationFrame(tick);
  }
  api.play = function () { if (!playing) { playing = true; window.requestAnimationFrame(tick); } };
  api.pause = function () { playing = false; show(); };
  document.getElementById("playpause").addEventListener("click", function () {
    if (playing) { api.pause(); this.textContent = "play"; } else { api.play(); this.textContent = "pause"; }
  });
  document.getElementById("period").addEventListener("input", function () { api.setPeriod(Number(this.value)); });
  api.setPeriod(cache.period);
  api.ready = true;
  if (playing) window.requestAnimationFrame(tick);
  else document.getElementById("playpause").textContent = "play";
})();
