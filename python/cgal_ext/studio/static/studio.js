// The studio's page: three.js points over the server's WebSocket (doc/studio.md). The server holds the whole
// state; the page holds the geometry once and, while a handle is dragged, blends the sample points' motions
// per point in the vertex shader (the library's diffusion, in float32).
'use strict';

const token = document.querySelector('meta[name=token]').content;
const $ = (id) => document.getElementById(id);
const RECORDS_PER_ROW = 1024; // sample points per row of the motion texture (3 texels each)
const MAX_GROUPS = 8;

const vertexShader = `
precision highp float;
precision highp int;
uniform bool live;
uniform highp sampler2D records;     // per sample point 3 texels: the rows of [A - I | c]
uniform highp sampler2D collarSteps; // per collar handle point 2 texels: position step, normal step
uniform mat4 groupT[${MAX_GROUPS}];
uniform float pointSize;
uniform bool showSelection;
uniform bool readback;
uniform float readbackWidth;
attribute vec3 shown;
attribute vec3 shownNormal;
attribute vec3 color;
attribute float label;
attribute vec3 s0; attribute vec3 s1; // the stencil's sample points
attribute vec3 w0; attribute vec3 w1; // and weights
attribute float hgroup;               // exact handle group, or -1
attribute vec4 collar;                // two collar slots (-1: none) and their weights
varying vec3 vColor;
varying vec3 vNormal;
varying vec3 vPosition;

void accumulate(float s, float w, inout vec4 r0, inout vec4 r1, inout vec4 r2) {
  if (w == 0.0) return;
  int j = int(s);
  ivec2 at = ivec2(3 * (j % ${RECORDS_PER_ROW}), j / ${RECORDS_PER_ROW});
  r0 += w * texelFetch(records, at, 0);
  r1 += w * texelFetch(records, at + ivec2(1, 0), 0);
  r2 += w * texelFetch(records, at + ivec2(2, 0), 0);
}

void collarStep(float slot, float w, inout vec3 step, inout vec3 normalStep) {
  if (slot < 0.0) return;
  int c = int(slot);
  ivec2 at = ivec2(2 * (c % ${RECORDS_PER_ROW}), c / ${RECORDS_PER_ROW});
  step += w * texelFetch(collarSteps, at, 0).xyz;
  normalStep += w * texelFetch(collarSteps, at + ivec2(1, 0), 0).xyz;
}

void main() {
  vec3 p = shown;
  vec3 n = shownNormal;
  if (live) {
    vec4 r0 = vec4(0.0), r1 = vec4(0.0), r2 = vec4(0.0);
    accumulate(s0.x, w0.x, r0, r1, r2); accumulate(s0.y, w0.y, r0, r1, r2); accumulate(s0.z, w0.z, r0, r1, r2);
    accumulate(s1.x, w1.x, r0, r1, r2); accumulate(s1.y, w1.y, r0, r1, r2); accumulate(s1.z, w1.z, r0, r1, r2);
    vec3 rest = position;
    p = rest + vec3(dot(r0.xyz, rest) + r0.w, dot(r1.xyz, rest) + r1.w, dot(r2.xyz, rest) + r2.w);
    // The normal turns by the cofactor matrix of the blended map I + turn (rows r0..r2).
    vec3 m0 = vec3(1.0 + r0.x, r1.x, r2.x), m1 = vec3(r0.y, 1.0 + r1.y, r2.y), m2 = vec3(r0.z, r1.z, 1.0 + r2.z);
    n = normalize(normal.x * cross(m1, m2) + normal.y * cross(m2, m0) + normal.z * cross(m0, m1));
    if (hgroup >= 0.0) {
      mat4 T = groupT[int(hgroup)];
      p = (T * vec4(rest, 1.0)).xyz;
      n = mat3(T) * normal;
    } else if (collar.x >= 0.0) {
      vec3 step = vec3(0.0), normalStep = vec3(0.0);
      collarStep(collar.x, collar.z, step, normalStep);
      collarStep(collar.y, collar.w, step, normalStep);
      if (step != vec3(0.0) || normalStep != vec3(0.0)) { p += step; n = normalize(n + normalStep); }
    }
  }
  vPosition = p;
  vec3 base = color;
  if (showSelection && label >= 1.0) {
    vec3 tint = label < 2.0 ? vec3(1.0, 0.85, 0.2) : (mod(label, 2.0) < 1.0 ? vec3(1.0, 0.25, 0.2) : vec3(0.3, 0.6, 1.0));
    base = mix(base, tint, 0.55);
  }
  vColor = base;
  vNormal = normalize(normalMatrix * n);
  if (readback) {
    // One pixel per point: the fragment writes the position (the test reads it back).
    float vid = float(gl_VertexID), x = mod(vid, readbackWidth), y = floor(vid / readbackWidth);
    gl_Position = vec4((x + 0.5) / readbackWidth * 2.0 - 1.0, (y + 0.5) / readbackWidth * 2.0 - 1.0, 0.0, 1.0);
    gl_PointSize = 1.0;
    return;
  }
  gl_Position = projectionMatrix * modelViewMatrix * vec4(p, 1.0);
  gl_PointSize = pointSize;
}`;

