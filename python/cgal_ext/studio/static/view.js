// The view: WebGL (three.js), the camera and its orbit, drawing on demand, the eye-dome lighting pass, the view
// presets with the up axis the user picks, and the passes the tools read back (depth, positions).
import * as THREE from '../three/build/three.module.js';
import { OrbitControls } from '../three/examples/jsm/controls/OrbitControls.js';
import { OUTPUT } from './material.js';
import { studio } from './shared.js';

const BACKGROUND = new THREE.Color(0x20242a);
export const UP_AXES = { '+z': [0, 0, 1], '-z': [0, 0, -1], '+y': [0, 1, 0], '-y': [0, -1, 0], '+x': [1, 0, 0],
                         '-x': [-1, 0, 0] };

// Eye-dome lighting (as Potree and CloudCompare have it): a point darkens by how much its neighbours on the
// screen lie in front of it, in log depth, so that relief reads without normals and edges outline themselves.
const edlVertex = `
varying vec2 vUv;
void main() { vUv = uv; gl_Position = vec4(position.xy, 0.0, 1.0); }`;
const edlFragment = `
precision highp float;
uniform sampler2D colourDepth;
uniform vec2 texel;
uniform float strength;
uniform float radius;
uniform vec3 background;
varying vec2 vUv;
void main() {
  vec4 c = texture2D(colourDepth, vUv);
  if (c.a <= 0.0) { gl_FragColor = vec4(background, 1.0); return; }
  float d = log2(c.a), response = 0.0;
  for (int k = 0; k < 8; ++k) {
    float a = 0.7853981634 * float(k);
    float neighbour = texture2D(colourDepth, vUv + radius * texel * vec2(cos(a), sin(a))).a;
    // The background counts as far away: the silhouette gets its outline.
    response += neighbour > 0.0 ? max(0.0, d - log2(neighbour)) : 0.02;
  }
  gl_FragColor = vec4(c.rgb * exp(-response / 8.0 * 300.0 * strength), 1.0);
}`;

export class View {
  constructor(canvas) {
    this.canvas = canvas;
    this.webgl = new THREE.WebGLRenderer({ canvas, context: canvas.getContext('webgl2', { antialias: false, preserveDrawingBuffer: true }) });
    this.webgl.setPixelRatio(1);
    this.webgl.autoClear = false;
    this.scene = new THREE.Scene();    // the points
    this.overlay = new THREE.Scene();  // drawn over them: the gizmo
    this.camera = new THREE.PerspectiveCamera(40, 1, 0.001, 1000);
    this.material = null;              // the points' DeformingMaterial
    this.points = null;
    this.up = '+z';
    this.edl = { enabled: true, strength: 1, radius: 1.4 };
    this.budget = 1000000;
    this.moving = false; this.orbiting = false; this.dragging = false;
    this.orbitEnabled = true;
    this.orbit = null;
    this.makeOrbit();
    this.target = null;
    const quad = new THREE.Mesh(new THREE.PlaneBufferGeometry(2, 2), new THREE.ShaderMaterial({
      vertexShader: edlVertex, fragmentShader: edlFragment, depthTest: false, depthWrite: false,
      uniforms: { colourDepth: { value: null }, texel: { value: new THREE.Vector2() }, strength: { value: 1 },
                  radius: { value: 1.4 }, background: { value: new THREE.Vector3(BACKGROUND.r, BACKGROUND.g, BACKGROUND.b) } },
    }));
    quad.frustumCulled = false;
    this.edlScene = new THREE.Scene();
    this.edlScene.add(quad);
    this.edlQuad = quad;
    this.edlCamera = new THREE.OrthographicCamera(-1, 1, 1, -1, 0, 1);
    this.drawPending = false;
    this.lastFrame = performance.now();
    this.continuous = false;
    window.addEventListener('resize', () => this.resize());
    this.resize();
  }

