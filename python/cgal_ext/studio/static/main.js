// The studio's page (doc/studio.md): three.js points over the server's WebSocket. The server holds the whole
// state; the page holds the geometry once and draws it, live while a handle is dragged.
//   protocol.js  the WebSocket and its binary frames
//   material.js  the points' shaders: the deforming blend, sprite sizes, the passes' outputs
//   view.js      WebGL, camera, orbit, presets and up axis, eye-dome lighting, depth and position read-backs
//   selection.js brush, lasso and connected part, taking what is seen
//   gizmo.js     the handle's gizmo, the drags, mirrored groups
//   panel.js     the side panel
import * as THREE from '../three/build/three.module.js';
import { Gizmo } from './gizmo.js';
import { DeformingMaterial } from './material.js';
import { Connection } from './protocol.js';
import { fallbackSpacing, Selection } from './selection.js';
import { Panel } from './panel.js';
import { $, showError, status, studio } from './shared.js';
import { View } from './view.js';

const token = document.querySelector('meta[name=token]').content;
const view = new View($('canvas'));
let material = null;
const connection = new Connection(token, { onCommand, onArrays });
const selection = new Selection(view, connection);
const gizmo = new Gizmo(view, connection);
const panel = new Panel({ view, connection, gizmo, material: () => material, onColors: () => onColors(plainColours()) });

// ---- messages -----------------------------------------------------------------------------------------------

function onCommand(m) {
  if (m.type === 'error' && m.replace) { askToReplace(m); return; }
  if (m.type === 'error') {
    showError(m.message);
    studio.busy = false;
    studio.inFlight = false;
    $('save-status').textContent = '';
    return;
  }
  if (m.type === 'refused') { showError(m.message); return; }
  if (m.type === 'progress') {
    $('progress-bar').style.width = `${Math.round(100 * m.fraction)}%`;
    status(`${m.stage}: ${Math.round(100 * m.fraction)} %`);
    // A save's progress also beside its button, at the panel's foot (a level of detail's save takes minutes).
    if (m.stage.startsWith('save')) $('save-status').textContent = `${m.stage}: ${Math.round(100 * m.fraction)} %`;
    return;
  }
  if (m.type === 'saved') {
    studio.lastSaved = m.files;
    status(`saved ${m.files.join(', ')}`);
    $('save-status').textContent = `saved ${m.files.join(', ')}`;
    return;
  }
  if (m.type === 'warning') { panel.showWarnings(m.warnings); return; }
  if (m.type === 'state') panel.onState(m);
}

// A save that would replace files this session did not write (another scan, an earlier session's save): the
// server refused it and named them; asked, the page sends it again with overwrite.
function askToReplace(m) {
  const files = m.replace.join(', ');
  if (window.confirm(`${files} already ${m.replace.length === 1 ? 'exists' : 'exist'} in the studio's folder and ` +
                     `this session did not write ${m.replace.length === 1 ? 'it' : 'them'}. Replace?`)) {
    connection.send({ type: 'save', name: m.name, overwrite: true });
  } else {
    showError(`not saved: ${files} kept`);
    $('save-status').textContent = '';
  }
}

function onArrays(header, a) {
  if (header.type === 'geometry') return onGeometry(header, a);
  if (header.type === 'labels') { setLabels(a.labels); studio.busy = false; selection.drawOverlay(); return; }
  if (header.type === 'renderer') return onPrepared(header, a);
  if (header.type === 'frame') return onFrame(header, a);
  if (header.type === 'shown' || header.type === 'details') return onShown(header, a);
  if (header.type === 'colors') return onColors(a.colors);
  if (header.type === 'spacing' && a.spacing && a.spacing.length === studio.n) studio.setSpacing(a.spacing);
}

// ---- geometry -------------------------------------------------------------------------------------------------