const fragmentShader = `
precision highp float;
uniform bool readback;
varying vec3 vColor;
varying vec3 vNormal;
varying vec3 vPosition;
void main() {
  if (readback) { gl_FragColor = vec4(vPosition, 1.0); return; }
  float light = 0.3 + 0.7 * abs(vNormal.z);
  gl_FragColor = vec4(vColor * light, 1.0);
}`;

// ---- state ----------------------------------------------------------------------------------------------------

const studio = {
  ws: null, state: null, n: 0, geometry: null, points: null, material: null,
  rest: null, labels: null, frameTimes: [], dragSeq: 0, frameSeq: 0, pending: null, inFlight: false,
  framesReceived: 0, errors: [], lastSaved: null, busy: false, renderer: null, timings: [],
};
window.studio = studio;
// Anything the content security policy blocks is a bug of the page's: shown, and the browser test fails on it.
document.addEventListener('securitypolicyviolation', (event) => {
  studio.errors.push(`content security policy: ${event.violatedDirective} blocked ${event.blockedURI}`);
});

const renderer = new THREE.WebGLRenderer({ canvas: $('canvas'), context: $('canvas').getContext('webgl2', { antialias: false, preserveDrawingBuffer: true }) });
renderer.setPixelRatio(1);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0x20242a);
const camera = new THREE.PerspectiveCamera(40, 1, 0.001, 1000);
let orbit = new THREE.OrbitControls(camera, $('canvas'));
const pivot = new THREE.Object3D();
scene.add(pivot);
const gizmo = new THREE.TransformControls(camera, $('canvas'));
gizmo.setSize(0.8);
scene.add(gizmo);
let pivotRest = new THREE.Matrix4(); // the pivot's matrix with the group at rest

function emptyTexture(width) {
  const t = new THREE.DataTexture(new Float32Array(4 * width), width, 1, THREE.RGBAFormat, THREE.FloatType);
  t.needsUpdate = true;
  return t;
}

studio.material = new THREE.ShaderMaterial({
  vertexShader, fragmentShader,
  uniforms: {
    live: { value: false }, records: { value: emptyTexture(3) }, collarSteps: { value: emptyTexture(2) },
    groupT: { value: Array.from({ length: MAX_GROUPS }, () => new THREE.Matrix4()) },
    pointSize: { value: 2 }, showSelection: { value: true }, readback: { value: false }, readbackWidth: { value: 1 },
  },
});

function resize() {
  const view = $('view');
  renderer.setSize(view.clientWidth, view.clientHeight, false);
  $('overlay').width = view.clientWidth;
  $('overlay').height = view.clientHeight;
  camera.aspect = view.clientWidth / Math.max(1, view.clientHeight);
  camera.updateProjectionMatrix();
  requestRender();
}