  makeOrbit() {
    // OrbitControls fixes its up axis when made: a new one for each up axis.
    const target = this.orbit ? this.orbit.target.clone() : new THREE.Vector3();
    if (this.orbit) this.orbit.dispose();
    this.orbit = new OrbitControls(this.camera, this.canvas);
    this.orbit.target.copy(target);
    this.orbit.enabled = this.orbitEnabled;
    this.orbit.addEventListener('change', () => this.requestRender());
    this.orbit.addEventListener('start', () => { this.orbiting = true; this.setMoving(true); });
    this.orbit.addEventListener('end', () => { this.orbiting = false; this.setMoving(this.dragging); });
  }

  setDragging(dragging) {
    this.dragging = dragging;
    this.setMoving(dragging || this.orbiting);
  }

  setOrbitEnabled(enabled) {
    this.orbitEnabled = enabled;
    this.orbit.enabled = enabled;
  }

  get width() { return this.canvas.clientWidth; }
  get height() { return this.canvas.clientHeight; }

  resize() {
    this.webgl.setSize(this.width, this.height, false);
    this.camera.aspect = this.width / Math.max(1, this.height);
    this.camera.updateProjectionMatrix();
    if (this.target) { this.target.dispose(); this.target = null; }
    this.requestRender();
  }

  colourDepthTarget(width, height) {
    return new THREE.WebGLRenderTarget(width, height, { type: THREE.FloatType, format: THREE.RGBAFormat,
      minFilter: THREE.NearestFilter, magFilter: THREE.NearestFilter, depthBuffer: true });
  }

  setPoints(points, material) {
    if (this.points) this.scene.remove(this.points);
    this.points = points;
    this.geometry = points.geometry; // every point's; while moving, the points draw the budget's subset
    this.material = material;
    this.scene.add(points);
    if (this.subset) this.subset.geometry.dispose(); // its buffers, made for the geometry replaced
    this.subset = null;
    this.applyBudget();
  }

  // The point budget (Potree's): while the view or a handle moves, at most `budget` points are drawn, a random
  // subset (spatially even on average) with sprites grown to cover for the others; every point when idle.
  setMoving(moving) {
    if (this.moving === moving) return;
    this.moving = moving;
    this.applyBudget();
  }

  applyBudget() {
    if (!this.points) return;
    const n = studio.n;
    const limited = this.moving && this.budget > 0 && n > this.budget;
    this.points.geometry = limited ? this.subsetGeometry() : this.geometry;
    if (this.material) this.material.uniforms.budgetScale.value = limited ? Math.sqrt(n / this.budget) : 1;
    studio.drawn = limited ? this.budget : n;
    this.requestRender();
  }

  // The budget's points as a geometry of their own: the first `budget` of a fixed shuffle (xorshift from a
  // constant seed: the same subset every time), their attributes gathered in increasing order into arrays of
  // their own, so that the vertex stage reads them in sequence (software GL spends most of a frame there). An
  // attribute is gathered again when it changed since (a new array or a new version).
  subsetGeometry() {
    const full = this.geometry, n = studio.n;
    if (!this.subset || this.subset.full !== full || this.subset.indices.length !== this.budget) {
      const order = new Uint32Array(n);
      for (let i = 0; i < n; ++i) order[i] = i;
      let x = 2463534242;
      for (let i = n - 1; i > 0; --i) {
        x ^= x << 13; x >>>= 0; x ^= x >>> 17; x ^= x << 5; x >>>= 0;
        const j = x % (i + 1);
        const t = order[i]; order[i] = order[j]; order[j] = t;
      }
      const indices = order.slice(0, this.budget).sort();
      if (this.subset) this.subset.geometry.dispose();
      this.subset = { full, indices, geometry: new THREE.BufferGeometry(), sources: {} };
    }
    const { indices, geometry, sources } = this.subset;
    for (const [name, attribute] of Object.entries(full.attributes)) {
      const known = sources[name];
      if (known && known.attribute === attribute && known.version === attribute.version) continue;
      const size = attribute.itemSize, from = attribute.array;
      let gathered = geometry.getAttribute(name);
      if (gathered && gathered.array.constructor === from.constructor && gathered.itemSize === size) {
        gathered.needsUpdate = true; // the same buffer, new values
      } else {
        gathered = new THREE.BufferAttribute(new from.constructor(indices.length * size), size, attribute.normalized);
        geometry.setAttribute(name, gathered);
      }
      const to = gathered.array;
      for (let k = 0; k < indices.length; ++k) {
        const i = indices[k] * size;
        for (let c = 0; c < size; ++c) to[k * size + c] = from[i + c];
      }
      sources[name] = { attribute, version: attribute.version };
    }
    return geometry;
  }

