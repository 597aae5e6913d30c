// The 3D view: WebGL2, Z up, the model standing on the chosen printer's plate as the
// slicer places it (centred in x and y, bottom at z = 0). Orbit, pan, zoom, fit; smooth
// shading with inside faces tinted; edges optional.

const MESH_VS = `#version 300 es
in vec3 aPos;
in vec3 aNormal;
uniform mat4 uViewProj;
uniform vec3 uOffset;
out vec3 vNormal;
out vec3 vWorld;
void main() {
  vec3 p = aPos + uOffset;
  vWorld = p;
  vNormal = aNormal;
  gl_Position = uViewProj * vec4(p, 1.0);
}`;

const MESH_FS = `#version 300 es
precision highp float;
in vec3 vNormal;
in vec3 vWorld;
uniform vec3 uEye;
out vec4 outColor;
void main() {
  vec3 n = normalize(vNormal);
  vec3 v = normalize(uEye - vWorld);
  // Inside faces (seen through a hole or a cut) are tinted, so an open mesh shows.
  vec3 base = gl_FrontFacing ? vec3(0.93, 0.55, 0.22) : vec3(0.55, 0.62, 0.75);
  if (!gl_FrontFacing) n = -n;
  if (dot(n, v) < 0.0) n = -n;
  float head = max(dot(n, v), 0.0);
  float sky = max(dot(n, normalize(vec3(0.3, 0.4, 1.0))), 0.0);
  float spec = pow(max(dot(reflect(-v, n), v), 0.0), 40.0) * 0.18;
  outColor = vec4(base * (0.22 + 0.6 * head + 0.25 * sky) + spec, 1.0);
}`;

const LINE_VS = `#version 300 es
in vec3 aPos;
uniform mat4 uViewProj;
uniform vec3 uOffset;
void main() { gl_Position = uViewProj * vec4(aPos + uOffset, 1.0); }`;

const LINE_FS = `#version 300 es
precision highp float;
uniform vec4 uColor;
out vec4 outColor;
void main() { outColor = uColor; }`;

function compile(gl, vs, fs) {
  const program = gl.createProgram();
  for (const [type, src] of [[gl.VERTEX_SHADER, vs], [gl.FRAGMENT_SHADER, fs]]) {
    const s = gl.createShader(type);
    gl.shaderSource(s, src);
    gl.compileShader(s);
    if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(s));
    gl.attachShader(program, s);
  }
  gl.bindAttribLocation(program, 0, 'aPos');
  gl.bindAttribLocation(program, 1, 'aNormal');
  gl.linkProgram(program);
  if (!gl.getProgramParameter(program, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(program));
  return program;
}

// Column-major 4x4 matrices.
function perspective(fovy, aspect, near, far) {
  const f = 1 / Math.tan(fovy / 2);
  const nf = 1 / (near - far);
  return new Float32Array([f / aspect, 0, 0, 0, 0, f, 0, 0, 0, 0, (far + near) * nf, -1, 0, 0, 2 * far * near * nf, 0]);
}