// Drawn on demand (a camera move, new motions, new attributes), never in an idle loop: a million points drawn
// in software would otherwise keep the page busy between the server's messages. studio.continuous draws every
// frame (to measure it); frameTimes holds the intervals between drawn frames.
let lastFrame = performance.now(), drawPending = false;
function requestRender() {
  if (drawPending) return;
  drawPending = true;
  requestAnimationFrame(draw);
}
function draw() {
  drawPending = false;
  const now = performance.now();
  studio.frameTimes.push(now - lastFrame);
  if (studio.frameTimes.length > 240) studio.frameTimes.shift();
  lastFrame = now;
  renderer.render(scene, camera);
  studio.timings.push(['drawn', now, performance.now()]);
  if (studio.continuous) requestRender();
}
studio.requestRender = requestRender;
orbit.addEventListener('change', requestRender);
gizmo.addEventListener('change', requestRender);
window.addEventListener('resize', resize);
resize();

// ---- messages -------------------------------------------------------------------------------------------------

function showError(text) {
  $('error').textContent = text;
  studio.errors.push(text);
}
function status(text) { $('status').textContent = text; }
function send(command) {
  if (!studio.ws || studio.ws.readyState !== 1) { showError('not connected to the studio server'); return; }
  $('error').textContent = '';
  studio.ws.send(JSON.stringify(command));
}
function sendIndices(header, indices) {
  const text = new TextEncoder().encode(JSON.stringify(Object.assign({ count: indices.length }, header)));
  const length = Math.ceil(text.length / 4) * 4;
  const buffer = new ArrayBuffer(4 + length + 4 * indices.length);
  new DataView(buffer).setUint32(0, length, true);
  new Uint8Array(buffer, 4, length).fill(32).set(text);
  new Uint32Array(buffer, 4 + length).set(indices);
  $('error').textContent = '';
  studio.ws.send(buffer);
}

function unpack(buffer) {
  const length = new DataView(buffer).getUint32(0, true);
  const header = JSON.parse(new TextDecoder().decode(new Uint8Array(buffer, 4, length)));
  const arrays = {};
  const types = { '<f4': Float32Array, '<u4': Uint32Array, '<u2': Uint16Array, '|i1': Int8Array, '|u1': Uint8Array,
                  '<i4': Int32Array };
  for (const a of header.arrays) {
    const Type = types[a.dtype];
    const count = a.shape.reduce((x, y) => x * y, 1);
    arrays[a.name] = new Type(buffer, 4 + length + a.offset, count);
  }
  return [header, arrays];
}

function connect() {
  const ws = new WebSocket(`ws://${location.host}/ws?token=${encodeURIComponent(token)}`);
  ws.binaryType = 'arraybuffer';
  studio.ws = ws;
  ws.onopen = () => status('connected');
  ws.onclose = (event) => {
    if (studio.refused) return;
    showError(`connection to the studio closed (${event.code}${event.reason ? ': ' + event.reason : ''}); reconnecting`);
    setTimeout(connect, 1000);
  };
  ws.onmessage = (event) => {
    try {
      if (typeof event.data === 'string') onCommand(JSON.parse(event.data));
      else onArrays(...unpack(event.data));
    } catch (error) { // a bug of the page's: shown, not swallowed
      showError(`the page failed on a message from the server: ${error}`);
    }
  };
}

function onCommand(m) {
  if (m.type === 'error' && m.replace) { askToReplace(m); return; }
  if (m.type === 'error') { showError(m.message); studio.busy = false; studio.inFlight = false; return; }
  if (m.type === 'refused') { studio.refused = true; showError(m.message); return; }
  if (m.type === 'progress') {
    $('progress-bar').style.width = `${Math.round(100 * m.fraction)}%`;
    status(`${m.stage}: ${Math.round(100 * m.fraction)} %`);
    return;
  }
  if (m.type === 'saved') { studio.lastSaved = m.files; status(`saved ${m.files.join(', ')}`); return; }
  if (m.type === 'state') onState(m);
}

// A save that would replace files this session did not write (another scan, an earlier session's save): the
// server refused it and named them; asked, the page sends it again with overwrite.
function askToReplace(m) {
  const files = m.replace.join(', ');
  if (window.confirm(`${files} already ${m.replace.length === 1 ? 'exists' : 'exist'} in the studio's folder and ` +
                     `this session did not write ${m.replace.length === 1 ? 'it' : 'them'}. Replace?`)) {
    send({ type: 'save', name: m.name, overwrite: true });
  } else {
    showError(`not saved: ${files} kept`);
  }
}