  // Drawn on demand (a camera move, new motions, new attributes), never in an idle loop: a million points drawn
  // in software would otherwise keep the page busy between the server's messages. `continuous` draws every
  // frame (to measure it); studio.frameTimes holds the intervals between drawn frames.
  requestRender() {
    if (this.drawPending) return;
    this.drawPending = true;
    requestAnimationFrame(() => this.draw());
  }

  draw() {
    this.drawPending = false;
    const now = performance.now();
    studio.frameTimes.push(now - this.lastFrame);
    if (studio.frameTimes.length > 240) studio.frameTimes.shift();
    this.lastFrame = now;
    this.render();
    studio.timings.push(['drawn', now, performance.now()]);
    if (this.continuous) this.requestRender();
  }

  pixelsPerUnit(height) {
    return height / (2 * Math.tan((this.camera.fov * Math.PI) / 360));
  }

  // The points with the given output into a render target (null: the canvas).
  renderPoints(output, target, height) {
    const u = this.material && this.material.uniforms;
    if (u) { u.outputMode.value = output; u.pixelsPerUnit.value = this.pixelsPerUnit(height); }
    this.webgl.setRenderTarget(target);
    if (target) this.webgl.setClearColor(0x000000, 0); else this.webgl.setClearColor(BACKGROUND, 1);
    this.webgl.clear();
    this.webgl.render(this.scene, this.camera);
    if (u) u.outputMode.value = OUTPUT.colour;
    this.webgl.setRenderTarget(null);
  }

  render() {
    if (this.edl.enabled && this.material) {
      if (!this.target) this.target = this.colourDepthTarget(this.width, this.height);
      this.renderPoints(OUTPUT.colourDepth, this.target, this.height);
      const u = this.edlQuad.material.uniforms;
      u.colourDepth.value = this.target.texture;
      u.texel.value.set(1 / this.width, 1 / this.height);
      u.strength.value = this.edl.strength;
      u.radius.value = this.edl.radius;
      this.webgl.setRenderTarget(null);
      this.webgl.clear();
      this.webgl.render(this.edlScene, this.edlCamera);
    } else {
      this.renderPoints(OUTPUT.colour, null, this.height);
    }
    this.webgl.clearDepth();
    this.webgl.render(this.overlay, this.camera);
  }

  // The view depth of the nearest point drawn at each pixel (0: background), rows from the top.
  depthPass() {
    const width = this.width, height = this.height;
    const target = this.colourDepthTarget(width, height);
    this.renderPoints(OUTPUT.colourDepth, target, height);
    const pixels = new Float32Array(4 * width * height);
    this.webgl.readRenderTargetPixels(target, 0, 0, width, height, pixels);
    target.dispose();
    const depth = new Float32Array(width * height);
    for (let y = 0; y < height; ++y) {
      for (let x = 0; x < width; ++x) depth[y * width + x] = pixels[4 * ((height - 1 - y) * width + x) + 3];
    }
    return { width, height, depth };
  }

  // The shader's positions, read back through a float render target: one pixel per point.
  readPositions(n) {
    const width = Math.ceil(Math.sqrt(n));
    const target = new THREE.WebGLRenderTarget(width, width, { type: THREE.FloatType, format: THREE.RGBAFormat,
      minFilter: THREE.NearestFilter, magFilter: THREE.NearestFilter, depthBuffer: false });
    this.material.uniforms.readbackWidth.value = width;
    this.renderPoints(OUTPUT.positions, target, width);
    const pixels = new Float32Array(4 * width * width);
    this.webgl.readRenderTargetPixels(target, 0, 0, width, width, pixels);
    target.dispose();
    const out = new Float32Array(3 * n);
    for (let i = 0; i < n; ++i) out.set(pixels.subarray(4 * i, 4 * i + 3), 3 * i);
    this.requestRender();
    return out;
  }