function sub(a, b) { return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]; }
function cross(a, b) { return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]; }
function norm(a) { const l = Math.hypot(a[0], a[1], a[2]) || 1; return [a[0] / l, a[1] / l, a[2] / l]; }
function dot(a, b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

function lookAt(eye, target, up) {
  const z = norm(sub(eye, target));
  const x = norm(cross(up, z));
  const y = cross(z, x);
  return new Float32Array([x[0], y[0], z[0], 0, x[1], y[1], z[1], 0, x[2], y[2], z[2], 0,
    -dot(x, eye), -dot(y, eye), -dot(z, eye), 1]);
}

function multiply(a, b) {
  const out = new Float32Array(16);
  for (let c = 0; c < 4; c++) {
    for (let r = 0; r < 4; r++) {
      let s = 0;
      for (let k = 0; k < 4; k++) s += a[k * 4 + r] * b[c * 4 + k];
      out[c * 4 + r] = s;
    }
  }
  return out;
}

// Area-weighted vertex normals (the cross product's length is twice the area).
function vertexNormals(positions, indices) {
  const normals = new Float32Array(positions.length);
  for (let t = 0; t < indices.length; t += 3) {
    const a = indices[t] * 3, b = indices[t + 1] * 3, c = indices[t + 2] * 3;
    const ux = positions[b] - positions[a], uy = positions[b + 1] - positions[a + 1], uz = positions[b + 2] - positions[a + 2];
    const vx = positions[c] - positions[a], vy = positions[c + 1] - positions[a + 1], vz = positions[c + 2] - positions[a + 2];
    const nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
    for (const i of [a, b, c]) { normals[i] += nx; normals[i + 1] += ny; normals[i + 2] += nz; }
  }
  return normals;
}

function uniqueEdges(indices) {
  const seen = new Set();
  const out = [];
  for (let t = 0; t < indices.length; t += 3) {
    for (let k = 0; k < 3; k++) {
      const a = indices[t + k], b = indices[t + (k + 1) % 3];
      const key = a < b ? a * 4294967296 + b : b * 4294967296 + a;
      if (!seen.has(key)) { seen.add(key); out.push(a, b); }
    }
  }
  return new Uint32Array(out);
}

export class View3D {
  constructor(canvas) {
    this.canvas = canvas;
    // No multisampling: under software rendering (SwiftShader, as in headless browsers and
    // machines without a GPU) it tripled the time from a new mesh to the screen
    // (docs/studio.md, Speed).
    const gl = canvas.getContext('webgl2', { antialias: false, preserveDrawingBuffer: false });
    if (!gl) throw new Error('this browser has no WebGL2');
    this.gl = gl;
    this.meshProgram = compile(gl, MESH_VS, MESH_FS);
    this.lineProgram = compile(gl, LINE_VS, LINE_FS);
    this.mesh = null;
    this.plate = null;
    this.showEdges = false;
    this.yaw = -Math.PI / 3;
    this.pitch = 0.45;
    this.distance = 100;
    this.target = [110, 110, 10];
    this.fitted = false;
    this.afterDraw = [];
    this.pending = false;
    this.setPlate([220, 220]);
    this.attachControls();
    new ResizeObserver(() => this.requestDraw()).observe(canvas);
  }

  attachControls() {
    const c = this.canvas;
    let drag = null;
    c.addEventListener('contextmenu', (e) => e.preventDefault());
    c.addEventListener('pointerdown', (e) => {
      drag = { x: e.clientX, y: e.clientY, pan: e.button === 2 || e.shiftKey };
      c.setPointerCapture(e.pointerId);
    });
    c.addEventListener('pointerup', () => { drag = null; });
    c.addEventListener('pointermove', (e) => {
      if (!drag) return;
      const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
      drag.x = e.clientX; drag.y = e.clientY;
      if (drag.pan) this.pan(dx, dy); else this.orbit(dx, dy);
    });
    c.addEventListener('wheel', (e) => {
      e.preventDefault();
      this.zoom(Math.exp(e.deltaY * 0.0015));
    }, { passive: false });
    c.addEventListener('keydown', (e) => { if (e.key === 'f' || e.key === 'F') this.fit(); });
  }

  orbit(dx, dy) {
    this.yaw -= dx * 0.008;
    this.pitch = Math.max(-1.5, Math.min(1.5, this.pitch + dy * 0.008));
    this.requestDraw();
  }

  pan(dx, dy) {
    const { right, up } = this.basis();
    const k = this.distance * 0.0015;
    for (let i = 0; i < 3; i++) this.target[i] += (-dx * right[i] + dy * up[i]) * k;
    this.requestDraw();
  }

  zoom(factor) {
    this.distance = Math.max(1e-3, this.distance * factor);
    this.requestDraw();
  }

  eye() {
    const cp = Math.cos(this.pitch);
    return [this.target[0] + this.distance * cp * Math.cos(this.yaw),
      this.target[1] + this.distance * cp * Math.sin(this.yaw),
      this.target[2] + this.distance * Math.sin(this.pitch)];
  }

  basis() {
    const forward = norm(sub(this.target, this.eye()));
    const right = norm(cross(forward, [0, 0, 1]));
    const up = cross(right, forward);
    return { right, up };
  }

  // The plate: its outline and a 10 mm grid, at z = 0, corner at the origin.
  setPlate(size) {
    const gl = this.gl;
    const [w, h] = size;
    const lines = [];
    const step = 10;
    for (let x = 0; x <= w + 1e-6; x += step) lines.push(x, 0, 0, x, h, 0);
    for (let y = 0; y <= h + 1e-6; y += step) lines.push(0, y, 0, w, y, 0);
    lines.push(w, 0, 0, w, h, 0, 0, h, 0, w, h, 0);
    const quad = [0, 0, 0, w, 0, 0, w, h, 0, 0, 0, 0, w, h, 0, 0, h, 0];
    if (this.plate) { gl.deleteBuffer(this.plate.lines); gl.deleteBuffer(this.plate.quad); }
    this.plate = {
      size: [w, h],
      lines: this.buffer(gl.ARRAY_BUFFER, new Float32Array(lines)),
      lineCount: lines.length / 3,
      quad: this.buffer(gl.ARRAY_BUFFER, new Float32Array(quad)),
    };
    this.requestDraw();
  }

  buffer(kind, data) {
    const gl = this.gl;
    const b = gl.createBuffer();
    gl.bindBuffer(kind, b);
    gl.bufferData(kind, data, gl.STATIC_DRAW);
    return b;
  }

  // A new mesh (positions in mm, model coordinates). Placed as the slicer places it.
  setMesh(positions, indices) {
    const gl = this.gl;
    if (this.mesh) {
      for (const b of [this.mesh.pos, this.mesh.nrm, this.mesh.idx, this.mesh.edges]) if (b) gl.deleteBuffer(b);
    }
    if (indices.length === 0) { this.mesh = null; this.requestDraw(); return; }
    const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
    for (let i = 0; i < positions.length; i += 3) {
      for (let k = 0; k < 3; k++) {
        const v = positions[i + k];
        if (v < lo[k]) lo[k] = v;
        if (v > hi[k]) hi[k] = v;
      }
    }
    const vao = gl.createVertexArray();
    gl.bindVertexArray(vao);
    const pos = this.buffer(gl.ARRAY_BUFFER, positions);
    gl.enableVertexAttribArray(0);
    gl.vertexAttribPointer(0, 3, gl.FLOAT, false, 0, 0);
    const nrm = this.buffer(gl.ARRAY_BUFFER, vertexNormals(positions, indices));
    gl.enableVertexAttribArray(1);
    gl.vertexAttribPointer(1, 3, gl.FLOAT, false, 0, 0);
    const idx = this.buffer(gl.ELEMENT_ARRAY_BUFFER, indices);
    gl.bindVertexArray(null);
    this.mesh = { vao, pos, nrm, idx, count: indices.length, indices, lo, hi, edges: null, edgeCount: 0 };
    if (this.showEdges) this.buildEdges();
    if (!this.fitted) { this.fit(); this.fitted = true; }
    this.requestDraw();
  }

  buildEdges() {
    const gl = this.gl, m = this.mesh;
    if (!m || m.edges) return;
    const edges = uniqueEdges(m.indices);
    const vao = gl.createVertexArray();
    gl.bindVertexArray(vao);
    gl.bindBuffer(gl.ARRAY_BUFFER, m.pos);
    gl.enableVertexAttribArray(0);
    gl.vertexAttribPointer(0, 3, gl.FLOAT, false, 0, 0);
    m.edges = this.buffer(gl.ELEMENT_ARRAY_BUFFER, edges);
    gl.bindVertexArray(null);
    m.edgeVao = vao;
    m.edgeCount = edges.length;
  }

  setEdges(on) {
    this.showEdges = on;
    if (on) this.buildEdges();
    this.requestDraw();
  }

  // Where the model's coordinates go on the plate.
  offset() {
    const [w, h] = this.plate.size;
    if (!this.mesh) return [0, 0, 0];
    const { lo, hi } = this.mesh;
    return [w / 2 - (lo[0] + hi[0]) / 2, h / 2 - (lo[1] + hi[1]) / 2, -lo[2]];
  }

  fit() {
    if (!this.mesh) return;
    const { lo, hi } = this.mesh;
    const o = this.offset();
    this.target = [0, 1, 2].map((k) => (lo[k] + hi[k]) / 2 + o[k]);
    const radius = Math.max(1e-3, Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]) / 2);
    this.distance = radius / Math.sin(this.fov() / 2) * 1.15;
    this.requestDraw();
  }

  fov() { return 40 * Math.PI / 180; }

  // Draws on the next animation frame; `then` runs once the frame is on screen (the frame
  // after the one that drew).
  requestDraw(then) {
    if (then) this.afterDraw.push(then);
    if (this.pending) return;
    this.pending = true;
    requestAnimationFrame(() => {
      this.pending = false;
      this.draw();
      const done = this.afterDraw;
      this.afterDraw = [];
      if (done.length) requestAnimationFrame(() => done.forEach((f) => f()));
    });
  }

  // Draws at once (a new preview should not wait for the next frame to start drawing);
  // `then` runs at the next animation frame, when the drawing is on screen.
  drawNow(then) {
    this.draw();
    if (then) requestAnimationFrame(then);
  }

  draw() {
    const gl = this.gl, c = this.canvas;
    const dpr = window.devicePixelRatio || 1;
    const w = Math.max(1, Math.round(c.clientWidth * dpr)), h = Math.max(1, Math.round(c.clientHeight * dpr));
    if (c.width !== w || c.height !== h) { c.width = w; c.height = h; }
    gl.viewport(0, 0, w, h);
    gl.clearColor(0.87, 0.9, 0.92, 1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.enable(gl.DEPTH_TEST);
    const eye = this.eye();
    const span = Math.max(this.plate.size[0], this.plate.size[1]);
    const near = Math.max(this.distance * 0.002, 1e-4);
    const far = this.distance * 4 + span * 3;
    const viewProj = multiply(perspective(this.fov(), w / h, near, far), lookAt(eye, this.target, [0, 0, 1]));
    const lp = this.lineProgram;
    gl.useProgram(lp);
    gl.uniformMatrix4fv(gl.getUniformLocation(lp, 'uViewProj'), false, viewProj);
    gl.uniform3fv(gl.getUniformLocation(lp, 'uOffset'), [0, 0, 0]);
    // The plate, pushed back in depth so the model's bottom and the grid win over it.
    gl.enable(gl.POLYGON_OFFSET_FILL);
    gl.polygonOffset(2, 4);
    gl.bindVertexArray(null);
    gl.bindBuffer(gl.ARRAY_BUFFER, this.plate.quad);
    gl.enableVertexAttribArray(0);
    gl.vertexAttribPointer(0, 3, gl.FLOAT, false, 0, 0);
    gl.disableVertexAttribArray(1);
    gl.uniform4fv(gl.getUniformLocation(lp, 'uColor'), [0.97, 0.97, 0.96, 1]);
    gl.drawArrays(gl.TRIANGLES, 0, 6);
    gl.disable(gl.POLYGON_OFFSET_FILL);
    gl.bindBuffer(gl.ARRAY_BUFFER, this.plate.lines);
    gl.vertexAttribPointer(0, 3, gl.FLOAT, false, 0, 0);
    gl.uniform4fv(gl.getUniformLocation(lp, 'uColor'), [0.7, 0.74, 0.78, 1]);
    gl.drawArrays(gl.LINES, 0, this.plate.lineCount);
    if (!this.mesh) return;
    const offset = this.offset();
    const mp = this.meshProgram;
    gl.useProgram(mp);
    gl.uniformMatrix4fv(gl.getUniformLocation(mp, 'uViewProj'), false, viewProj);
    gl.uniform3fv(gl.getUniformLocation(mp, 'uOffset'), offset);
    gl.uniform3fv(gl.getUniformLocation(mp, 'uEye'), eye);
    gl.enable(gl.POLYGON_OFFSET_FILL);
    gl.polygonOffset(1, 1);
    gl.bindVertexArray(this.mesh.vao);
    gl.drawElements(gl.TRIANGLES, this.mesh.count, gl.UNSIGNED_INT, 0);
    gl.disable(gl.POLYGON_OFFSET_FILL);
    if (this.showEdges && this.mesh.edges) {
      gl.useProgram(lp);
      gl.uniform3fv(gl.getUniformLocation(lp, 'uOffset'), offset);
      gl.uniform4fv(gl.getUniformLocation(lp, 'uColor'), [0.15, 0.1, 0.05, 1]);
      gl.bindVertexArray(this.mesh.edgeVao);
      gl.drawElements(gl.LINES, this.mesh.edgeCount, gl.UNSIGNED_INT, 0);
    }
    gl.bindVertexArray(null);
  }
}