function onState(m) {
  studio.state = m;
  studio.busy = false;
  const files = $('file');
  if (m.files && files.options.length !== m.files.length) {
    files.innerHTML = '';
    for (const f of m.files) files.add(new Option(f, f));
  }
  if (m.scan) files.value = m.scan;
  const group = $('group');
  const wanted = m.groups;
  if (group.options.length !== wanted) {
    const active = Math.min(Math.max(group.selectedIndex, 0), wanted - 1);
    group.innerHTML = '';
    for (let g = 0; g < wanted; ++g) group.add(new Option(`handle group ${g}`, g));
    group.selectedIndex = wanted ? Math.max(active, wanted - 1) : -1;
  }
  for (const key of ['order', 'rotations', 'strength_distance']) $(key).value = m.settings[key];
  $('history').textContent = `step ${m.step} of ${m.steps}`;
  status(m.scan ? `${m.scan}: ${m.points} points, region ${m.region}, ${m.groups} handle group(s)` +
                  (m.preprocessed ? ', ready to drag' : '') : 'no scan open');
  $('progress-bar').style.width = '0';
  if (!m.preprocessed) { detachGizmo(); studio.renderer = null; studio.material.uniforms.live.value = false; }
  else if (studio.renderer && !gizmo.dragging) attachGizmo();
  requestRender();
}

function onArrays(header, a) {
  studio.timings.push([header.type, performance.now()]);
  if (header.type === 'geometry') return onGeometry(header, a);
  if (header.type === 'labels') { setLabels(a.labels); return; }
  if (header.type === 'renderer') return onRenderer(header, a);
  if (header.type === 'frame') return onFrame(header, a);
  if (header.type === 'shown' || header.type === 'details') return onShown(header, a);
  if (header.type === 'colors') return onColors(a.colors);
}

// ---- geometry -------------------------------------------------------------------------------------------------

function onGeometry(header, a) {
  const n = a.positions.length / 3;
  studio.n = n;
  if (studio.points) { scene.remove(studio.points); studio.geometry.dispose(); }
  const g = new THREE.BufferGeometry();
  // The rest pose the shader deforms from: the shown state unless the server sent another.
  studio.rest = a.rest ? a.rest.slice() : a.positions.slice();
  g.setAttribute('position', new THREE.BufferAttribute(studio.rest, 3));
  g.setAttribute('normal', new THREE.BufferAttribute(a.rest_normals ? a.rest_normals.slice() : a.normals.slice(), 3));
  g.setAttribute('shown', new THREE.BufferAttribute(a.positions.slice(), 3));
  g.setAttribute('shownNormal', new THREE.BufferAttribute(a.normals.slice(), 3));
  g.setAttribute('color', new THREE.BufferAttribute(new Uint8Array(3 * n).fill(191), 3, true));
  g.setAttribute('label', new THREE.BufferAttribute(new Int8Array(n), 1));
  g.computeBoundingSphere();
  studio.geometry = g;
  studio.points = new THREE.Points(g, studio.material);
  studio.points.frustumCulled = false;
  scene.add(studio.points);
  setLabels(a.labels);
  studio.material.uniforms.live.value = false;
  fit();
  requestRender();
  if ($('color').value !== 'plain') send({ type: 'colors', by: $('color').value });
}

function setLabels(labels) {
  studio.labels = labels.slice();
  const attribute = studio.geometry.getAttribute('label');
  attribute.array.set(labels);
  attribute.needsUpdate = true;
  requestRender();
}

function onColors(colors) {
  const attribute = studio.geometry.getAttribute('color');
  attribute.array.set(colors);
  attribute.needsUpdate = true;
  requestRender();
}

function fit() {
  // Looks along the bounding box's thinnest axis (the model's widest side faces the viewer), up the longest of
  // the others, z or else y where it is about as long (the usual up axes of scans).
  if (!studio.geometry) return;
  const sphere = studio.geometry.boundingSphere;
  studio.geometry.computeBoundingBox();
  const size = studio.geometry.boundingBox.getSize(new THREE.Vector3()).toArray();
  const thinnest = size.indexOf(Math.min(...size));
  const others = [2, 1, 0].filter((k) => k !== thinnest);
  const longest = Math.max(...others.map((k) => size[k]));
  const axis = (k) => new THREE.Vector3().setComponent(k, 1);
  camera.up.copy(axis(others.find((k) => size[k] >= 0.9 * longest)));
  orbit.dispose(); // OrbitControls fixes its up axis when made
  orbit = new THREE.OrbitControls(camera, $('canvas'));
  orbit.addEventListener('change', requestRender);
  updateOrbit();
  const distance = sphere.radius / Math.sin((camera.fov * Math.PI) / 360);
  orbit.target.copy(sphere.center);
  camera.position.copy(sphere.center).add(axis(thinnest).multiplyScalar(-distance));
  camera.near = distance / 100;
  camera.far = distance * 10;
  camera.updateProjectionMatrix();
  orbit.update();
}