  // Screen position (canvas pixels) and view depth of every shown point.
  projectAll() {
    const n = studio.n;
    const shown = studio.geometry.getAttribute('shown').array;
    this.camera.updateMatrixWorld();
    const m = new THREE.Matrix4().multiplyMatrices(this.camera.projectionMatrix, this.camera.matrixWorldInverse).elements;
    const width = this.width, height = this.height;
    const screen = new Float32Array(2 * n), depth = new Float32Array(n);
    for (let i = 0; i < n; ++i) {
      const x = shown[3 * i], y = shown[3 * i + 1], z = shown[3 * i + 2];
      const w = m[3] * x + m[7] * y + m[11] * z + m[15]; // the view depth, for a perspective camera
      depth[i] = w;
      if (w <= 0) { screen[2 * i] = NaN; screen[2 * i + 1] = NaN; continue; }
      screen[2 * i] = ((m[0] * x + m[4] * y + m[8] * z + m[12]) / w * 0.5 + 0.5) * width;
      screen[2 * i + 1] = (0.5 - (m[1] * x + m[5] * y + m[9] * z + m[13]) / w * 0.5) * height;
    }
    return { screen, depth };
  }

  // Viewport position of a world point.
  screenOf(x, y, z) {
    this.camera.updateMatrixWorld();
    const v = new THREE.Vector3(x, y, z).project(this.camera);
    const r = this.canvas.getBoundingClientRect();
    return [r.left + (v.x * 0.5 + 0.5) * r.width, r.top + (0.5 - v.y * 0.5) * r.height];
  }

  // ---- presets and the up axis --------------------------------------------------------------------------------

  bounds() {
    const g = studio.geometry;
    g.computeBoundingBox();
    return { box: g.boundingBox, size: g.boundingBox.getSize(new THREE.Vector3()).toArray(), sphere: g.boundingSphere };
  }

  // +z when the scan's z extent is the largest or about it (scanners' and CAD's up), else +y (meshes' up).
  static defaultUp(size) {
    return size[2] >= 0.8 * Math.max(...size) ? '+z' : '+y';
  }

  setUp(axis) {
    this.up = axis;
    this.camera.up.fromArray(UP_AXES[axis]);
    this.makeOrbit();
  }

  // The viewing direction of a preset: front looks along the thinner horizontal axis (the widest side faces the
  // viewer), side along the other, top down the up axis.
  presetDirection(name) {
    const { size } = this.bounds();
    const upVector = new THREE.Vector3().fromArray(UP_AXES[this.up]);
    const k = UP_AXES[this.up].findIndex((c) => c !== 0);
    const [a, b] = [0, 1, 2].filter((i) => i !== k);
    const thin = size[a] <= size[b] ? a : b, wide = thin === a ? b : a;
    const axis = (i, sign) => new THREE.Vector3().setComponent(i, sign);
    if (name === 'top') {
      // A hair off the up axis, so that the orbit knows which way is up on the screen (front's far side).
      return upVector.clone().negate().add(axis(thin, 1e-3)).normalize();
    }
    if (name === 'side') return axis(wide, -1);
    return axis(thin, 1);
  }

  preset(name) {
    if (!studio.geometry) return;
    this.look(this.presetDirection(name));
  }

  // Frames the whole model looking along `direction` (default: as now), with the chosen up axis.
  look(direction) {
    const { sphere } = this.bounds();
    const d = direction ? direction.clone().normalize()
      : new THREE.Vector3().subVectors(this.orbit.target, this.camera.position).normalize();
    this.camera.up.fromArray(UP_AXES[this.up]);
    const halfFov = (this.camera.fov * Math.PI) / 360;
    const narrowest = Math.min(halfFov, Math.atan(Math.tan(halfFov) * this.camera.aspect));
    const distance = sphere.radius / Math.sin(narrowest);
    this.orbit.target.copy(sphere.center);
    this.camera.position.copy(sphere.center).addScaledVector(d, -distance);
    this.camera.near = distance / 100;
    this.camera.far = distance * 10;
    this.camera.updateProjectionMatrix();
    this.makeOrbit();
    this.orbit.target.copy(sphere.center);
    this.orbit.update();
    this.requestRender();
  }

  fit() {
    if (studio.geometry) this.look(null);
  }
}