function onGeometry(header, a) {
  const n = a.positions.length / 3;
  // A new scan starts at its own view; a commit or a fill (the same scan, more points) keeps the view.
  const scanChanged = !studio.geometry || !studio.state || studio.state.scan !== header.scan;
  studio.n = n;
  if (header.label_codes) studio.labelCodes = header.label_codes;
  if (header.max_groups) studio.maxGroups = header.max_groups;
  if (studio.geometry) studio.geometry.dispose();
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
  g.computeBoundingBox();
  const size = g.boundingBox.getSize(new THREE.Vector3()).toArray();
  studio.fallbackSpacing = fallbackSpacing(size, n);
  studio.spacing = a.spacing ? a.spacing.slice() : null;
  g.setAttribute('spacing', new THREE.BufferAttribute(studio.spacing || new Float32Array(n).fill(studio.fallbackSpacing), 1));
  studio.geometry = g;
  const previous = material;
  material = new DeformingMaterial(studio.maxGroups);
  if (previous) {
    for (const key of ['showSelection', 'pointScale', 'worldSizes']) material.uniforms[key].value = previous.uniforms[key].value;
    previous.material.dispose();
  } else {
    material.uniforms.pointScale.value = Number($('point-size').value);
  }
  const points = new THREE.Points(g, material.material);
  points.frustumCulled = false;
  view.setPoints(points, material);
  studio.inserted = a.inserted ? a.inserted.slice() : null;
  if (studio.inserted) onColors(plainColours());
  setLabels(a.labels);
  if (scanChanged) panel.startView(header.scan, size);
  view.requestRender();
  if ($('color').value !== 'plain') connection.send({ type: 'colors', by: $('color').value });
}

function setLabels(labels) {
  studio.labels = labels.slice();
  const attribute = studio.geometry.getAttribute('label');
  attribute.array.set(labels);
  attribute.needsUpdate = true;
  view.requestRender();
}

// Plain grey, the points a fill inserted green.
function plainColours() {
  const colours = new Uint8Array(3 * studio.n).fill(191);
  if (studio.inserted) {
    for (let i = 0; i < studio.n; ++i) if (studio.inserted[i]) colours.set([120, 200, 120], 3 * i);
  }
  return colours;
}

function onColors(colors) {
  const attribute = studio.geometry.getAttribute('color');
  attribute.array.set(colors);
  attribute.needsUpdate = true;
  view.requestRender();
}

// ---- editing ----------------------------------------------------------------------------------------------------

function onPrepared(header, a) {
  try {
    material.prepare(studio.geometry, studio.n, header, a);
  } catch (error) { showError(error.message); return; }
  studio.prepared = true;
  studio.movable = a.movable;
  view.requestRender();
}

function onFrame(header, a) {
  studio.inFlight = false;
  studio.framesReceived += 1;
  material.frame(a.frame, studio.state.groups);
  view.requestRender();
  gizmo.flush();
}

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
  material.live = false;
  view.requestRender();
}

// ---- for the tests and the benchmark ---------------------------------------------------------------------------

Object.assign(studio, {
  view, gizmo, selection, panel,
  send: (command) => connection.send(command),
  sendIndices: (header, indices) => connection.sendIndices(header, indices),
  requestRender: () => view.requestRender(),
  readback: () => Array.from(view.readPositions(studio.n)),
  screenOf: (x, y, z) => view.screenOf(x, y, z),
  pivotScreen: () => {
    gizmo.pivot.updateMatrixWorld(true);
    const p = new THREE.Vector3().setFromMatrixPosition(gizmo.pivot.matrixWorld);
    return view.screenOf(p.x, p.y, p.z);
  },
  projectAll: () => view.projectAll().screen,
  // Each point's spacing set from outside (to measure the sprites against another spacing).
  setSpacing: (values) => {
    studio.spacing = Float32Array.from(values);
    studio.geometry.setAttribute('spacing', new THREE.BufferAttribute(studio.spacing, 1));
    view.requestRender();
  },
  // Which canvas pixels show the background, as a string of 0 and 1, rows from the top.
  backgroundPixels: () => {
    view.render();
    const gl = view.webgl.getContext(), width = view.width, height = view.height;
    const pixels = new Uint8Array(4 * width * height);
    gl.readPixels(0, 0, width, height, gl.RGBA, gl.UNSIGNED_BYTE, pixels);
    const background = [0x20, 0x24, 0x2a], out = new Array(width * height);
    for (let y = 0; y < height; ++y) {
      for (let x = 0; x < width; ++x) {
        const at = 4 * ((height - 1 - y) * width + x);
        out[y * width + x] = pixels[at] === background[0] && pixels[at + 1] === background[1] && pixels[at + 2] === background[2] ? '1' : '0';
      }
    }
    return { width, height, mask: out.join('') };
  },
  cameraMatrices: () => {
    view.camera.updateMatrixWorld();
    return { view: view.camera.matrixWorldInverse.toArray(), projection: view.camera.projectionMatrix.toArray(),
             width: view.width, height: view.height, rect: view.canvas.getBoundingClientRect().toJSON() };
  },
});

// Drawing every frame, to measure it (the benchmark).
Object.defineProperty(studio, 'continuous', {
  get: () => view.continuous,
  set: (value) => { view.continuous = value; if (value) view.requestRender(); },
});

connection.connect();