// ---- selection: brush and lasso in screen space -------------------------------------------------------------

let stroke = null;

function projectAll() {
  // Screen position of every shown point (the camera does not move during a stroke).
  const shown = studio.geometry.getAttribute('shown').array;
  const m = new THREE.Matrix4().multiplyMatrices(camera.projectionMatrix, camera.matrixWorldInverse).elements;
  const width = $('canvas').clientWidth, height = $('canvas').clientHeight;
  const screen = new Float32Array(2 * studio.n);
  for (let i = 0; i < studio.n; ++i) {
    const x = shown[3 * i], y = shown[3 * i + 1], z = shown[3 * i + 2];
    const w = m[3] * x + m[7] * y + m[11] * z + m[15];
    if (w <= 0) { screen[2 * i] = NaN; continue; }
    screen[2 * i] = ((m[0] * x + m[4] * y + m[8] * z + m[12]) / w * 0.5 + 0.5) * width;
    screen[2 * i + 1] = (0.5 - (m[1] * x + m[5] * y + m[9] * z + m[13]) / w * 0.5) * height;
  }
  return screen;
}

function tool() { return document.querySelector('input[name=tool]:checked').value; }

function canvasPoint(event) {
  const r = $('canvas').getBoundingClientRect();
  return [event.clientX - r.left, event.clientY - r.top];
}

function paintUnder([x, y]) {
  const radius = Number($('brush-size').value);
  const r2 = radius * radius, screen = stroke.screen, label = studio.geometry.getAttribute('label');
  const preview = stroke.erase ? (stroke.target === 'roi' ? 0 : 1) : (stroke.target === 'roi' ? 1 : 2 + stroke.group);
  for (let i = 0; i < studio.n; ++i) {
    const dx = screen[2 * i] - x, dy = screen[2 * i + 1] - y;
    if (dx * dx + dy * dy <= r2 && !stroke.mask[i]) {
      stroke.mask[i] = 1;
      label.array[i] = preview;
    }
  }
  label.needsUpdate = true;
  requestRender();
}

function drawLasso() {
  const context = $('overlay').getContext('2d');
  context.clearRect(0, 0, $('overlay').width, $('overlay').height);
  if (!stroke || stroke.kind !== 'lasso' || stroke.path.length < 2) return;
  context.strokeStyle = '#ff0';
  context.beginPath();
  context.moveTo(...stroke.path[0]);
  for (const p of stroke.path) context.lineTo(...p);
  context.closePath();
  context.stroke();
}

function insideLasso(path, x, y) {
  let inside = false;
  for (let a = 0, b = path.length - 1; a < path.length; b = a++) {
    const [xa, ya] = path[a], [xb, yb] = path[b];
    if ((ya > y) !== (yb > y) && x < ((xb - xa) * (y - ya)) / (yb - ya) + xa) inside = !inside;
  }
  return inside;
}

$('canvas').addEventListener('pointerdown', (event) => {
  if (tool() === 'orbit' || !studio.geometry || event.button !== 0) return;
  const target = document.querySelector('input[name=target]:checked').value;
  if (target === 'handle' && $('group').options.length === 0) { showError('make a handle group first (New handle group)'); return; }
  stroke = { kind: tool(), target, erase: $('erase').checked, group: Math.max(0, $('group').selectedIndex),
             screen: projectAll(), mask: new Uint8Array(studio.n), path: [canvasPoint(event)] };
  $('canvas').setPointerCapture(event.pointerId);
  if (stroke.kind === 'brush') paintUnder(canvasPoint(event));
});
$('canvas').addEventListener('pointermove', (event) => {
  if (!stroke) return;
  stroke.path.push(canvasPoint(event));
  if (stroke.kind === 'brush') paintUnder(canvasPoint(event));
  else drawLasso();
});
$('canvas').addEventListener('pointerup', () => {
  if (!stroke) return;
  const s = stroke;
  stroke = null;
  drawLasso();
  if (s.kind === 'lasso') {
    for (let i = 0; i < studio.n; ++i) if (insideLasso(s.path, s.screen[2 * i], s.screen[2 * i + 1])) s.mask[i] = 1;
  }
  const indices = [];
  for (let i = 0; i < studio.n; ++i) if (s.mask[i]) indices.push(i);
  sendIndices({ type: 'select', target: s.target, mode: s.erase ? 'erase' : 'add', group: s.group }, indices);
});

function updateOrbit() {
  orbit.enabled = tool() === 'orbit' && !gizmo.dragging;
}
for (const input of document.querySelectorAll('input[name=tool]')) input.addEventListener('change', updateOrbit);

// ---- editing: the gizmo, live frames, release ---------------------------------------------------------------

function groupTransform(g) {
  const m = new THREE.Matrix4();
  const t = studio.state && studio.state.transforms[g];
  if (t) m.set(...t);
  return m;
}

function attachGizmo() {
  const g = $('group').selectedIndex;
  if (g < 0 || !studio.labels) return;
  // The pivot: the centroid of the group's points at rest, carried by the group's current transform.
  const c = new THREE.Vector3();
  let count = 0;
  for (let i = 0; i < studio.n; ++i) if (studio.labels[i] === 2 + g) {
    c.x += studio.rest[3 * i]; c.y += studio.rest[3 * i + 1]; c.z += studio.rest[3 * i + 2]; ++count;
  }
  c.divideScalar(Math.max(count, 1));
  pivotRest = new THREE.Matrix4().makeTranslation(c.x, c.y, c.z);
  pivot.matrix.multiplyMatrices(groupTransform(g), pivotRest);
  pivot.matrix.decompose(pivot.position, pivot.quaternion, pivot.scale);
  pivot.updateMatrixWorld(true);
  gizmo.attach(pivot);
  gizmo.setMode(document.querySelector('input[name=gizmo]:checked').value);
  studio.activeGroup = g;
  requestRender();
}
function detachGizmo() { gizmo.detach(); requestRender(); }

function onRenderer(header, a) {
  // Each point's stencil (6 sample points and weights; zero weights for the points the edit cannot move), its
  // exact handle group and its collar entries, as vertex attributes.
  const g = studio.geometry, n = studio.n;
  const Index = a.stencil_samples.constructor;
  const s0 = new Index(3 * n), s1 = new Index(3 * n), w0 = new Float32Array(3 * n), w1 = new Float32Array(3 * n);
  const hgroup = new Int8Array(n).fill(-1), collar = new Float32Array(4 * n).fill(-1);
  const m = a.movable.length ? a.stencil_samples.length / a.movable.length : 6;
  if (m > 6) { showError(`the page blends at most 6 sample points per point, not ${m}`); return; }
  const samples = a.stencil_samples, weights = a.stencil_weights;
  for (let k = 0; k < a.movable.length; ++k) {
    const i = a.movable[k];
    for (let e = 0; e < m; ++e) {
      const at = 3 * i + (e % 3);
      if (e < 3) { s0[at] = samples[k * m + e]; w0[at] = weights[k * m + e]; }
      else { s1[at] = samples[k * m + e]; w1[at] = weights[k * m + e]; }
    }
    hgroup[i] = a.handle_group[k];
  }
  for (let k = 0; k < a.collar_points.length; ++k) {
    const at = 4 * a.collar_points[k];
    collar[at] = a.collar_slots[2 * k]; collar[at + 1] = a.collar_slots[2 * k + 1];
    collar[at + 2] = a.collar_weights[2 * k]; collar[at + 3] = a.collar_weights[2 * k + 1];
  }
  g.setAttribute('s0', new THREE.BufferAttribute(s0, 3));
  g.setAttribute('s1', new THREE.BufferAttribute(s1, 3));
  g.setAttribute('w0', new THREE.BufferAttribute(w0, 3));
  g.setAttribute('w1', new THREE.BufferAttribute(w1, 3));
  g.setAttribute('hgroup', new THREE.BufferAttribute(hgroup, 1));
  g.setAttribute('collar', new THREE.BufferAttribute(collar, 4));
  const sampleCount = header.sample_points;
  const rows = Math.ceil(sampleCount / RECORDS_PER_ROW);
  studio.material.uniforms.records.value = new THREE.DataTexture(new Float32Array(4 * 3 * RECORDS_PER_ROW * rows),
    3 * RECORDS_PER_ROW, rows, THREE.RGBAFormat, THREE.FloatType);
  const collarRows = Math.max(1, Math.ceil(header.collar_handles / RECORDS_PER_ROW));
  studio.material.uniforms.collarSteps.value = new THREE.DataTexture(new Float32Array(4 * 2 * RECORDS_PER_ROW * collarRows),
    2 * RECORDS_PER_ROW, collarRows, THREE.RGBAFormat, THREE.FloatType);
  studio.renderer = { samples: sampleCount, collar: header.collar_handles };
  studio.movable = a.movable;
  requestRender();
}

function onFrame(header, a) {
  studio.inFlight = false;
  studio.framesReceived += 1;
  const { samples, collar } = studio.renderer;
  const f = a.frame;
  const records = studio.material.uniforms.records.value;
  records.image.data.set(f.subarray(0, 12 * samples));
  records.needsUpdate = true;
  const groups = studio.state.groups;
  for (let g = 0; g < groups; ++g) {
    const r = f.subarray(12 * (samples + g), 12 * (samples + g + 1));
    studio.material.uniforms.groupT.value[g].set(r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8], r[9], r[10], r[11], 0, 0, 0, 1);
  }
  const steps = f.subarray(12 * (samples + groups));
  const texture = studio.material.uniforms.collarSteps.value.image.data;
  for (let c = 0; c < collar; ++c) {
    texture.set(steps.subarray(6 * c, 6 * c + 3), 8 * c);
    texture.set(steps.subarray(6 * c + 3, 6 * c + 6), 8 * c + 4);
  }
  studio.material.uniforms.collarSteps.value.needsUpdate = true;
  studio.material.uniforms.live.value = true;
  requestRender();
  flushDrag();
}

function flushDrag() {
  // One frame in flight: the latest transform waits for the previous frame's motions.
  if (studio.inFlight || !studio.pending) return;
  studio.inFlight = true;
  send(studio.pending);
  studio.pending = null;
}

gizmo.addEventListener('objectChange', () => {
  if (!gizmo.dragging) return;
  pivot.updateMatrixWorld(true);
  const T = new THREE.Matrix4().multiplyMatrices(pivot.matrixWorld, new THREE.Matrix4().getInverse(pivotRest));
  const e = T.elements; // column-major
  const rows = [e[0], e[4], e[8], e[12], e[1], e[5], e[9], e[13], e[2], e[6], e[10], e[14], 0, 0, 0, 1];
  studio.pending = { type: 'drag', group: studio.activeGroup, matrix: rows, seq: ++studio.dragSeq };
  studio.lastDrag = rows;
  flushDrag();
});
gizmo.addEventListener('dragging-changed', (event) => {
  updateOrbit();
  if (!event.value) {
    const finish = () => {
      if (studio.inFlight || studio.pending) { setTimeout(finish, 5); return; }
      studio.busy = true;
      send({ type: 'release' });
    };
    finish();
  }
});

function onShown(header, a) {
  const g = studio.geometry;
  const shown = g.getAttribute('shown');
  const normals = g.getAttribute('shownNormal');
  a.indices.forEach((i, k) => {
    shown.array[3 * i] = a.positions[3 * k]; shown.array[3 * i + 1] = a.positions[3 * k + 1]; shown.array[3 * i + 2] = a.positions[3 * k + 2];
    if (a.normals) { normals.array[3 * i] = a.normals[3 * k]; normals.array[3 * i + 1] = a.normals[3 * k + 1]; normals.array[3 * i + 2] = a.normals[3 * k + 2]; }
  });
  shown.needsUpdate = true;
  normals.needsUpdate = true;
  studio.material.uniforms.live.value = false;
  requestRender();
}

// The shader's positions, read back through a float render target: one pixel per point.
studio.readback = () => {
  const width = Math.ceil(Math.sqrt(studio.n));
  const target = new THREE.WebGLRenderTarget(width, width, { type: THREE.FloatType, format: THREE.RGBAFormat,
    minFilter: THREE.NearestFilter, magFilter: THREE.NearestFilter, depthBuffer: false });
  const u = studio.material.uniforms;
  u.readback.value = true;
  u.readbackWidth.value = width;
  const clear = renderer.getClearColor().clone(), alpha = renderer.getClearAlpha();
  renderer.setClearColor(0x000000, 0);
  renderer.setRenderTarget(target);
  renderer.clear();
  const background = scene.background;
  scene.background = null;
  gizmo.visible = false;
  renderer.render(scene, camera);
  scene.background = background;
  gizmo.visible = true;
  const pixels = new Float32Array(4 * width * width);
  renderer.readRenderTargetPixels(target, 0, 0, width, width, pixels);
  renderer.setRenderTarget(null);
  renderer.setClearColor(clear, alpha);
  u.readback.value = false;
  target.dispose();
  const out = new Float32Array(3 * studio.n);
  for (let i = 0; i < studio.n; ++i) out.set(pixels.subarray(4 * i, 4 * i + 3), 3 * i);
  return Array.from(out);
};
// Screen position of a world point (for tests and tools).
studio.screenOf = (x, y, z) => {
  const v = new THREE.Vector3(x, y, z).project(camera);
  const r = $('canvas').getBoundingClientRect();
  return [r.left + (v.x * 0.5 + 0.5) * r.width, r.top + (0.5 - v.y * 0.5) * r.height];
};
studio.pivotScreen = () => { pivot.updateMatrixWorld(true); const p = new THREE.Vector3().setFromMatrixPosition(pivot.matrixWorld); return studio.screenOf(p.x, p.y, p.z); };

// ---- panel ------------------------------------------------------------------------------------------------------

$('open').onclick = () => send({ type: 'load', path: $('file').value });
$('fit').onclick = fit;
$('color').onchange = () => {
  if ($('color').value === 'plain') onColors(new Uint8Array(3 * studio.n).fill(191));
  else send({ type: 'colors', by: $('color').value });
};
$('show-selection').onchange = () => { studio.material.uniforms.showSelection.value = $('show-selection').checked; requestRender(); };
$('point-size').oninput = () => { studio.material.uniforms.pointSize.value = Number($('point-size').value); requestRender(); };
$('new-group').onclick = () => { send({ type: 'new_group' }); $('paint-handle').checked = true; };
$('group').onchange = () => { if (studio.renderer) attachGizmo(); };
$('invert').onclick = () => send({ type: 'invert' });
$('clear').onclick = () => send({ type: 'clear' });
$('load-edit').onclick = () => send({ type: 'load_edit', path: $('edit-file').value });
for (const key of ['order', 'rotations', 'strength_distance']) $(key).onchange = () => send({ type: 'settings', [key]: $(key).value });
$('edit-start').onclick = () => { studio.busy = true; send({ type: 'preprocess' }); };
for (const input of document.querySelectorAll('input[name=gizmo]')) input.onchange = () => { gizmo.setMode(input.value); requestRender(); };
$('undo').onclick = () => { studio.busy = true; send({ type: 'undo' }); };
$('redo').onclick = () => { studio.busy = true; send({ type: 'redo' }); };
$('details-s').oninput = () => { $('details-value').textContent = Number($('details-s').value).toFixed(1); };
$('details-preview').onclick = () => { studio.busy = true; send({ type: 'details', mode: $('details-mode').value, s: Number($('details-s').value) }); };
$('details-apply').onclick = () => { studio.busy = true; send({ type: 'details', mode: $('details-mode').value, s: Number($('details-s').value), apply: true }); };
$('save').onclick = () => send({ type: 'save', name: $('save-name').value });
window.addEventListener('keydown', (event) => {
  if (event.ctrlKey && event.key === 'z') $('undo').click();
  if (event.ctrlKey && event.key === 'y') $('redo').click();
});

connect();
